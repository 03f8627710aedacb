//! `exogait simulate`: closed-loop steps of the real controller
//! (gait-control) on the simulated exoskeleton and pilot (sim), with the
//! tables the firmware carries in flash or a table file, optionally with
//! faults injected (`--inject`). Prints the run's metrics, or with `--json`
//! what the run did to the pilot and each fault's detection and reaction;
//! writes a plot (`--plot`, SVG or PNG). No algorithm here:
//! `sim::scenario`, `sim::inject` and `sim::outcome` do the work.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use gait_control::operator::Gait;
use serde::Serialize;
use sim::inject::Injection;

/// Longest simulated run, s.
const MAX_SECONDS: f64 = 120.0;

/// Which gait to simulate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
#[value(rename_all = "kebab-case")]
pub enum SimGait {
    /// Level walking.
    Walk,
    /// Stair ascent on the paper's staircase (rise 93.5 mm, tread 275 mm).
    StairUp,
    /// Stair descent on the same staircase walked down (the trailing heel
    /// lifts: the feet's toe rocker).
    StairDown,
}

impl SimGait {
    /// The table kind.
    pub fn kind(self) -> gait_core::tables::GaitKind {
        match self {
            Self::Walk => gait_core::tables::GaitKind::Walk,
            Self::StairUp => gait_core::tables::GaitKind::StairUp,
            Self::StairDown => gait_core::tables::GaitKind::StairDown,
        }
    }
}

/// Options of `exogait simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// The gait: walk, stair-up or stair-down (with the table the firmware
    /// carries for it), or a gait's name in the bundle given with
    /// `--bundle`.
    #[arg(long, value_name = "NAME", default_value = "walk")]
    pub gait: String,
    /// A patient's bundle (`exogait tables`): the device fitted to its
    /// patient plays its gait named by `--gait`.
    #[arg(long, value_name = "FILE.bundle", conflicts_with = "table")]
    pub bundle: Option<PathBuf>,
    /// Simulated time at most, s (default: enough for the steps asked, 4 s
    /// and the table's step time plus 3 s a step; the run also stops 1.5 s
    /// after the last landing asked for, or 1 s into a safe hold).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub seconds: Option<f64>,
    /// Steps (landings) to walk.
    #[arg(long, default_value_t = 4)]
    pub steps: usize,
    /// Write a plot of the run (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Play this table (flash format, `exogait table`) or `optimize`
    /// report instead of the flash table; its kind sets the gait. Refused
    /// before the run when the device cannot play it.
    #[arg(long, value_name = "FILE")]
    pub table: Option<std::path::PathBuf>,
    /// Inject a fault: KIND[=VALUE][:TARGET]@SECONDS, e.g.
    /// `encoder-parity:left-knee@2.5`, `encoder-jump=200:right-hip@3.1`,
    /// `motor-weak=0.5:left-knee@2`, `estop@5`, `overrun=5@4`. Repeatable.
    /// Kinds: encoder-bus, encoder-parity, encoder-error-flag,
    /// encoder-stuck, encoder-jump=<counts>, encoder-glitch=<counts> (on
    /// left-/right-hip, -knee, -ankle); fsr-open, fsr-short,
    /// fsr-over-range, fsr-spike=<newtons> (on left-/right-foot, -crutch);
    /// adc-bus; motor-weak=<fraction>, gear-slip=<fraction>, motor-stuck,
    /// pwm-fail, dir-fail, current-open, current-short (on a hip or knee);
    /// estop, estop-read, button-read, overrun=<count>,
    /// pilot-lean=<rad>, pilot-stops-balancing, and with `--replan on`
    /// replan-timeout, replan-refused (the next re-plan's answer late or
    /// refused: the table is played) (no target).
    #[arg(long, value_name = "FAULT", value_parser = parse_injection)]
    pub inject: Vec<Injection>,
    /// Print a JSON summary (landings, tracking, limit margins, fall,
    /// faults with detection and reaction) instead of the text.
    #[arg(long)]
    pub json: bool,
    /// The pilot and whether the board re-plans.
    #[command(flatten)]
    pub conditions: crate::conditions::Conditions,
}

fn parse_injection(text: &str) -> Result<Injection, String> {
    text.parse::<Injection>().map_err(|e| e.to_string())
}

/// `--json`: what the run did to the pilot and each fault's course.
#[derive(Debug, Serialize)]
struct SimulateJson {
    gait: &'static str,
    steps_asked: usize,
    landings: usize,
    landed_on_plan: bool,
    injected: Vec<InjectedJson>,
    tracking_rms_rad: [f64; 4],
    tracking_peak_rad: [f64; 4],
    worst_limit_margin_rad: f64,
    worst_limit_joint: &'static str,
    fell: bool,
    fell_reason: Option<String>,
    faults: Vec<FaultJson>,
    ended_by: Option<String>,
    /// Per step: its landing less the previous one less the planned
    /// step, m.
    step_error_m: Vec<f64>,
    /// Per step: the time the device waited for the pilot before it, s.
    waited_s: Vec<f64>,
    /// Each re-plan: its answer and its cost on the board.
    replans: Vec<ReplanJson>,
    conditions: crate::conditions::Conditions,
}

#[derive(Debug, Serialize)]
struct ReplanJson {
    asked_s: f64,
    /// The re-planner's answer: `replanned` or `table`.
    answer: &'static str,
    evals: u16,
    instructions: u64,
}

#[derive(Debug, Serialize)]
struct InjectedJson {
    fault: String,
    at_s: f64,
}

#[derive(Debug, Serialize)]
struct FaultJson {
    code: String,
    name: &'static str,
    injected_s: Option<f64>,
    detected_s: f64,
    latency_ticks: Option<u64>,
    reaction: &'static str,
    /// The channel the supervisor's log first names it on (joint, ankle,
    /// force sensor or motor index), if any.
    channel: Option<u8>,
    safe_state_s: Option<f64>,
}

/// The hips' and knees' names, in joint order.
pub(crate) const JOINT_NAMES: [&str; 4] = ["left-hip", "left-knee", "right-hip", "right-knee"];

fn reaction_name(r: gait_control::faults::Reaction) -> &'static str {
    use gait_control::faults::Reaction;
    match r {
        Reaction::None => "none",
        Reaction::PlayTable => "play-table",
        Reaction::FinishStepThenHold => "finish-step-then-hold",
        Reaction::SafeHold => "safe-hold",
        Reaction::DisableMotors => "motors-disabled",
    }
}

/// Runs the steps; exit status 0 when every step asked for landed within
/// 5 cm of its planned length from the foot before it and nothing faulted, 1 otherwise, 2 when the
/// run could not be set up, the table is refused or the options are
/// unusable.
pub fn run(args: &SimulateArgs) -> u8 {
    if let Some(Err(e)) = args.plot.as_deref().map(crate::plot_path::check) {
        eprintln!("exogait simulate: {e}");
        return 2;
    }
    if let Some(t) = args.seconds {
        if !(t.is_finite() && t > 0.0 && t <= MAX_SECONDS) {
            eprintln!("exogait simulate: --seconds must be in (0, {MAX_SECONDS}]");
            return 2;
        }
    }
    if args.steps == 0 || args.steps > 20 {
        eprintln!("exogait simulate: --steps must be in 1..=20");
        return 2;
    }
    if let Err(e) = args.conditions.check() {
        eprintln!("exogait simulate: {e}");
        return 2;
    }

    let (bundle_file, device) =
        match crate::bundle_file::BundleFile::and_device(args.bundle.as_deref()) {
            Ok(loaded) => loaded,
            Err(e) => {
                eprintln!("exogait simulate: {e}");
                return 2;
            }
        };
    let bundle = bundle_file.as_ref().and_then(|f| f.bundle().ok());
    let bundle_table = match (&bundle, &bundle_file) {
        (Some(b), Some(f)) => match b.find(&args.gait) {
            Some((_, g)) => Some(g.table),
            None => {
                eprintln!(
                    "exogait simulate: the bundle holds no gait {:?} (it holds {})",
                    args.gait,
                    f.names().join(", ")
                );
                return 2;
            }
        },
        _ => None,
    };
    let named = if bundle_table.is_some() {
        None
    } else {
        match <SimGait as ValueEnum>::from_str(&args.gait, false) {
            Ok(g) => Some(g),
            Err(_) => {
                eprintln!(
                    "exogait simulate: --gait {:?}: without --bundle, one of walk, stair-up, stair-down",
                    args.gait
                );
                return 2;
            }
        }
    };
    let image = match &args.table {
        Some(path) => match crate::table::load_playable(path, &device) {
            Ok(i) => Some(i),
            Err(e) => {
                eprintln!("exogait simulate: {}", e.message);
                return 2;
            }
        },
        None => None,
    };
    let file_table = image
        .as_deref()
        .and_then(|i| gait_core::tables::GaitTable::parse(i).ok())
        .or(bundle_table);
    let kind = file_table.map_or(
        named.map_or(gait_core::tables::GaitKind::Walk, SimGait::kind),
        |t| t.kind(),
    );
    let gait = sim::compare::gait_of(kind);
    let label = match gait {
        Gait::Walk => "walking",
        Gait::StairUp => "climbing stairs",
        Gait::StairDown => "descending stairs",
    };
    let source = match (&args.table, &args.bundle) {
        (Some(p), _) => p.display().to_string(),
        (None, Some(p)) => format!("{} gait {}", p.display(), args.gait),
        (None, None) => "the flash table".to_string(),
    };
    let tables = match file_table {
        Some(t) => sim::compare::tables_of(t),
        None => sim::scenario::flash_tables(),
    };
    let step_s = file_table.map_or(2.3, |t| f64::from(t.duration_s()));
    let seconds = args
        .seconds
        .unwrap_or_else(|| (4.0 + args.steps as f64 * (step_s + 3.0)).min(MAX_SECONDS));
    if let Some(f) = args.inject.iter().find(|f| f.at_s >= seconds) {
        eprintln!(
            "exogait simulate: --inject {f}: at {} s it would strike after the run's {seconds} s (--seconds)",
            f.at_s
        );
        return 2;
    }
    let injections = args.inject.clone();
    let conditions = args.conditions;
    let slot = gait_control::replan::ReplanSlot::new();
    let mut setup = Ok(());
    let run = match sim::scenario::run_tables_with(
        &device,
        tables,
        gait,
        conditions.pilot(sim::scenario::strong_pilot()),
        seconds,
        args.steps,
        |rig| {
            setup = conditions.prepare(rig, &slot);
            for f in injections {
                rig.schedule(f);
            }
        },
    ) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("exogait simulate: {e}");
            return 2;
        }
    };
    if let Err(e) = setup {
        eprintln!("exogait simulate: {e}");
        return 2;
    }
    let step = run.summary.planned_landing_x_m;
    // Each step is judged from where its stance foot stood (the previous
    // landing): a step lands within 5 cm of its planned length.
    let landed_x: Vec<f64> = run.summary.landing_points.iter().map(|(_, x)| *x).collect();
    // The first from the stance foot the run started on (0 unless placed
    // off: `--stance-foot-off`).
    let start_x = run
        .rig
        .trace
        .first()
        .map_or(0.0, |s| s.state.points_m[0][0]);
    let from = |i: usize| {
        i.checked_sub(1)
            .and_then(|j| landed_x.get(j))
            .copied()
            .unwrap_or(start_x)
    };
    let on_plan = landed_x.len() >= args.steps
        && landed_x
            .iter()
            .take(args.steps)
            .enumerate()
            .all(|(i, x)| (x - from(i) - step).abs() < 0.05);
    if args.json {
        let o = sim::outcome::outcome(&run.rig, run.ended_by.as_ref());
        let answer = SimulateJson {
            gait: gait_opt::clinical_report::gait_name(kind),
            steps_asked: args.steps,
            landings: o.landings,
            landed_on_plan: on_plan,
            injected: run
                .rig
                .injected()
                .iter()
                .map(|(f, t)| InjectedJson {
                    fault: f.to_string(),
                    at_s: *t,
                })
                .collect(),
            tracking_rms_rad: o.tracking_rms_rad,
            tracking_peak_rad: o.tracking_peak_rad,
            worst_limit_margin_rad: o.worst_limit_margin_rad,
            worst_limit_joint: JOINT_NAMES.get(o.worst_limit_joint).copied().unwrap_or("?"),
            fell: o.fell.is_some(),
            fell_reason: o.fell.clone(),
            faults: o
                .faults
                .iter()
                .map(|f| FaultJson {
                    code: format!("0x{:04x}", f.code.code()),
                    name: f.code.name(),
                    injected_s: f.injected_s,
                    detected_s: f.detected_s,
                    latency_ticks: f.latency_ticks,
                    reaction: reaction_name(f.reaction),
                    channel: f.channel,
                    safe_state_s: f.safe_state_s,
                })
                .collect(),
            ended_by: run.ended_by.as_ref().map(ToString::to_string),
            step_error_m: landed_x
                .iter()
                .enumerate()
                .map(|(i, x)| x - from(i) - step)
                .collect(),
            waited_s: sim::summary::waited_before_swings(&run.rig.trace, f64::from(device.dt_s)),
            replans: run
                .rig
                .replans()
                .iter()
                .map(|r| ReplanJson {
                    asked_s: r.asked_at as f64 * f64::from(device.dt_s),
                    answer: match r.answer.outcome {
                        _ if r.ready_at == u64::MAX => "late",
                        gait_control::replan::ReplanOutcome::Replanned => "replanned",
                        _ => "table",
                    },
                    evals: r.answer.evals,
                    instructions: r.answer.instructions(),
                })
                .collect(),
            conditions,
        };
        match serde_json::to_string_pretty(&answer) {
            Ok(text) => outln!("{text}"),
            Err(e) => {
                eprintln!("exogait simulate: JSON: {e}");
                return 2;
            }
        }
    } else {
        outln!(
            "exogait closed loop: {label}, {} step(s), {source}",
            args.steps
        );
        for (f, t) in run.rig.injected() {
            outln!("injected               {f} (at {t:.3} s)");
        }
        outln!("{}", run.summary);
        if let Some(e) = &run.ended_by {
            outln!("simulation stopped     {e}");
        }
    }
    if let Some(path) = &args.plot {
        match sim::plot::plot_run(&run.rig.trace, &run.summary, path) {
            Ok(()) if args.json => eprintln!("plot: {}", path.display()),
            Ok(()) => outln!("plot                     {}", path.display()),
            Err(e) => {
                eprintln!("exogait simulate: {}: {e}", path.display());
                return 2;
            }
        }
    }
    if on_plan && run.summary.faults.is_empty() && run.ended_by.is_none() {
        return 0;
    }
    // Say why the run is not a success, on stderr whatever the format.
    let landed = landed_x.len().min(args.steps);
    if !run.summary.faults.is_empty() {
        eprintln!(
            "exogait simulate: the controller latched {}",
            run.summary.faults.join(", ")
        );
    }
    if landed < args.steps {
        eprintln!(
            "exogait simulate: {landed} of {} steps landed within {seconds} s{}",
            args.steps,
            run.ended_by
                .as_ref()
                .map(|e| format!(" ({e})"))
                .unwrap_or_default()
        );
    } else if !on_plan {
        eprintln!("exogait simulate: a step landed more than 5 cm from its planned length");
    }
    1
}
