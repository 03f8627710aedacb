//! `exogait faults`: the seeded randomised fault campaign (`sim::campaign`)
//! — many closed-loop runs, each with sensor noise and one random fault —
//! with a progress bar on a terminal, and its tally per kind: falls, joints
//! past a stop (each with how many no named case explains), missed
//! detections, false trips; then healthy runs of each gait with the same
//! noise and no fault, and theirs. Exit 0 only when both meet their goal
//! (none of them; for the fault runs, no unnamed fall or stop), 1
//! otherwise, 2 for unusable options. With `--bundle`, all of it on the
//! device fitted to a patient, over every gait of the patient's family.

use std::io::IsTerminal;
use std::path::PathBuf;

use crate::simulate::JOINT_NAMES;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use sim::campaign::{
    CampaignGaits, HEALTHY_STEPS, HealthyTally, NamedCase, Tally, healthy_plan_over, healthy_tally,
    plan_over, play_all_healthy_on, play_all_on, tally, tally_by_gait,
};
use sim::scenario::strong_pilot;

/// Options of `exogait faults`.
#[derive(Debug, Args)]
pub struct FaultsArgs {
    /// Fault runs (0 … 100,000; not 0 with `--healthy 0`).
    #[arg(long, default_value_t = 300)]
    pub runs: usize,
    /// The campaign's seed (the same seed gives the same runs).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Healthy runs of each gait beside the fault runs (0 … 10,000):
    /// sensor noise, no fault, three steps; anything latched is a false
    /// trip.
    #[arg(long, default_value_t = 100)]
    pub healthy: usize,
    /// A patient's bundle (`exogait tables`): the campaign and the healthy
    /// runs on the device fitted to its patient, over every gait of the
    /// bundle (each drawn as often as the others) instead of the device's
    /// own three.
    #[arg(long, value_name = "FILE.bundle")]
    pub bundle: Option<PathBuf>,
    /// Print the tally as JSON, with every run that fell, crossed a stop,
    /// missed a detection or tripped falsely.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Serialize)]
struct TallyJson {
    runs: usize,
    falls: usize,
    unnamed_falls: usize,
    past_a_stop: usize,
    unnamed_past_a_stop: usize,
    missed: usize,
    false_trips: usize,
    errors: usize,
}

impl From<&Tally> for TallyJson {
    fn from(t: &Tally) -> Self {
        Self {
            runs: t.runs,
            falls: t.falls,
            unnamed_falls: t.unnamed_falls,
            past_a_stop: t.past_a_stop,
            unnamed_past_a_stop: t.unnamed_past_a_stop,
            missed: t.missed,
            false_trips: t.false_trips,
            errors: t.errors,
        }
    }
}

#[derive(Debug, Serialize)]
struct BadRunJson {
    gait: String,
    fault: String,
    noise_seed: u64,
    fell: Option<String>,
    /// The case docs/campaign.md names the fall with (`None`: the device's).
    named_case: Option<&'static str>,
    worst_limit_margin_rad: f64,
    /// The joint of the smallest margin, and which of its stops.
    worst_limit_joint: &'static str,
    worst_limit_stop: &'static str,
    /// The case whose reason took every joint that crossed a stop past it
    /// (`None`: none crossed, or the device's).
    named_stop: Option<&'static str>,
    /// The joints the controller braked at some tick, in joint order (not
    /// one 0x0404 only held in place; the e-stop's motors disabled are not
    /// listed): for a hip or knee fault, more than its joint is the
    /// residual's cascade (`docs/safety.md`, "The torque residual").
    braked_joints: Vec<&'static str>,
    missed: bool,
    false_trip: bool,
    error: Option<String>,
}

#[derive(Debug, Serialize)]
struct CampaignJson {
    seed: u64,
    /// The bundle campaigned (`None`: the device's own gaits).
    bundle: Option<String>,
    all: TallyJson,
    by_kind: Vec<(String, TallyJson)>,
    /// The fault runs per gait.
    by_gait: Vec<(String, TallyJson)>,
    bad_runs: Vec<BadRunJson>,
    healthy: HealthyJson,
}

/// A healthy run's tally in JSON.
#[derive(Debug, Serialize)]
struct HealthyTallyJson {
    runs: usize,
    falls: usize,
    past_a_stop: usize,
    false_trips: usize,
    short: usize,
    errors: usize,
}

impl From<&HealthyTally> for HealthyTallyJson {
    fn from(t: &HealthyTally) -> Self {
        Self {
            runs: t.runs,
            falls: t.falls,
            past_a_stop: t.past_a_stop,
            false_trips: t.false_trips,
            short: t.short,
            errors: t.errors,
        }
    }
}

#[derive(Debug, Serialize)]
struct BadHealthyRunJson {
    gait: String,
    noise_seed: u64,
    landings: usize,
    fell: Option<String>,
    worst_limit_margin_rad: f64,
    faults: Vec<String>,
    error: Option<String>,
}

#[derive(Debug, Serialize)]
struct HealthyJson {
    all: HealthyTallyJson,
    by_gait: Vec<(String, HealthyTallyJson)>,
    bad_runs: Vec<BadHealthyRunJson>,
}

/// A progress bar over `n` runs on a terminal, hidden otherwise.
fn progress(n: usize) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(n as u64);
    if let Ok(style) = ProgressStyle::with_template(
        "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} runs, eta {eta}",
    ) {
        bar.set_style(style);
    }
    bar
}

/// Runs the campaign and the healthy runs on the machine's cores.
pub fn run(args: &FaultsArgs) -> u8 {
    if args.runs > 100_000 || args.healthy > 10_000 || args.runs + args.healthy == 0 {
        eprintln!(
            "exogait faults: --runs must be in 0..=100000 and --healthy in 0..=10000, not both 0"
        );
        return 2;
    }
    let (bundle_file, device) =
        match crate::bundle_file::BundleFile::and_device(args.bundle.as_deref()) {
            Ok(loaded) => loaded,
            Err(e) => {
                eprintln!("exogait faults: {e}");
                return 2;
            }
        };
    let bundle = match bundle_file
        .as_ref()
        .map(crate::bundle_file::BundleFile::bundle)
    {
        Some(Err(e)) => {
            eprintln!("exogait faults: {e}");
            return 2;
        }
        Some(Ok(b)) => Some(b),
        None => None,
    };
    let gaits = match &bundle {
        Some(b) => CampaignGaits::of_bundle(b),
        None => CampaignGaits::built_in(),
    };
    if gaits.is_empty() {
        eprintln!("exogait faults: the bundle holds no gait");
        return 2;
    }
    let runs = plan_over(args.seed, args.runs, &gaits);
    let healthy_runs = healthy_plan_over(args.seed, args.healthy, &gaits);
    let started = std::time::Instant::now();
    let total = runs.len() + healthy_runs.len();
    let bar = progress(total);
    // Piped, a line at every tenth of the runs instead of the bar.
    let piped = bar.is_hidden();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let tick = || {
        bar.inc(1);
        let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if piped && (n * 10 / total.max(1)) != ((n - 1) * 10 / total.max(1)) {
            eprintln!(
                "exogait faults: {n}/{total} runs, {:.0} s",
                started.elapsed().as_secs_f64()
            );
        }
    };
    let results = play_all_on(&runs, &device, strong_pilot(), &gaits, &tick);
    let healthy = play_all_healthy_on(&healthy_runs, &device, &gaits, &tick);
    bar.finish_and_clear();
    eprintln!(
        "exogait faults: {total} runs in {:.1} s",
        started.elapsed().as_secs_f64()
    );
    if results.len() != runs.len() || healthy.len() != healthy_runs.len() {
        eprintln!(
            "exogait faults: only {} of {} runs finished",
            results.len() + healthy.len(),
            runs.len() + healthy_runs.len()
        );
        return 2;
    }
    let (by_kind, all) = tally(&results);
    let faults_by_gait = tally_by_gait(&results, gaits.len());
    let (by_gait, all_healthy) = healthy_tally(&healthy);
    if args.json {
        let answer = CampaignJson {
            seed: args.seed,
            bundle: args.bundle.as_ref().map(|p| p.display().to_string()),
            all: TallyJson::from(&all),
            by_kind: by_kind
                .iter()
                .map(|(k, t)| ((*k).to_string(), TallyJson::from(t)))
                .collect(),
            by_gait: faults_by_gait
                .iter()
                .map(|(g, t)| (gaits.name(*g).to_string(), TallyJson::from(t)))
                .collect(),
            bad_runs: results
                .iter()
                .filter(|r| {
                    r.outcome.fell.is_some()
                        || r.outcome.worst_limit_margin_rad < 0.0
                        || r.missed()
                        || r.false_trip
                        || r.error.is_some()
                })
                .map(|r| BadRunJson {
                    gait: gaits.name(r.run.slot).to_string(),
                    fault: r.run.fault.to_string(),
                    noise_seed: r.run.noise_seed,
                    fell: r.outcome.fell.clone(),
                    named_case: r.named_fall().map(NamedCase::name),
                    worst_limit_margin_rad: r.outcome.worst_limit_margin_rad,
                    worst_limit_joint: JOINT_NAMES
                        .get(r.outcome.worst_limit_joint)
                        .copied()
                        .unwrap_or("?"),
                    worst_limit_stop: match r.outcome.limit_margins.get(r.outcome.worst_limit_joint)
                    {
                        Some((_, true)) => "flexion",
                        _ => "extension",
                    },
                    named_stop: r.named_stop().map(NamedCase::name),
                    braked_joints: JOINT_NAMES
                        .iter()
                        .zip(r.outcome.braked_joints)
                        .filter_map(|(&name, braked)| braked.then_some(name))
                        .collect(),
                    missed: r.missed(),
                    false_trip: r.false_trip,
                    error: r.error.clone(),
                })
                .collect(),
            healthy: HealthyJson {
                all: HealthyTallyJson::from(&all_healthy),
                by_gait: by_gait
                    .iter()
                    .map(|(g, t)| (gaits.name(*g).to_string(), HealthyTallyJson::from(t)))
                    .collect(),
                bad_runs: healthy
                    .iter()
                    .filter(|r| r.bad())
                    .map(|r| BadHealthyRunJson {
                        gait: gaits.name(r.run.slot).to_string(),
                        noise_seed: r.run.noise_seed,
                        landings: r.outcome.landings,
                        fell: r.outcome.fell.clone(),
                        worst_limit_margin_rad: r.outcome.worst_limit_margin_rad,
                        faults: r
                            .outcome
                            .faults
                            .iter()
                            .map(|f| format!("0x{:04x}", f.code.code()))
                            .collect(),
                        error: r.error.clone(),
                    })
                    .collect(),
            },
        };
        match serde_json::to_string_pretty(&answer) {
            Ok(t) => outln!("{t}"),
            Err(e) => {
                eprintln!("exogait faults: JSON: {e}");
                return 2;
            }
        }
    } else {
        if let Some(path) = &args.bundle {
            outln!(
                "exogait faults: {} on its fitted device: {} gaits ({})",
                path.display(),
                gaits.len(),
                gaits
                    .iter()
                    .map(|g| g.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        if !runs.is_empty() {
            outln!(
                "exogait faults: {} runs, seed {}, one random fault each, sensor noise ±3/±10 counts",
                all.runs,
                args.seed
            );
            outln!(
                "{:<24} {:>5} {:>6} {:>8} {:>11} {:>8} {:>7} {:>12} {:>7}",
                "kind",
                "runs",
                "falls",
                "unnamed",
                "past a stop",
                "unnamed",
                "missed",
                "false trips",
                "errors"
            );
            let row = |name: &str, t: &Tally| {
                outln!(
                    "{:<24} {:>5} {:>6} {:>8} {:>11} {:>8} {:>7} {:>12} {:>7}",
                    name,
                    t.runs,
                    t.falls,
                    t.unnamed_falls,
                    t.past_a_stop,
                    t.unnamed_past_a_stop,
                    t.missed,
                    t.false_trips,
                    t.errors
                );
            };
            for (k, t) in &by_kind {
                row(k, t);
            }
            row("all", &all);
            outln!("the same runs per gait:");
            for (g, t) in &faults_by_gait {
                row(gaits.name(*g), t);
            }
        }
        if !healthy_runs.is_empty() {
            outln!(
                "healthy runs: {} per gait, {} steps, no fault, sensor noise ±3/±10 counts",
                args.healthy,
                HEALTHY_STEPS
            );
            outln!(
                "{:<24} {:>5} {:>6} {:>11} {:>12} {:>6} {:>7}",
                "gait",
                "runs",
                "falls",
                "past a stop",
                "false trips",
                "short",
                "errors"
            );
            let row = |name: &str, t: &HealthyTally| {
                outln!(
                    "{:<24} {:>5} {:>6} {:>11} {:>12} {:>6} {:>7}",
                    name,
                    t.runs,
                    t.falls,
                    t.past_a_stop,
                    t.false_trips,
                    t.short,
                    t.errors
                );
            };
            for (g, t) in &by_gait {
                row(gaits.name(*g), t);
            }
            row("all", &all_healthy);
            for r in healthy.iter().filter(|r| r.bad()) {
                let codes: Vec<String> = r
                    .outcome
                    .faults
                    .iter()
                    .map(|f| format!("0x{:04x} at {:.3} s", f.code.code(), f.detected_s))
                    .collect();
                outln!(
                    "  {} noise seed {}: {} landings, faults [{}]{}",
                    gaits.name(r.run.slot),
                    r.run.noise_seed,
                    r.outcome.landings,
                    codes.join(", "),
                    r.outcome
                        .fell
                        .as_ref()
                        .map_or(String::new(), |f| format!(", fell: {f}"))
                );
            }
        }
    }
    // No fall and no stop crossed but for the cases docs/campaign.md
    // names with their physical reason.
    let goal = all.unnamed_falls == 0
        && all.unnamed_past_a_stop == 0
        && all.missed == 0
        && all.false_trips == 0
        && all.errors == 0;
    let healthy_goal = all_healthy.falls == 0
        && all_healthy.past_a_stop == 0
        && all_healthy.false_trips == 0
        && all_healthy.short == 0
        && all_healthy.errors == 0;
    u8::from(!(goal && healthy_goal))
}
