//! Plots of a [`Report`]: joint angles, swing-ankle path and stance-ankle
//! torque of the baseline and the optimised gait, in one figure.
//!
//! The format follows the file name: `.svg` through the SVG backend, any
//! other extension (`.png`) through the bitmap backend. Text needs a TTF
//! font: `$EXOGAIT_FONT`, else DejaVu Sans or Liberation Sans from the usual
//! Debian paths (`fonts-dejavu-core`).

use std::ops::Range;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::report::{Report, SampleRow};

pub use plot_font::PlotError;
use plot_font::draw_err;
use sim::plot::{Figure, Series, padded_range, write_figure};

/// Draws `report` to `path` (SVG or PNG by extension), 1200×900 pixels.
pub fn plot_report(report: &Report, path: &Path) -> Result<(), PlotError> {
    write_figure(&ReportFigure(report), path, (1200, 900))
}

/// A report's figure ([`plot_report`]).
struct ReportFigure<'a>(&'a Report);

impl Figure for ReportFigure<'_> {
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static,
    {
        draw(self.0, root)
    }
}

fn column(rows: &[SampleRow], f: impl Fn(&SampleRow) -> Option<f64>) -> Series {
    rows.iter()
        .filter_map(|r| f(r).map(|v| (r.t_s, v)))
        .collect()
}

/// The range of the series' y values, padded.
fn bounds(series: &[&Series]) -> (f64, f64) {
    padded_range(series, |p| p.1)
}

/// The axes and labels of one of the report's four panels.
struct Axes<'a> {
    caption: &'a str,
    x_desc: &'a str,
    y_desc: Option<&'a str>,
    x: Range<f64>,
    y: Range<f64>,
    /// The legend on a half-transparent white box (over many lines).
    legend_background: bool,
}

/// Draws `lines` (series, colour, name) on `area` with `axes`, and their
/// legend.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    axes: Axes<'_>,
    lines: &[(&Series, RGBColor, &str)],
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let mut chart = ChartBuilder::on(area)
        .caption(axes.caption, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(45)
        .build_cartesian_2d(axes.x, axes.y)
        .map_err(draw_err)?;
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(axes.x_desc);
    if let Some(y_desc) = axes.y_desc {
        mesh.y_desc(y_desc);
    }
    mesh.draw().map_err(draw_err)?;
    for &(s, c, n) in lines {
        chart
            .draw_series(LineSeries::new(s.iter().copied(), c.stroke_width(2)))
            .map_err(draw_err)?
            .label(n)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c));
    }
    let mut legend = chart.configure_series_labels();
    if axes.legend_background {
        legend.background_style(WHITE.mix(0.8));
    }
    legend.border_style(BLACK).draw().map_err(draw_err)
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
        let lines: Vec<(&Series, RGBColor, &str)> = series
            .iter()
            .zip(colours)
            .zip(names)
            .map(|((s, c), n)| (s, c, n))
            .collect();
        let axes = Axes {
            caption: &format!("joint angles Θ, {label} (deg)"),
            x_desc: "t (s)",
            y_desc: None,
            x: 0.0..ts,
            y: lo..hi,
            legend_background: true,
        };
        draw_panel(panel, axes, &lines)?;
    }
    // Swing-ankle path.
    if let Some(panel) = panels.get(2) {
        let po: Series = opt.iter().map(|r| (r.p5_m[0], r.p5_m[1])).collect();
        let pb: Series = base.iter().map(|r| (r.p5_m[0], r.p5_m[1])).collect();
        let xs: Vec<f64> = po.iter().chain(&pb).map(|p| p.0).collect();
        let xlo = xs.iter().copied().fold(f64::INFINITY, f64::min);
        let xhi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (ylo, yhi) = bounds(&[&po, &pb]);
        let axes = Axes {
            caption: "swing-ankle path p5 (m)",
            x_desc: "x (m)",
            y_desc: Some("y (m)"),
            x: (xlo - 0.02)..(xhi + 0.02),
            y: ylo..yhi,
            legend_background: false,
        };
        draw_panel(
            panel,
            axes,
            &[(&po, BLUE, "optimised"), (&pb, RED, "baseline")],
        )?;
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
        let axes = Axes {
            caption: "stance-ankle torque τ where c_k = 1 (N·m)",
            x_desc: "t (s)",
            y_desc: None,
            x: 0.0..ts,
            y: lo..hi,
            legend_background: false,
        };
        draw_panel(
            panel,
            axes,
            &[(&to, BLUE, "optimised"), (&tb, RED, "baseline")],
        )?;
    }
    Ok(())
}
