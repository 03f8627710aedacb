//! Reading the human reference data: the CSV files of each source, their
//! heel-strike and toe-off events, and the periodic splines that make the
//! sampled curves smooth enough for second differences. Input only; the
//! step is built from the curves in `baseline.rs`.

use std::path::Path;

use super::{BaselineError, Source};

/// Reference curves on a percent-of-cycle axis, degrees.
pub(super) struct Curves {
    pub(super) thigh: PeriodicSpline,
    pub(super) knee: PeriodicSpline,
    /// Heel strike and toe-off, percent of the file's axis.
    pub(super) heel_strike_pct: f64,
    pub(super) toe_off_pct: f64,
}

/// A periodic (period 100 %) cubic interpolating spline, C² everywhere.
///
/// Why not linear interpolation: the data are sampled every 0.1–2 % of the
/// cycle, and the cost takes second differences of Φ at Δt = 0.01 s, so
/// every kink of a piecewise-linear curve becomes a torque spike (tens of
/// N·m per knot at 2 % spacing) that belongs to the interpolation, not to
/// the human gait.
pub(super) struct PeriodicSpline {
    x: Vec<f64>,
    y: Vec<f64>,
    /// Second derivatives at the knots.
    m: Vec<f64>,
}

impl PeriodicSpline {
    /// Knots `x` strictly increasing within [0, 100), at least 3 of them.
    fn new(x: Vec<f64>, y: Vec<f64>) -> Self {
        let n = x.len();
        let knot = |i: isize| -> (f64, f64) {
            // Knot i with periodic wrap: x shifted by whole periods.
            let k = i.rem_euclid(n as isize) as usize;
            let wraps = i.div_euclid(n as isize) as f64;
            (
                x.get(k).copied().unwrap_or(0.0) + 100.0 * wraps,
                y.get(k).copied().unwrap_or(0.0),
            )
        };
        // h_{i−1} M_{i−1} + 2 (h_{i−1} + h_i) M_i + h_i M_{i+1} = r_i, cyclic;
        // strictly diagonally dominant, so Gauss–Seidel converges at least
        // by half per sweep.
        let mut rows = Vec::with_capacity(n);
        for i in 0..n as isize {
            let (xp, yp) = knot(i - 1);
            let (xi, yi) = knot(i);
            let (xn, yn) = knot(i + 1);
            let (h0, h1) = (xi - xp, xn - xi);
            rows.push((
                h0,
                2.0 * (h0 + h1),
                h1,
                6.0 * ((yn - yi) / h1 - (yi - yp) / h0),
            ));
        }
        let mut m = vec![0.0; n];
        for _ in 0..200 {
            for i in 0..n {
                let prev = m.get((i + n - 1) % n).copied().unwrap_or(0.0);
                let next = m.get((i + 1) % n).copied().unwrap_or(0.0);
                if let (Some(&(a, d, c, r)), Some(mi)) = (rows.get(i), m.get_mut(i)) {
                    *mi = (r - a * prev - c * next) / d;
                }
            }
        }
        Self { x, y, m }
    }

    pub(super) fn at(&self, x: f64) -> f64 {
        let n = self.x.len();
        let x = x.rem_euclid(100.0);
        // Interval [x_i, x_{i+1}) with wrap (before the first knot: the last
        // interval, shifted down one period).
        let j = self.x.partition_point(|&p| p <= x);
        let i = (j + n - 1) % n;
        let xi = self.x.get(i).copied().unwrap_or(0.0) - if j == 0 { 100.0 } else { 0.0 };
        let xn = self.x.get((i + 1) % n).copied().unwrap_or(0.0)
            + if i + 1 == n && j != 0 { 100.0 } else { 0.0 };
        let (yi, yn) = (
            self.y.get(i).copied().unwrap_or(0.0),
            self.y.get((i + 1) % n).copied().unwrap_or(0.0),
        );
        let (mi, mn) = (
            self.m.get(i).copied().unwrap_or(0.0),
            self.m.get((i + 1) % n).copied().unwrap_or(0.0),
        );
        let h = xn - xi;
        if h <= 0.0 {
            return yi;
        }
        let (a, b) = (xn - x, x - xi);
        mi * a * a * a / (6.0 * h)
            + mn * b * b * b / (6.0 * h)
            + (yi / h - mi * h / 6.0) * a
            + (yn / h - mn * h / 6.0) * b
    }
}

fn read_csv(path: &Path, columns: &[&str]) -> Result<Vec<Vec<f64>>, BaselineError> {
    let text =
        std::fs::read_to_string(path).map_err(|e| BaselineError::Io(path.to_path_buf(), e))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .ok_or_else(|| BaselineError::Format(path.to_path_buf(), "empty file".into()))?
        .split(',')
        .map(str::trim)
        .collect();
    let idx: Vec<usize> = columns
        .iter()
        .map(|c| {
            header
                .iter()
                .position(|h| h == c)
                .ok_or_else(|| BaselineError::Format(path.to_path_buf(), format!("no column {c}")))
        })
        .collect::<Result<_, _>>()?;
    let mut out = vec![Vec::new(); columns.len()];
    for (ln, line) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').collect();
        for (col, &i) in out.iter_mut().zip(&idx) {
            let v = cells
                .get(i)
                .and_then(|c| c.trim().parse::<f64>().ok())
                .ok_or_else(|| {
                    BaselineError::Format(
                        path.to_path_buf(),
                        format!("line {}: bad number", ln + 2),
                    )
                })?;
            col.push(v);
        }
    }
    Ok(out)
}

pub(super) fn load(source: Source, dir: &Path) -> Result<Curves, BaselineError> {
    let sub = |v: &[f64], w: &[f64]| v.iter().zip(w).map(|(a, b)| a - b).collect::<Vec<_>>();
    let take = |file: &str, cols: &[&str]| read_csv(&dir.join(file), cols);
    let c = match source {
        Source::Fukuchi2018Walk => {
            let v = take(
                "walk_fukuchi2018/fukuchi2018_walk_mean_sd_2pct.csv",
                &["pct_gait_cycle", "hip_flex_deg_mean", "knee_flex_deg_mean"],
            )?;
            (v, 0.0, 62.0, None)
        }
        Source::WinterWalk => {
            let v = take(
                "walk_winter/winter_walk_right_HS_to_HS.csv",
                &["pct_gait_cycle", "hip_flex_deg", "knee_flex_deg"],
            )?;
            (v, 0.0, 60.9, None)
        }
        Source::ViconWalk => {
            let v = take(
                "walk_vicon_gaitutils/vicon_normal_sagittal_2pct.csv",
                &[
                    "pct_gait_cycle",
                    "HipFlexExt_mean_deg",
                    "KneeFlexExt_mean_deg",
                    "PelvicTilt_mean_deg",
                ],
            )?;
            (v, 0.0, 65.48, Some(3))
        }
        Source::ReznickStairI20 => {
            let v = take(
                "stair_reznick_cortino/reznick_stair_ascent_mean_150pt.csv",
                &["pct_linspace", "thigh_i20_deg", "knee_i20_deg"],
            )?;
            (v, 5.0, 68.0, None)
        }
        Source::RienerStairAscent => {
            let v = take(
                "stair_riener_cortino/riener_stair_ascent_1000pt.csv",
                &["pct_gait_cycle", "hip_flex_deg", "knee_flex_deg"],
            )?;
            (v, 0.0, 63.0, None)
        }
        Source::ReznickStairD20 => {
            let v = take(
                "stair_reznick_cortino/reznick_stair_descent_mean_150pt.csv",
                &["pct_linspace", "thigh_d20_deg", "knee_d20_deg"],
            )?;
            (v, 24.0, 86.0, None)
        }
    };
    let (mut v, hs, to, tilt) = c;
    let tilt_col = tilt.and_then(|i| v.get(i).cloned());
    let mut it = v.drain(..);
    let (Some(mut pct), Some(mut thigh), Some(mut knee)) = (it.next(), it.next(), it.next()) else {
        return Err(BaselineError::Format(
            dir.to_path_buf(),
            "missing columns".into(),
        ));
    };
    drop(it);
    if let Some(t) = tilt_col {
        thigh = sub(&thigh, &t);
    }
    // A file whose last row is 100 % repeats its first (periodic): drop it
    // so interpolation wraps cleanly; a 150-point linspace file (Reznick)
    // has no repeat and is re-labelled with a period of 150 samples.
    if pct.last().is_some_and(|&p| p >= 100.0 - 1e-9) {
        if matches!(source, Source::ReznickStairI20 | Source::ReznickStairD20) {
            let n = pct.len() as f64;
            pct = (0..pct.len()).map(|i| 100.0 * i as f64 / n).collect();
        } else {
            pct.pop();
            thigh.pop();
            knee.pop();
        }
    }
    if pct.len() < 10
        || pct.iter().any(|&p| !(0.0..100.0).contains(&p))
        || pct.windows(2).any(|w| matches!(w, [a, b] if b <= a))
    {
        return Err(BaselineError::Format(
            dir.to_path_buf(),
            format!("{source:?}: percent axis not increasing"),
        ));
    }
    Ok(Curves {
        thigh: PeriodicSpline::new(pct.clone(), thigh),
        knee: PeriodicSpline::new(pct, knee),
        heel_strike_pct: hs,
        toe_off_pct: to,
    })
}
