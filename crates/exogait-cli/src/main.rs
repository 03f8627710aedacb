//! `exogait`: the project's command-line tool.
//!
//! Thin by design: it parses JSON lines, calls gait-core and prints JSON
//! lines; `optimize` and `cost` call gait-opt. No algorithm lives here. See
//! `crates/exogait-cli/README.md`.

// First: its macros serve the modules below.
#[macro_use]
mod out;

mod bundle_cmd;
mod bundle_file;
mod commands;
mod compare;
mod conditions;
mod cost;
mod family;
mod faults;
mod fit;
mod jsonl;
mod model_file;
mod optimize;
mod patient_file;
mod plot_path;
mod simulate;
mod table;

use std::io;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use gait_core::BodyModel;

/// Exit status when every input line was answered.
const EXIT_OK: u8 = 0;
/// Exit status when at least one line was answered with an error.
const EXIT_LINE_FAILED: u8 = 1;
/// Exit status for a bad `--model` file or an I/O failure.
const EXIT_FATAL: u8 = 2;
// `optimize`: 0 report written, 1 the search failed, 2 bad arguments,
// model or I/O. `cost`: 0 J agrees with the file's, 1 it does not, 2 bad
// file. clap's own usage errors also exit with 2.

/// Exoskeleton gait model tools: JSON lines in on stdin, JSON lines out on
/// stdout, one answer per input line, SI units (m, kg, s, rad, N·m).
#[derive(Debug, Parser)]
#[command(name = "exogait", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The body model of the model commands (`fk`, `ik`, `dynamics`,
/// `optimize`); the others take theirs from the device, a patient file or
/// a bundle.
#[derive(Debug, clap::Args)]
struct ModelArgs {
    /// Body model JSON: `{"links":[…×5],"limits":{…}}` or
    /// `{"pilot":{"height_m":…,"mass_kg":…}}` (default: the paper's Table III).
    #[arg(long, value_name = "FILE.json")]
    model: Option<PathBuf>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Inverse dynamics: {"phi":[5],"dphi":[5],"ddphi":[5]} → {"t_phi":[5],"t_theta":[5]}.
    Dynamics(ModelArgs),
    /// Forward kinematics: {"phi":[5]} → {"p":[[x,y]×5]} (stance ankle at the origin).
    Fk(ModelArgs),
    /// Inverse kinematics: {"x5","y5","phi1","phi3","r2"} → {"phi":[5],"theta":[5]}.
    Ik(ModelArgs),
    /// Optimises a swing step (paper mode or a geometry of one's own) and
    /// writes the JSON report (and a plot). stair-down has no paper mode: it
    /// defaults to the paper's stair (rise 0.0935 m, tread 0.275 m, 2.28 s).
    Optimize {
        #[command(flatten)]
        args: optimize::OptimizeArgs,
        #[command(flatten)]
        model: ModelArgs,
    },
    /// Recomputes J from a report file and compares it with the stored J
    /// (exit 1 if they differ by more than 1e-9 relative, 2 for a bad file).
    Cost {
        /// The report (from `exogait optimize`).
        #[arg(value_name = "FILE.json")]
        file: PathBuf,
    },
    /// Closed loop: the real controller on the simulated exoskeleton and
    /// pilot, with a built-in gait, a table file or a bundle's gait; prints
    /// the metrics (exit 0 when every step asked for landed within 5 cm of
    /// its planned length with no fault, 1 otherwise, saying why; 2 for
    /// unusable options or a refused table or bundle).
    Simulate(simulate::SimulateArgs),
    /// A gait against the human-data gait at its geometry, same device and
    /// pilot, in the closed loop (the paper's Table II; exit 0 when both
    /// land every step without a fault, 1 otherwise, 2 for unusable
    /// options or a refused bundle).
    Compare(compare::CompareArgs),
    /// An `optimize` report as a gait table in the flash format (checked
    /// against the device first).
    Table(table::TableArgs),
    /// A patient's body model from height and mass (and measured thigh,
    /// shank, foot): writes the patient file and prints it (exit 2 for
    /// measures the device cannot be fitted to).
    Fit(fit::FitArgs),
    /// A patient's gait family (walking paces, stairs up and down) as a
    /// verified bundle: each gait searched, admitted and played in the
    /// closed loop; the ones the device cannot play are left out with the
    /// reason (exit 1 if none is cleared, 2 for unusable input).
    Tables(family::TablesArgs),
    /// Lists a bundle after verifying it for this device (exit 2 for a
    /// corrupt, truncated or foreign bundle).
    Bundle(bundle_cmd::BundleArgs),
    /// A seeded randomised fault campaign in the closed loop: one random
    /// fault per run; the tally per kind, then healthy runs of each gait
    /// (exit 0 when no fall and no stop crossed is the device's — each one
    /// a named case with its physical reason — no detection is missed, no
    /// healthy run trips; 1 otherwise; 2 for unusable options).
    Faults(faults::FaultsArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match &cli.command {
        Command::Fit(args) => ExitCode::from(fit::run(args)),
        Command::Tables(args) => ExitCode::from(family::run(args)),
        Command::Bundle(args) => ExitCode::from(bundle_cmd::run(args)),
        Command::Simulate(args) => ExitCode::from(simulate::run(args)),
        Command::Faults(args) => ExitCode::from(faults::run(args)),
        Command::Table(args) => ExitCode::from(table::run(args)),
        Command::Compare(args) => ExitCode::from(compare::run(args)),
        Command::Cost { file } => run_cost(file),
        Command::Optimize { args, model } => {
            let given = match load_model(model) {
                Ok(m) => model.model.is_some().then_some(m),
                Err(code) => return code,
            };
            match optimize::run(args, given) {
                Ok(()) => ExitCode::from(EXIT_OK),
                Err(optimize::Failure::Search(e)) => {
                    eprintln!("exogait: {e}");
                    ExitCode::from(EXIT_LINE_FAILED)
                }
                Err(optimize::Failure::Usage(e)) => {
                    eprintln!("exogait: {e}");
                    ExitCode::from(EXIT_FATAL)
                }
            }
        }
        Command::Dynamics(m) | Command::Fk(m) | Command::Ik(m) => {
            let model = match load_model(m) {
                Ok(model) => model,
                Err(code) => return code,
            };
            run_lines(&cli.command, &model)
        }
    }
}

/// The model `--model` names, or Table III; a bad file exits 2.
fn load_model(m: &ModelArgs) -> Result<BodyModel<f64>, ExitCode> {
    match &m.model {
        None => Ok(BodyModel::<f64>::paper_table_iii()),
        Some(path) => model_file::load(path).map_err(|e| {
            eprintln!("exogait: {e}");
            ExitCode::from(EXIT_FATAL)
        }),
    }
}

/// `cost`: 0 when the recomputed J agrees, 1 when not, 2 for a bad file.
fn run_cost(file: &std::path::Path) -> ExitCode {
    match cost::run(file) {
        Ok(answer) => {
            match serde_json::to_string(&answer) {
                Ok(text) => outln!("{text}"),
                Err(e) => {
                    eprintln!("exogait: {e}");
                    return ExitCode::from(EXIT_FATAL);
                }
            }
            if answer.agrees() {
                ExitCode::from(EXIT_OK)
            } else {
                eprintln!(
                    "exogait: {}: recomputed J differs from the stored J by more than {} (relative)",
                    file.display(),
                    cost::TOLERANCE
                );
                ExitCode::from(EXIT_LINE_FAILED)
            }
        }
        Err(e) => {
            eprintln!("exogait: {e}");
            ExitCode::from(EXIT_FATAL)
        }
    }
}

/// `fk`, `ik`, `dynamics`: JSON lines in and out on `model`.
fn run_lines(command: &Command, model: &BodyModel<f64>) -> ExitCode {
    let stdin = io::stdin().lock();
    let stdout = io::stdout().lock();
    let result = match command {
        Command::Dynamics(_) => jsonl::run(stdin, stdout, |r| commands::dynamics(model, r)),
        Command::Fk(_) => jsonl::run(stdin, stdout, |r| commands::fk(model, r)),
        _ => {
            let solver = gait_core::ik::IkSolver::new(model);
            jsonl::run(stdin, stdout, |r| commands::ik(&solver, r))
        }
    };
    match result {
        Ok(summary) if summary.failed == 0 => ExitCode::from(EXIT_OK),
        Ok(summary) => {
            eprintln!(
                "exogait: {} of {} lines failed",
                summary.failed, summary.answered
            );
            ExitCode::from(EXIT_LINE_FAILED)
        }
        // A closed output is the reader's choice (`out`): no message. The
        // lines not answered are not answered, so not 0.
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => ExitCode::from(EXIT_FATAL),
        Err(e) => {
            eprintln!("exogait: I/O error: {e}");
            ExitCode::from(EXIT_FATAL)
        }
    }
}
