//! The control tick on the target, phase by phase: records the controller's
//! inputs in the simulator (`sim::replay`, walks, stair ascent and descent,
//! a fault and its safe hold), builds them into the QEMU image, and checks
//! what the image prints after replaying them (`firmware::tick_replay`).

use std::path::PathBuf;
use std::sync::OnceLock;

use crate::{Result, cargo, root, run};

/// Worst instructions a tick may take in any phase (issue 13: the budget).
pub const BUDGET_INSTR: u64 = 10_000;
/// Largest difference allowed between the target's and the host's motor
/// commands for the same inputs, N·m (both run the same f32 code: the
/// replay finds none; this leaves room for a compiler's reassociation).
pub const COMMAND_BOUND_NM: f64 = 1e-3;

/// The recording (made once per xtask run): `target/replay/ticks.bin`.
pub fn recording() -> Result<PathBuf> {
    static MADE: OnceLock<std::result::Result<PathBuf, String>> = OnceLock::new();
    MADE.get_or_init(|| {
        let dir = root().join("target/replay");
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let file = dir.join("ticks.bin");
        run(cargo()
            .args(["run", "-q", "-p", "sim", "--example", "record_ticks", "--"])
            .arg(&file))?;
        Ok(file)
    })
    .clone()
}

/// One `tick: phase=… avg=… worst=… ticks=…` line.
struct PhaseLine {
    name: String,
    worst: u64,
}

fn field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    line.split_whitespace()
        .find_map(|w| w.strip_prefix(key)?.strip_prefix('='))
}

/// Checks the replay's lines in the QEMU output: every phase within the
/// budget, the commands within the bound of the host's.
pub fn check(qemu_stdout: &str) -> Result {
    let lines: Vec<&str> = qemu_stdout
        .lines()
        .filter_map(|l| l.trim().strip_prefix("tick: "))
        .collect();
    let phases: Vec<PhaseLine> = lines
        .iter()
        .filter_map(|l| {
            Some(PhaseLine {
                name: field(l, "phase")?.to_owned(),
                worst: field(l, "worst")?.parse().ok()?,
            })
        })
        .collect();
    let summary = lines
        .iter()
        .find(|l| l.starts_with("replayed"))
        .ok_or("the QEMU image replayed no recorded ticks")?;
    let diff: f64 = field(summary, "max_command_diff_nm")
        .and_then(|d| d.parse().ok())
        .ok_or_else(|| format!("cannot read the command difference in `{summary}`"))?;
    for wanted in ["standing", "swing", "transfer", "safe-hold"] {
        if !phases.iter().any(|p| p.name == wanted) {
            return Err(format!("the replay has no `{wanted}` ticks"));
        }
    }
    let over: Vec<String> = phases
        .iter()
        .filter(|p| p.worst > BUDGET_INSTR)
        .map(|p| format!("{} (worst {})", p.name, p.worst))
        .collect();
    if !over.is_empty() {
        return Err(format!(
            "the tick is over its budget of {BUDGET_INSTR} instructions in: {}",
            over.join(", ")
        ));
    }
    if diff.is_nan() || diff > COMMAND_BOUND_NM {
        return Err(format!(
            "the target's motor commands differ from the host's by {diff} N·m \
             (bound {COMMAND_BOUND_NM})"
        ));
    }
    println!(
        "tick replay: every phase within {BUDGET_INSTR} instructions; commands within \
         {diff:e} N·m of the host's"
    );
    Ok(())
}
