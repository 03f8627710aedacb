//! Plot of a closed-loop run (SVG, or PNG by extension): joint angles (in
//! degrees) against the controller's reference (dashed, in a colour of
//! its own), the feet's paths, and the load on the crutches with the
//! pilot's ankle torque; each time panel shades the gait's phases (swing,
//! weight transfer, safe hold) and marks each fault where it latched.
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
    write_figure(&RunFigure { trace, summary }, path, (1400, 900))
}

/// A figure that draws itself on any plotters backend, so that the choice
/// of SVG or bitmap by the file's extension is written once
/// ([`write_figure`]), for sim's plots and gait-opt's alike.
pub trait Figure {
    /// Draws the whole figure on `root`.
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static;
}

/// Draws `figure` to `path`, `size` pixels: SVG when the extension is
/// `.svg`, any other (`.png`) through the bitmap backend.
pub fn write_figure(figure: &impl Figure, path: &Path, size: (u32, u32)) -> Result<(), PlotError> {
    ensure_font()?;
    let svg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if svg {
        let root = SVGBackend::new(path, size).into_drawing_area();
        figure.draw_on(&root)?;
        root.present().map_err(draw_err)
    } else {
        let root = BitMapBackend::new(path, size).into_drawing_area();
        figure.draw_on(&root)?;
        root.present().map_err(draw_err)
    }
}

/// Points of one line, (x, y).
pub type Series = Vec<(f64, f64)>;

/// The range of `axis` over the finite points of `series`, padded by 5 %
/// on each side so that no line runs along the frame; (−1, 1) when there
/// is none.
pub fn padded_range(series: &[&Series], axis: impl Fn(&(f64, f64)) -> f64) -> (f64, f64) {
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

/// What a time panel shows besides its lines: the phases as shaded
/// spans, and the faults as marked instants.
#[derive(Default)]
struct Timeline {
    /// (start, end, colour, name) of each span of a phase worth seeing.
    bands: Vec<(f64, f64, RGBColor, &'static str)>,
    /// (time, label) of each fault as it latched.
    marks: Vec<(f64, String)>,
}

/// Swing (light yellow), weight transfer (light green), safe hold (light
/// red); standing and waiting are left white.
const SWING_BAND: RGBColor = RGBColor(255, 244, 204);
const TRANSFER_BAND: RGBColor = RGBColor(214, 240, 214);
const HOLD_BAND: RGBColor = RGBColor(250, 210, 210);

fn timeline(trace: &[Sample]) -> Timeline {
    use gait_control::sequencer::Phase;
    let kind = |p: &Phase| match p {
        Phase::Swing { .. } => Some((SWING_BAND, "swing")),
        Phase::Transfer { .. } => Some((TRANSFER_BAND, "transfer")),
        Phase::SafeHold { .. } => Some((HOLD_BAND, "safe hold")),
        Phase::Standing | Phase::WaitingReady { .. } => None,
    };
    let mut out = Timeline::default();
    let mut open: Option<(f64, RGBColor, &'static str)> = None;
    let mut seen = gait_control::faults::FaultSet::EMPTY;
    for s in trace {
        let t = s.state.time_s;
        let now = kind(&s.report.phase);
        if open.map(|(_, c, _)| c) != now.map(|(c, _)| c) {
            if let Some((t0, c, n)) = open.take() {
                out.bands.push((t0, t, c, n));
            }
            open = now.map(|(c, n)| (t, c, n));
        }
        for code in s.report.faults.iter() {
            if !seen.contains(code) {
                seen.insert(code);
                out.marks.push((t, format!("0x{:04x}", code.code())));
            }
        }
    }
    if let (Some((t0, c, n)), Some(last)) = (open, trace.last()) {
        out.bands.push((t0, last.state.time_s, c, n));
    }
    out
}

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    caption: &str,
    x_label: &str,
    y_label: &str,
    lines: &[(String, Series, RGBColor, bool)],
    timeline: &Timeline,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let all: Vec<&Series> = lines.iter().map(|l| &l.1).collect();
    let (x0, x1) = padded_range(&all, |p| p.0);
    let (y0, y1) = padded_range(&all, |p| p.1);
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
    for &(a, b, c, _) in &timeline.bands {
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(a, y0), (b, y1)],
                ShapeStyle::from(c).filled(),
            )))
            .map_err(draw_err)?;
    }
    for (t, label) in &timeline.marks {
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(*t, y0), (*t, y1)],
                ShapeStyle::from(BLACK).stroke_width(1),
            )))
            .map_err(draw_err)?;
        chart
            .draw_series(std::iter::once(Text::new(
                label.clone(),
                (*t, y1),
                ("sans-serif", 13),
            )))
            .map_err(draw_err)?;
    }
    // Solid lines first and wider, dashed ones on top: a line that follows
    // another closely (a reference, the other crutch) stays visible.
    let mut order: Vec<&(String, Series, RGBColor, bool)> = lines.iter().collect();
    order.sort_by_key(|l| l.3);
    for (name, series, colour, dashed) in order {
        let c = *colour;
        if *dashed {
            let style = ShapeStyle::from(c).stroke_width(2);
            chart
                .draw_series(DashedLineSeries::new(series.iter().copied(), 6, 4, style))
                .map_err(draw_err)?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c));
        } else {
            let style = ShapeStyle::from(c).stroke_width(3);
            chart
                .draw_series(LineSeries::new(series.iter().copied(), style))
                .map_err(draw_err)?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c));
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(draw_err)?;
    Ok(())
}

/// A closed-loop run's figure ([`plot_run`]).
struct RunFigure<'a> {
    trace: &'a [Sample],
    summary: &'a RunSummary,
}

impl Figure for RunFigure<'_> {
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static,
    {
        draw(self.trace, self.summary, root)
    }
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
    let title = format!(
        "{title}   (shaded: swing yellow, weight transfer green, safe hold red; lines: faults)"
    );
    let root = root.titled(&title, ("sans-serif", 20)).map_err(draw_err)?;
    let panels = root.split_evenly((2, 2));
    let t = |s: &Sample| s.state.time_s;
    let joint = |j: usize| -> (Series, Series) {
        (
            trace
                .iter()
                .map(|s| (t(s), s.state.joint_angles_rad[j].to_degrees()))
                .collect(),
            trace
                .iter()
                .map(|s| (t(s), f64::from(s.report.reference_rad[j]).to_degrees()))
                .collect(),
        )
    };
    let tl = timeline(trace);
    let none = Timeline::default();
    // Hip red, its reference orange; knee blue, its reference teal.
    let colours = [RED, BLUE];
    let reference_colours = [RGBColor(255, 150, 0), RGBColor(0, 160, 160)];
    for (k, (side, base)) in [("left", 0usize), ("right", 2usize)]
        .into_iter()
        .enumerate()
    {
        let (hip, hip_ref) = joint(base);
        let (knee, knee_ref) = joint(base + 1);
        let lines = vec![
            (format!("{side} hip"), hip, colours[0], false),
            (
                format!("{side} hip reference"),
                hip_ref,
                reference_colours[0],
                true,
            ),
            (format!("{side} knee"), knee, colours[1], false),
            (
                format!("{side} knee reference"),
                knee_ref,
                reference_colours[1],
                true,
            ),
        ];
        if let Some(area) = panels.get(k) {
            panel(
                area,
                &format!("{side} leg: flexion against the reference"),
                "t (s)",
                "degrees",
                &lines,
                &tl,
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
            &none,
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
                ("right crutch".into(), crutch(1), BLUE, true),
                ("|pilot torque|".into(), pilot, BLACK, true),
            ],
            &tl,
        )?;
    }
    Ok(())
}

/// Draws a comparison of two gaits on the same device to `path` (SVG or
/// PNG by extension): both gaits' crutch forces and the pilot's torque on
/// shared axes (time since each gait's first swing), and each step's crutch
/// impulse F as bars.
pub fn plot_comparison(
    title: &str,
    shipped: &crate::compare::GaitRun,
    human: &crate::compare::GaitRun,
    path: &Path,
) -> Result<(), PlotError> {
    let figure = ComparisonFigure {
        title,
        shipped,
        human,
    };
    write_figure(&figure, path, (1400, 900))
}

/// Two gaits' comparison figure ([`plot_comparison`]).
struct ComparisonFigure<'a> {
    title: &'a str,
    shipped: &'a crate::compare::GaitRun,
    human: &'a crate::compare::GaitRun,
}

impl Figure for ComparisonFigure<'_> {
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static,
    {
        draw_comparison(self.title, self.shipped, self.human, root)
    }
}

/// Picks a value from a tick's (crutch forces, pilot torque).
type Pick = dyn Fn(&([f64; 2], f64)) -> f64;

fn draw_comparison<DB: DrawingBackend>(
    title: &str,
    shipped: &crate::compare::GaitRun,
    human: &crate::compare::GaitRun,
    root: &DrawingArea<DB, Shift>,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(draw_err)?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(draw_err)?;
    let (top, bottom) = root.split_vertically(560);
    let panels = top.split_evenly((1, 2));
    // Time from each gait's first swing, thinned to every 10th tick.
    let series = |run: &crate::compare::GaitRun, pick: &Pick| -> Series {
        let t0 = run.steps.first().map_or(0.0, |s| s.start_s);
        run.series
            .iter()
            .step_by(10)
            .filter(|(t, ..)| *t >= t0)
            .map(|(t, f, p)| (t - t0, pick(&(*f, *p))))
            .collect()
    };
    let total = |x: &([f64; 2], f64)| x.0[0] + x.0[1];
    let pilot = |x: &([f64; 2], f64)| x.1.abs();
    let quantities: [(&str, &str, &Pick); 2] = [
        ("crutch force, both crutches (N)", "N", &total),
        ("|pilot ankle torque| (N·m)", "N·m", &pilot),
    ];
    for (area, (caption, unit, pick)) in panels.iter().zip(quantities) {
        panel(
            area,
            caption,
            "t from the first swing (s)",
            unit,
            &[
                ("shipped table".into(), series(shipped, pick), BLUE, false),
                ("human-data gait".into(), series(human, pick), RED, false),
            ],
            &Timeline::default(),
        )?;
    }
    let steps = shipped.steps.len().max(human.steps.len()).max(1);
    let top_f = shipped
        .steps
        .iter()
        .chain(&human.steps)
        .map(|s| s.impulse_ns)
        .fold(1.0f64, f64::max)
        * 1.15;
    let mut chart = ChartBuilder::on(&bottom)
        .caption(
            "crutch impulse F per step (N·s): shipped (blue), human (red)",
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(0.0..steps as f64, 0.0..top_f)
        .map_err(draw_err)?;
    chart
        .configure_mesh()
        .x_desc("step")
        .y_desc("N·s")
        .draw()
        .map_err(draw_err)?;
    let bars = |run: &crate::compare::GaitRun, offset: f64, colour: RGBColor| {
        run.steps
            .iter()
            .enumerate()
            .map(move |(i, s)| {
                let x = i as f64 + offset;
                Rectangle::new([(x, 0.0), (x + 0.35, s.impulse_ns)], colour.filled())
            })
            .collect::<Vec<_>>()
    };
    chart
        .draw_series(bars(shipped, 0.12, BLUE))
        .map_err(draw_err)?;
    chart
        .draw_series(bars(human, 0.53, RED))
        .map_err(draw_err)?;
    Ok(())
}
