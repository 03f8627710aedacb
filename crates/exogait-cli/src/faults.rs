//! `exogait faults`: the seeded randomised fault campaign (`sim::campaign`)
//! — many closed-loop runs, each with sensor noise and one random fault —
//! with a progress bar on a terminal, and its tally per kind: falls, joints
//! past a stop, missed detections, false trips. Exit 0 only when the
//! campaign meets its goal (none of them), 1 otherwise, 2 for unusable
//! options.

use std::io::IsTerminal;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use sim::campaign::{Tally, plan, play_all, tally};

/// Options of `exogait faults`.
#[derive(Debug, Args)]
pub struct FaultsArgs {
    /// Runs (1 … 100,000).
    #[arg(long, default_value_t = 300)]
    pub runs: usize,
    /// The campaign's seed (the same seed gives the same runs).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print the tally as JSON, with every run that fell, crossed a stop,
    /// missed a detection or tripped falsely.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Serialize)]
struct TallyJson {
    runs: usize,
    falls: usize,
    past_a_stop: usize,
    missed: usize,
    false_trips: usize,
    errors: usize,
}

impl From<&Tally> for TallyJson {
    fn from(t: &Tally) -> Self {
        Self {
            runs: t.runs,
            falls: t.falls,
            past_a_stop: t.past_a_stop,
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
    fell: Option<String>,
    worst_limit_margin_rad: f64,
    missed: bool,
    false_trip: bool,
    error: Option<String>,
}

#[derive(Debug, Serialize)]
struct CampaignJson {
    seed: u64,
    all: TallyJson,
    by_kind: Vec<(String, TallyJson)>,
    bad_runs: Vec<BadRunJson>,
}

/// Runs the campaign on two threads (this machine's cores).
pub fn run(args: &FaultsArgs) -> u8 {
    if args.runs == 0 || args.runs > 100_000 {
        eprintln!("exogait faults: --runs must be in 1..=100000");
        return 2;
    }
    let device = match exogait_device::DeviceConfig::exogait() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("exogait faults: device configuration: {e:?}");
            return 2;
        }
    };
    let runs = plan(args.seed, args.runs);
    let bar = if std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(runs.len() as u64);
        if let Ok(style) = ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} runs, eta {eta}",
        ) {
            bar.set_style(style);
        }
        bar
    } else {
        ProgressBar::hidden()
    };
    let results = play_all(&runs, &device, &|| bar.inc(1));
    bar.finish_and_clear();
    if results.len() != runs.len() {
        eprintln!(
            "exogait faults: only {} of {} runs finished",
            results.len(),
            runs.len()
        );
        return 2;
    }
    let (by_kind, all) = tally(&results);
    if args.json {
        let answer = CampaignJson {
            seed: args.seed,
            all: TallyJson::from(&all),
            by_kind: by_kind
                .iter()
                .map(|(k, t)| ((*k).to_string(), TallyJson::from(t)))
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
                    gait: format!("{:?}", r.run.gait),
                    fault: r.run.fault.to_string(),
                    fell: r.outcome.fell.clone(),
                    worst_limit_margin_rad: r.outcome.worst_limit_margin_rad,
                    missed: r.missed(),
                    false_trip: r.false_trip,
                    error: r.error.clone(),
                })
                .collect(),
        };
        match serde_json::to_string_pretty(&answer) {
            Ok(t) => println!("{t}"),
            Err(e) => {
                eprintln!("exogait faults: JSON: {e}");
                return 2;
            }
        }
    } else {
        println!(
            "exogait faults: {} runs, seed {}, one random fault each, sensor noise ±3/±10 counts",
            all.runs, args.seed
        );
        println!(
            "{:<24} {:>5} {:>6} {:>11} {:>7} {:>12} {:>7}",
            "kind", "runs", "falls", "past a stop", "missed", "false trips", "errors"
        );
        let row = |name: &str, t: &Tally| {
            println!(
                "{:<24} {:>5} {:>6} {:>11} {:>7} {:>12} {:>7}",
                name, t.runs, t.falls, t.past_a_stop, t.missed, t.false_trips, t.errors
            );
        };
        for (k, t) in &by_kind {
            row(k, t);
        }
        row("all", &all);
    }
    let goal = all.falls == 0
        && all.past_a_stop == 0
        && all.missed == 0
        && all.false_trips == 0
        && all.errors == 0;
    u8::from(!goal)
}
