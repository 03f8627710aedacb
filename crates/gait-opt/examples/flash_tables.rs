//! Writes the generated gait-table module the firmware links into flash:
//! `cargo run --release -p gait-opt --example flash_tables -- PATH`
//! (normally through `cargo xtask tables`). The stair-ascent table's
//! closed-loop refinement takes minutes; its progress goes to stderr.
//! `-- PATH --replay`: instead of searching, recompute the refinement
//! recorded in the file at PATH (what the CI test does; seconds), e.g. after
//! a change to the provenance's wording.

use std::process::ExitCode;
use std::time::Instant;

use gait_opt::tables::{RefineRecord, RefineSource};

fn main() -> ExitCode {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: flash_tables OUT.rs");
        return ExitCode::from(2);
    };
    let source = if std::env::args().nth(2).as_deref() == Some("--replay") {
        let record = std::fs::read_to_string(&path)
            .ok()
            .and_then(|s| RefineRecord::from_flash_module(&s, "STAIR_UP"));
        let Some(record) = record else {
            eprintln!("flash_tables: no refinement recorded in {path}");
            return ExitCode::FAILURE;
        };
        RefineSource::Recorded(Box::new(record))
    } else {
        RefineSource::Search
    };
    let t0 = Instant::now();
    let mut progress = |evals: usize, best: f64| {
        eprintln!(
            "{:7.1} s  closed-loop refinement: {evals:5} evaluations, best {best:.2} N·s",
            t0.elapsed().as_secs_f64()
        );
    };
    let src = gait_opt::tables::flash_module_source_with(&source, &mut progress);
    eprintln!("generated in {:.1} s", t0.elapsed().as_secs_f64());
    match src {
        Ok(src) => match std::fs::write(&path, src) {
            Ok(()) => {
                println!("wrote {path}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("flash_tables: cannot write {path}: {e}");
                ExitCode::FAILURE
            }
        },
        Err(e) => {
            eprintln!("flash_tables: {e}");
            ExitCode::FAILURE
        }
    }
}
