//! `exogait optimize`: the step problem from the command line (paper mode
//! or a geometry of one's own), gait-opt's search, the baseline, the JSON
//! report and its plot.
//!
//! Non-paper geometry (any of --stride/--step-time/--rise/--tread/--model):
//! - walk: start (−stride/2, 0), landing (+stride/2, 0);
//! - stair-up: start (−tread, −rise), landing (+tread, +rise), the stance
//!   foot on the first step (the paper's stair is tread 0.275, rise 0.0935:
//!   stride 0.55);
//! - stair-down: start (−tread, +rise), landing (+tread, −rise), the stance
//!   foot on the middle step; no paper mode.
//!
//! The stance-shank profile φ1(t) and r2(0) are the paper case's, with the
//! profile's time constants scaled to the step time (k·ts₀/ts, t_c·ts/ts₀),
//! so that its shape over the normalised swing is unchanged. Stair-down has
//! none in the paper; it uses [`STAIR_DOWN_STANCE`].

use std::io::IsTerminal;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use gait_core::BodyModel;
use gait_core::gait::StanceAnkleProfile;
use gait_core::problem::{PaperCase, PaperProblem, StepCase};
use gait_opt::{
    OptimizeConfig, OptimizeError, Progress, Report, Source, baseline, baseline_for_problem,
    default_data_dir, plot_report,
};
use indicatif::{ProgressBar, ProgressStyle};

/// The paper-mode record J (scipy DE + Powell, docs/optimiser.md).
const RECORD_WALK: f64 = 3361.9;
/// The paper-mode record J for stair ascent.
const RECORD_STAIR_UP: f64 = 1476.6;

/// The paper's stair (section V): rise, tread (m) and step time (s).
pub const PAPER_STAIR: (f64, f64, f64) = (0.0935, 0.275, 2.28);

/// Stair descent's assumed stance-shank profile at ts = 2.28 s,
/// (a, b, k, t_c) = (0, 0.7 rad, 4 1/s, ts/2): the stair ascent's logistic
/// with a larger forward lean at the end, because the hip must come down
/// and forward over the stance foot for the swing ankle to reach the step
/// below. At the paper's stair the initial guess's landing is out of the
/// IK's reach (its 45° cap on stance-knee flexion) unless φ1(ts) ≳ 0.5 rad;
/// with b = 0.6 rad the search found no feasible step in 20,000
/// evaluations, 0.7 rad (40°) is the smallest of 0.6, 0.7, 0.8, 1.0 that it
/// solves (and 0.8, 1.0 give higher J). r2(0) = 0.5 as in ascent.
pub const STAIR_DOWN_STANCE: StanceAnkleProfile<f64> = StanceAnkleProfile {
    a_rad: 0.0,
    b_rad: 0.7,
    k_per_s: 4.0,
    t_c_s: 1.14,
};

/// Weight of the squared excess over a model file's joint limits, N²·m²
/// per rad² per sample (1° over for a tenth of the step costs about a good
/// step's whole torque part).
const MODEL_LIMIT_WEIGHT: f64 = 1.0e7;

/// Which step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CaseArg {
    /// Level walking (paper: stride 0.6 m, step time 2.24 s).
    Walk,
    /// Stair ascent (paper: rise 0.0935 m, tread 0.275 m, step time 2.28 s).
    StairUp,
    /// Stair descent: no paper mode; defaults to the paper's stair.
    StairDown,
}

impl CaseArg {
    fn label(self) -> &'static str {
        match self {
            Self::Walk => "walk",
            Self::StairUp => "stair_up",
            Self::StairDown => "stair_down",
        }
    }
}

/// How the problem is defined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ModeArg {
    /// Exactly the paper-mode problem (walk and stair-up only).
    Paper,
    /// The step built from the geometry options (their defaults are the
    /// paper's values).
    Custom,
    /// The device's own problem: double support first, the predicted
    /// crutch load as the cost, within the device's drives and supervisor
    /// (the flash tables are made so); geometry options apply, --model
    /// sets the body and its joint limits.
    Clinical,
}

/// `exogait optimize` options.
#[derive(Debug, Args)]
pub struct OptimizeArgs {
    /// Which step to optimise.
    #[arg(long, value_enum)]
    case: CaseArg,
    /// paper (default for walk and stair-up): the paper-mode problem exactly;
    /// custom: built from the geometry options. stair-down has no paper mode.
    /// Any geometry option or --model implies custom.
    #[arg(long, value_enum)]
    mode: Option<ModeArg>,
    /// Walk: stride, m (swing ankle from −stride/2 to +stride/2; paper 0.6).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    stride: Option<f64>,
    /// Step time ts, s (paper: 2.24 walk, 2.28 stairs).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    step_time: Option<f64>,
    /// Stairs: rise of one step, m (paper 0.0935).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    rise: Option<f64>,
    /// Stairs: tread of one step, m (paper 0.275; stride = 2·tread).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    tread: Option<f64>,
    /// Seed of the search (same seed and budget: same result).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Budget: cost evaluations (at least 200).
    #[arg(long, default_value_t = 20_000, value_name = "N")]
    evals: usize,
    /// Where to write the JSON report.
    #[arg(long, value_name = "FILE.json")]
    out: PathBuf,
    /// Also draw the report (.svg, or .png for any other extension).
    #[arg(long, value_name = "FILE.svg|.png")]
    plot: Option<PathBuf>,
}

/// What went wrong, by exit status.
#[derive(Debug)]
pub enum Failure {
    /// Bad arguments, model, or I/O (exit 2).
    Usage(String),
    /// The search found no feasible step (exit 1).
    Search(String),
}

/// The problem the arguments describe and whether it is paper mode.
pub struct Setup {
    /// The problem.
    pub problem: PaperProblem<f64>,
    /// True for `PaperProblem::paper`.
    pub paper: bool,
}

fn positive(name: &str, v: Option<f64>, lo: f64, hi: f64) -> Result<Option<f64>, String> {
    match v {
        Some(x) if !(x.is_finite() && x >= lo && x <= hi) => {
            Err(format!("--{name} must be within {lo}..{hi}, got {x}"))
        }
        other => Ok(other),
    }
}

/// Builds the problem from the arguments (see the module documentation).
pub fn setup(a: &OptimizeArgs, model: Option<BodyModel<f64>>) -> Result<Setup, String> {
    let stride = positive("stride", a.stride, 0.05, 1.2)?;
    let step_time = positive("step-time", a.step_time, 0.5, 5.1)?;
    let rise = positive("rise", a.rise, 0.0, 0.25)?;
    let tread = positive("tread", a.tread, 0.05, 0.6)?;
    let overrides: Vec<&str> = [
        ("--stride", stride.is_some()),
        ("--step-time", step_time.is_some()),
        ("--rise", rise.is_some()),
        ("--tread", tread.is_some()),
        ("--model", model.is_some()),
    ]
    .into_iter()
    .filter_map(|(n, given)| given.then_some(n))
    .collect();
    match (a.case, a.mode) {
        (CaseArg::StairDown, Some(ModeArg::Paper)) => {
            return Err(
                "stair-down has no paper mode (the paper optimises walking and stair \
                        ascent only); leave out --mode or use --mode custom"
                    .into(),
            );
        }
        (_, Some(ModeArg::Paper)) if !overrides.is_empty() => {
            return Err(format!(
                "--mode paper is the paper's problem exactly and cannot be combined with {}; \
                 leave out --mode paper to optimise that geometry",
                overrides.join(", ")
            ));
        }
        _ => {}
    }
    match a.case {
        CaseArg::Walk if rise.is_some() || tread.is_some() => {
            return Err("--rise and --tread are for stair cases; walk takes --stride".into());
        }
        CaseArg::StairUp | CaseArg::StairDown if stride.is_some() => {
            return Err("stair cases take --tread (stride = 2·tread), not --stride".into());
        }
        _ => {}
    }
    let paper_case = match a.case {
        CaseArg::Walk => PaperCase::Walk,
        CaseArg::StairUp | CaseArg::StairDown => PaperCase::StairUp,
    };
    let custom =
        a.case == CaseArg::StairDown || a.mode == Some(ModeArg::Custom) || !overrides.is_empty();
    if !custom {
        return Ok(Setup {
            problem: PaperProblem::paper(paper_case),
            paper: true,
        });
    }
    let base = StepCase::<f64>::paper(paper_case);
    let ts0 = base.step_time_s;
    let ts = step_time.unwrap_or(ts0);
    let (rise0, tread0, _) = PAPER_STAIR;
    let (start_m, landing_m) = match a.case {
        CaseArg::Walk => {
            let s = stride.unwrap_or(base.landing_m[0] - base.start_m[0]);
            ([-s / 2.0, 0.0], [s / 2.0, 0.0])
        }
        CaseArg::StairUp => {
            let (r, t) = (rise.unwrap_or(rise0), tread.unwrap_or(tread0));
            ([-t, -r], [t, r])
        }
        CaseArg::StairDown => {
            let (r, t) = (rise.unwrap_or(rise0), tread.unwrap_or(tread0));
            ([-t, r], [t, -r])
        }
    };
    let profile = match a.case {
        CaseArg::StairDown => STAIR_DOWN_STANCE,
        _ => base.stance,
    };
    let stance = StanceAnkleProfile {
        a_rad: profile.a_rad,
        b_rad: profile.b_rad,
        k_per_s: profile.k_per_s * (ts0 / ts),
        t_c_s: profile.t_c_s * (ts / ts0),
    };
    let case = StepCase {
        start_m,
        landing_m,
        step_time_s: ts,
        stance,
        r2_start: base.r2_start,
        phi3_start_rad: base.phi3_start_rad,
        end_posture: None,
        rest_at_ends: false,
        foot: None,
        ik: gait_core::ik::IkOptions::paper(),
    };
    let given = model.is_some();
    let model = model.unwrap_or_else(BodyModel::paper_table_iii);
    let mut problem = PaperProblem::new(case, model);
    if given {
        // The model file's joint limits hold: a soft limit at the stops
        // themselves, heavy enough that the optimum stays inside.
        problem.joint_range_limit = Some(gait_core::problem::JointRangeLimit {
            limits: *model.limits(),
            margin_rad: 0.0,
            weight: MODEL_LIMIT_WEIGHT,
        });
    }
    Ok(Setup {
        problem,
        paper: false,
    })
}

/// Runs `exogait optimize --mode clinical`: writes a clinical report.
fn run_clinical(a: &OptimizeArgs, model: Option<BodyModel<f64>>) -> Result<(), Failure> {
    use gait_core::tables::GaitKind;
    use gait_opt::clinical::{ClinicalCase, ClinicalConfig, optimize_clinical};
    use gait_opt::clinical_report::ClinicalReport;
    if a.plot.is_some() {
        return Err(Failure::Usage(
            "--plot draws paper-mode reports; play a clinical report with \
             `exogait simulate --table REPORT.json --plot FILE`"
                .into(),
        ));
    }
    let stride = positive("stride", a.stride, 0.05, 1.2).map_err(Failure::Usage)?;
    let step_time = positive("step-time", a.step_time, 0.5, 5.0).map_err(Failure::Usage)?;
    let rise = positive("rise", a.rise, 0.0, 0.25).map_err(Failure::Usage)?;
    let tread = positive("tread", a.tread, 0.05, 0.6).map_err(Failure::Usage)?;
    let device = exogait_device::DeviceConfig::exogait()
        .map_err(|e| Failure::Usage(format!("device configuration: {e:?}")))?;
    let kind = match a.case {
        CaseArg::Walk => GaitKind::Walk,
        CaseArg::StairUp => GaitKind::StairUp,
        CaseArg::StairDown => GaitKind::StairDown,
    };
    let mut case = ClinicalCase::for_gait(kind, &device);
    if let Some(s) = stride {
        case.spacing_m = [s / 2.0, 0.0];
    }
    if let Some(t) = tread {
        case.spacing_m[0] = t;
    }
    if let Some(r) = rise {
        case.spacing_m[1] = if kind == GaitKind::StairDown { -r } else { r };
    }
    if let Some(t) = step_time {
        case.step_time_s = t;
    }
    if let Some(m) = model {
        case = case.with_model(m);
    }
    let config = ClinicalConfig {
        seed: a.seed,
        max_evals: a.evals,
    };
    let r = optimize_clinical(&case, &config, &mut |_, _| {})
        .map_err(|e| Failure::Search(e.to_string()))?;
    let report = ClinicalReport::new(&case, &r, a.seed);
    let text = report
        .to_json()
        .map_err(|e| Failure::Usage(format!("report: {e}")))?;
    std::fs::write(&a.out, text + "\n")
        .map_err(|e| Failure::Usage(format!("--out {}: cannot write: {e}", a.out.display())))?;
    let e = &r.evaluation;
    outln!(
        "{} (clinical mode): spacing ({}, {}) m, ts {} s, seed {}\n\
         predicted balance impulse {:.1} N·s (J {:.1}, penalties {:.1}); pilot peak {:.1} N·m; \
         joint peaks {:.0}/{:.0}/{:.0}/{:.0} N·m; clearance {:.3} m\n\
         {} evaluations; report {}",
        a.case.label(),
        case.spacing_m[0],
        case.spacing_m[1],
        case.step_time_s,
        a.seed,
        e.balance_ns,
        e.j,
        e.penalty,
        e.pilot_peak_nm,
        e.joint_peak_nm[0],
        e.joint_peak_nm[1],
        e.joint_peak_nm[2],
        e.joint_peak_nm[3],
        e.clearance_m,
        r.evaluations,
        a.out.display()
    );
    // The result must be a gait the device can play (on the model asked
    // for): otherwise the search failed, whatever its cost.
    let image = gait_opt::tables::table_image(kind, &case.ik, &r.phi)
        .map_err(|e| Failure::Search(format!("the result is not a table: {e}")))?;
    let on = device
        .fitted(&case.model)
        .map_err(|e| Failure::Usage(format!("model: {e}")))?;
    crate::table::admit(&image, &on, &a.out).map_err(|e| {
        Failure::Search(format!(
            "no playable step found ({}); the report is written for inspection",
            e.message
        ))
    })?;
    Ok(())
}

/// Runs `exogait optimize`.
pub fn run(a: &OptimizeArgs, model: Option<BodyModel<f64>>) -> Result<(), Failure> {
    if a.mode == Some(ModeArg::Clinical) {
        return run_clinical(a, model);
    }
    let s = setup(a, model).map_err(Failure::Usage)?;
    if a.evals < 200 {
        return Err(Failure::Usage(format!(
            "--evals must be at least 200, got {}",
            a.evals
        )));
    }
    let paper_case = match a.case {
        CaseArg::Walk => PaperCase::Walk,
        CaseArg::StairUp | CaseArg::StairDown => PaperCase::StairUp,
    };
    let mut config = OptimizeConfig::new(paper_case);
    config.seed = a.seed;
    config.max_evals = a.evals;

    let bar = if std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(a.evals as u64);
        if let Ok(style) = ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} evaluations, best J {msg}",
        ) {
            bar.set_style(style);
        }
        bar.set_message("none feasible yet");
        bar
    } else {
        ProgressBar::hidden()
    };
    let mut progress = |p: &Progress| {
        bar.set_position(p.evaluations as u64);
        if p.best_j.is_finite() {
            bar.set_message(format!("{:.1}", p.best_j));
        }
    };
    let result = gait_opt::solver::optimize_problem(&s.problem, &config, &mut progress).map_err(
        |e| match e {
            OptimizeError::NoFeasiblePoint => Failure::Search(format!(
                "no feasible step found in {} evaluations: the IK cannot reach this geometry \
                 with the assumed stance-shank profile (try a smaller rise or tread, or \
                 another seed or budget)",
                a.evals
            )),
            other => Failure::Search(other.to_string()),
        },
    );
    bar.finish_and_clear();
    let result = result?;

    let (base, note) = if a.case == CaseArg::StairDown {
        (
            None,
            Some(
                "no stair-descent baseline: gait-opt has no descent data source \
                 (baselines exist for walking and stair ascent)"
                    .to_string(),
            ),
        )
    } else {
        let built = if s.paper {
            baseline(paper_case)
        } else {
            baseline_for_problem(&s.problem, Source::primary(paper_case), &default_data_dir())
        };
        match built {
            Ok(b) => (Some(b), None),
            Err(e) => (None, Some(format!("baseline not built: {e}"))),
        }
    };
    let mut report = Report::for_problem(a.case.label(), &s.problem, &result, base.as_ref())
        .map_err(|e| Failure::Search(format!("report: {e}")))?;
    report.baseline_note = note;
    let text = report
        .to_json()
        .map_err(|e| Failure::Usage(format!("report: {e}")))?;
    std::fs::write(&a.out, text + "\n")
        .map_err(|e| Failure::Usage(format!("--out {}: cannot write: {e}", a.out.display())))?;
    if let Some(path) = &a.plot {
        plot_report(&report, path)
            .map_err(|e| Failure::Usage(format!("--plot {}: {e}", path.display())))?;
    }
    out!("{}", summary(a, &s, &report));
    Ok(())
}

fn pct_below(reference: f64, value: f64) -> f64 {
    100.0 * (reference - value) / reference
}

/// The few lines printed after a run.
fn summary(a: &OptimizeArgs, s: &Setup, r: &Report) -> String {
    let c = &r.problem;
    let mut out = format!(
        "{} ({}): start ({}, {}) m, landing ({}, {}) m, ts {} s, seed {}\n",
        c.case,
        if s.paper {
            "paper mode"
        } else {
            "custom geometry"
        },
        c.start_m[0],
        c.start_m[1],
        c.landing_m[0],
        c.landing_m[1],
        c.step_time_s,
        r.solver.seed,
    );
    out += &format!(
        "J = {:.1} (torque {:.1} + velocity {:.1}), tau RMS {:.1} N·m, peak {:.1} N·m\n",
        r.j.j, r.j.torque, r.j.velocity, r.tau_rms_nm, r.tau_peak_nm
    );
    if s.paper {
        let record = match a.case {
            CaseArg::Walk => RECORD_WALK,
            _ => RECORD_STAIR_UP,
        };
        out += &format!(
            "paper-mode record J = {record}: {:.1} % {}\n",
            pct_below(record, r.j.j).abs(),
            if r.j.j <= record { "lower" } else { "higher" }
        );
    }
    match (&r.baseline, &r.reduction_pct) {
        (Some(b), Some(red)) => {
            out += &format!(
                "baseline {:?}: J = {:.1} (torque {:.1}), tau RMS {:.1}, peak {:.1} N·m\n",
                b.source, b.j.j, b.j.torque, b.j.tau_rms_nm, b.j.tau_peak_nm
            );
            out += &format!(
                "reduction: torque part {:.1} %, tau RMS {:.1} %, tau peak {:.1} %, J {:.1} %\n",
                red.torque_part, red.tau_rms, red.tau_peak, red.j
            );
        }
        _ => {
            out += &format!(
                "baseline: none ({})\n",
                r.baseline_note.as_deref().unwrap_or("not built")
            );
        }
    }
    out += &format!(
        "{} evaluations, {} CMA-ES runs, {:.2} s wall; report {}",
        r.solver.evaluations,
        r.solver.runs,
        r.solver.wall_s,
        a.out.display()
    );
    if let Some(p) = &a.plot {
        out += &format!(", plot {}", p.display());
    }
    out.push('\n');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(case: CaseArg) -> OptimizeArgs {
        OptimizeArgs {
            case,
            mode: None,
            stride: None,
            step_time: None,
            rise: None,
            tread: None,
            seed: 1,
            evals: 200,
            out: PathBuf::from("x.json"),
            plot: None,
        }
    }

    #[test]
    fn custom_mode_at_paper_values_is_paper_mode() -> Result<(), String> {
        for (case, pc) in [
            (CaseArg::Walk, PaperCase::Walk),
            (CaseArg::StairUp, PaperCase::StairUp),
        ] {
            let mut a = args(case);
            assert!(setup(&a, None)?.paper);
            a.mode = Some(ModeArg::Custom);
            let s = setup(&a, None)?;
            assert!(!s.paper);
            assert_eq!(s.problem, PaperProblem::paper(pc));
        }
        Ok(())
    }

    #[test]
    fn stair_down_defaults_are_feasible_at_the_initial_guess() -> Result<(), String> {
        let s = setup(&args(CaseArg::StairDown), None)?;
        assert!(!s.paper);
        assert_eq!(s.problem.case.start_m, [-0.275, 0.0935]);
        assert_eq!(s.problem.case.landing_m, [0.275, -0.0935]);
        let p = s.problem.initial_guess();
        s.problem.cost(&p).map_err(|e| e.to_string())?;
        Ok(())
    }

    #[test]
    fn paper_mode_with_geometry_is_refused() {
        let mut a = args(CaseArg::Walk);
        a.mode = Some(ModeArg::Paper);
        a.stride = Some(0.5);
        assert!(setup(&a, None).is_err_and(|e| e.contains("--stride")));
        let mut a = args(CaseArg::StairDown);
        a.mode = Some(ModeArg::Paper);
        assert!(setup(&a, None).is_err_and(|e| e.contains("no paper mode")));
        let mut a = args(CaseArg::Walk);
        a.rise = Some(0.1);
        assert!(setup(&a, None).is_err());
    }
}
