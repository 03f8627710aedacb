//! Plots of a [`Report`]: joint angles, swing-ankle path and stance-ankle
//! torque of the baseline and the optimised gait, in one figure.
//!
//! The format follows the file name: `.svg` through the SVG backend, any
//! other extension (`.png`) through the bitmap backend. Text needs a TTF
//! font: `$EXOGAIT_FONT`, else DejaVu Sans or Liberation Sans from the usual
//! Debian paths (`fonts-dejavu-core`).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::report::{Report, SampleRow};

pub use plot_font::PlotError;
use plot_font::{draw_err, font_ready as ensure_font};

/// Draws `report` to `path` (SVG or PNG by extension), 1200×900 pixels.
pub fn plot_report(report: &Report, path: &Path) -> Result<(), PlotError> {
    ensure_font()?;
    let size = (1200, 900);
    let svg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if svg {
        let root = SVGBackend::new(path, size).into_drawing_area();
        draw(report, &root)?;
        root.present().map_err(draw_err)
    } else {
        let root = BitMapBackend::new(path, size).into_drawing_area();
        draw(report, &root)?;
        root.present().map_err(draw_err)
    }
}

type Series = Vec<(f64, f64)>;

fn column(rows: &[SampleRow], f: impl Fn(&SampleRow) -> Option<f64>) -> Series {
    rows.iter()
        .filter_map(|r| f(r).map(|v| (r.t_s, v)))
        .collect()
}

fn bounds(series: &[&Series]) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in series {
        for &(_, y) in s.iter() {
            if y.is_finite() {
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (-1.0, 1.0);
    }
    let pad = 0.05 * (hi - lo).max(1e-6);
    (lo - pad, hi + pad)
}

fn draw<DB: DrawingBackend>(report: &Report, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(draw_err)?;
    let title = format!(
        "{}: optimised J = {:.1} vs baseline J = {}",
        report.problem.case,
        report.j.j,
        report
            .baseline
            .as_ref()
            .map_or("—".to_string(), |b| format!("{:.1}", b.j.j))
    );
    let root = root.titled(&title, ("sans-serif", 24)).map_err(draw_err)?;
    let panels = root.split_evenly((2, 2));
    let empty = Vec::new();
    let base = report.baseline.as_ref().map_or(&empty, |b| &b.samples);
    let opt = &report.samples;
    let ts = report.problem.step_time_s;
    let colours = [RED, BLUE, GREEN, MAGENTA, CYAN];
    let names = [
        "θ1 ankle",
        "θ2 st. knee",
        "θ3 st. hip",
        "θ4 sw. hip",
        "θ5 sw. knee",
    ];
    // Joint angles (anatomical sign of each joint), optimised and baseline.
    for (panel, (rows, label)) in panels
        .iter()
        .take(2)
        .zip([(opt, "optimised"), (base, "baseline")])
    {
        let series: Vec<Series> = (0..5)
            .map(|j| column(rows, |r| r.theta_rad.get(j).map(|v| v.to_degrees())))
            .collect();
        let refs: Vec<&Series> = series.iter().collect();
        let (lo, hi) = bounds(&refs);
        let mut chart = ChartBuilder::on(panel)
            .caption(format!("joint angles Θ, {label} (deg)"), ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(45)
            .build_cartesian_2d(0.0..ts, lo..hi)
            .map_err(draw_err)?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .draw()
            .map_err(draw_err)?;
        for ((s, c), n) in series.iter().zip(colours).zip(names) {
            chart
                .draw_series(LineSeries::new(s.iter().copied(), c.stroke_width(2)))
                .map_err(draw_err)?
                .label(n)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(draw_err)?;
    }
    // Swing-ankle path.
    if let Some(panel) = panels.get(2) {
        let po: Series = opt.iter().map(|r| (r.p5_m[0], r.p5_m[1])).collect();
        let pb: Series = base.iter().map(|r| (r.p5_m[0], r.p5_m[1])).collect();
        let xs: Vec<f64> = po.iter().chain(&pb).map(|p| p.0).collect();
        let xlo = xs.iter().copied().fold(f64::INFINITY, f64::min);
        let xhi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (ylo, yhi) = bounds(&[&po, &pb]);
        let mut chart = ChartBuilder::on(panel)
            .caption("swing-ankle path p5 (m)", ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(45)
            .build_cartesian_2d((xlo - 0.02)..(xhi + 0.02), ylo..yhi)
            .map_err(draw_err)?;
        chart
            .configure_mesh()
            .x_desc("x (m)")
            .y_desc("y (m)")
            .draw()
            .map_err(draw_err)?;
        for (s, c, n) in [(&po, BLUE, "optimised"), (&pb, RED, "baseline")] {
            chart
                .draw_series(LineSeries::new(s.iter().copied(), c.stroke_width(2)))
                .map_err(draw_err)?
                .label(n)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c));
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .draw()
            .map_err(draw_err)?;
    }
    // Stance-ankle torque τ where it counts (c_k = 1).
    if let Some(panel) = panels.get(3) {
        let tau = |rows: &[SampleRow]| {
            column(rows, |r| {
                if r.c_k > 0.0 {
                    r.tau_nm.and_then(|t| t.first().copied())
                } else {
                    None
                }
            })
        };
        let (to, tb) = (tau(opt), tau(base));
        let (lo, hi) = bounds(&[&to, &tb]);
        let mut chart = ChartBuilder::on(panel)
            .caption(
                "stance-ankle torque τ where c_k = 1 (N·m)",
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(45)
            .build_cartesian_2d(0.0..ts, lo..hi)
            .map_err(draw_err)?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .draw()
            .map_err(draw_err)?;
        for (s, c, n) in [(&to, BLUE, "optimised"), (&tb, RED, "baseline")] {
            chart
                .draw_series(LineSeries::new(s.iter().copied(), c.stroke_width(2)))
                .map_err(draw_err)?
                .label(n)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c));
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .draw()
            .map_err(draw_err)?;
    }
    Ok(())
}
