//! `exogait`: the project's command-line tool.
//!
//! Thin by design: it parses JSON lines, calls gait-core and prints JSON
//! lines. No algorithm lives here. See `crates/exogait-cli/README.md`.

mod commands;
mod jsonl;
mod model_file;

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

/// Exoskeleton gait model tools: JSON lines in on stdin, JSON lines out on
/// stdout, one answer per input line, SI units (m, kg, s, rad, N·m).
#[derive(Debug, Parser)]
#[command(name = "exogait", version, about, long_about = None)]
struct Cli {
    /// Body model JSON: `{"links":[…×5],"limits":{…}}` or
    /// `{"pilot":{"height_m":…,"mass_kg":…}}` (default: the paper's Table III).
    #[arg(long, global = true, value_name = "FILE.json")]
    model: Option<PathBuf>,

    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Inverse dynamics: {"phi":[5],"dphi":[5],"ddphi":[5]} → {"t_phi":[5],"t_theta":[5]}.
    Dynamics,
    /// Forward kinematics: {"phi":[5]} → {"p":[[x,y]×5]} (stance ankle at the origin).
    Fk,
    /// Inverse kinematics: {"x5","y5","phi1","phi3","r2"} → {"phi":[5],"theta":[5]}.
    Ik,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let model = match &cli.model {
        None => BodyModel::<f64>::paper_table_iii(),
        Some(path) => match model_file::load(path) {
            Ok(m) => m,
            Err(e) => {
                eprintln!("exogait: {e}");
                return ExitCode::from(EXIT_FATAL);
            }
        },
    };
    let stdin = io::stdin().lock();
    let stdout = io::stdout().lock();
    let result = match cli.command {
        Command::Dynamics => jsonl::run(stdin, stdout, |r| commands::dynamics(&model, r)),
        Command::Fk => jsonl::run(stdin, stdout, |r| commands::fk(&model, r)),
        Command::Ik => {
            let solver = gait_core::ik::IkSolver::new(&model);
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
        Err(e) => {
            eprintln!("exogait: I/O error: {e}");
            ExitCode::from(EXIT_FATAL)
        }
    }
}
