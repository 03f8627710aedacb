//! Plot of a closed-loop run (SVG, or PNG by extension): joint angles
//! against the controller's reference, the feet's paths, and the load on
//! the crutches with the pilot's ankle torque.
//!
//! Text needs a TTF font (plotters' ab_glyph backend, no fontconfig):
//! `$EXOGAIT_FONT`, else DejaVu Sans or Liberation Sans from the usual Debian
//! paths (crates/plot-font, shared with gait-opt's report plots).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::closed_loop::Sample;
use crate::summary::RunSummary;

pub use plot_font::PlotError;
use plot_font::{draw_err, font_ready as ensure_font};

/// Draws a run to `path` (SVG or PNG by extension), 1400×900 pixels.
pub fn plot_run(trace: &[Sample], summary: &RunSummary, path: &Path) -> Result<(), PlotError> {
    ensure_font()?;
    let size = (1400, 900);
    let svg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if svg {
        let root = SVGBackend::new(path, size).into_drawing_area();
        draw(trace, summary, &root)?;
        root.present().map_err(draw_err)
    } else {
        let root = BitMapBackend::new(path, size).into_drawing_area();
        draw(trace, summary, &root)?;
        root.present().map_err(draw_err)
    }
}

type Series = Vec<(f64, f64)>;

fn range(series: &[&Series], axis: impl Fn(&(f64, f64)) -> f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for s in series {
        for p in s.iter() {
            let v = axis(p);
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (-1.0, 1.0);
    }
    let pad = 0.05 * (hi - lo).max(1e-6);
    (lo - pad, hi + pad)
}

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    caption: &str,
    x_label: &str,
    y_label: &str,
    lines: &[(String, Series, RGBColor, bool)],
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let all: Vec<&Series> = lines.iter().map(|l| &l.1).collect();
    let (x0, x1) = range(&all, |p| p.0);
    let (y0, y1) = range(&all, |p| p.1);
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(draw_err)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .draw()
        .map_err(draw_err)?;
    for (name, series, colour, dashed) in lines {
        let style = ShapeStyle::from(*colour).stroke_width(if *dashed { 1 } else { 2 });
        let c = *colour;
        chart
            .draw_series(LineSeries::new(series.iter().copied(), style))
            .map_err(draw_err)?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(draw_err)?;
    Ok(())
}

fn draw<DB: DrawingBackend>(
    trace: &[Sample],
    summary: &RunSummary,
    root: &DrawingArea<DB, Shift>,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(draw_err)?;
    let title = match &summary.landing {
        Some(l) => format!(
            "exogait closed loop: {} landing(s); first at x = {:.3} m (plan {:.3} m), crutch load F = {:.0} N·s",
            summary.landings,
            l.position_m[0],
            summary.planned_landing_x_m,
            summary.crutch_impulse_ns
        ),
        None => "exogait closed loop: no landing".to_string(),
    };
    let root = root.titled(&title, ("sans-serif", 22)).map_err(draw_err)?;
    let panels = root.split_evenly((2, 2));
    let t = |s: &Sample| s.state.time_s;
    let joint = |j: usize| -> (Series, Series) {
        (
            trace
                .iter()
                .map(|s| (t(s), s.state.joint_angles_rad[j]))
                .collect(),
            trace
                .iter()
                .map(|s| (t(s), f64::from(s.report.reference_rad[j])))
                .collect(),
        )
    };
    let colours = [RED, BLUE];
    for (k, (side, base)) in [("left", 0usize), ("right", 2usize)]
        .into_iter()
        .enumerate()
    {
        let (hip, hip_ref) = joint(base);
        let (knee, knee_ref) = joint(base + 1);
        let lines = vec![
            (format!("{side} hip"), hip, colours[0], false),
            (format!("{side} hip ref"), hip_ref, colours[0], true),
            (format!("{side} knee"), knee, colours[1], false),
            (format!("{side} knee ref"), knee_ref, colours[1], true),
        ];
        if let Some(area) = panels.get(k) {
            panel(
                area,
                &format!("{side} leg: flexion vs reference"),
                "t (s)",
                "rad",
                &lines,
            )?;
        }
    }
    let foot = |i: usize| -> Series {
        trace
            .iter()
            .map(|s| (s.state.feet_m[i][0], s.state.feet_m[i][1]))
            .collect()
    };
    if let Some(area) = panels.get(2) {
        panel(
            area,
            "feet in the world (x forward, y up)",
            "x (m)",
            "y (m)",
            &[
                ("left ankle".into(), foot(0), RED, false),
                ("right ankle".into(), foot(1), BLUE, false),
            ],
        )?;
    }
    let crutch = |i: usize| -> Series {
        trace
            .iter()
            .map(|s| (t(s), s.state.crutch_forces_n[i]))
            .collect()
    };
    let pilot: Series = trace
        .iter()
        .map(|s| (t(s), s.state.pilot_torque_nm.abs()))
        .collect();
    if let Some(area) = panels.get(3) {
        panel(
            area,
            "crutches (N) and |pilot ankle torque| (N·m)",
            "t (s)",
            "N, N·m",
            &[
                ("left crutch".into(), crutch(0), RED, false),
                ("right crutch".into(), crutch(1), BLUE, false),
                ("|pilot torque|".into(), pilot, BLACK, true),
            ],
        )?;
    }
    Ok(())
}
