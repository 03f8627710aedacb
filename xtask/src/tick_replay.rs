//! The control tick on the target, phase by phase: records the controller's
//! inputs in the simulator (`sim::replay`, walks, stair ascent and descent,
//! a fault and its safe hold), builds them into the QEMU image, and checks
//! what the image prints after replaying them (`firmware::tick_replay`).

use std::path::PathBuf;
use std::sync::OnceLock;

use crate::{Result, cargo, root, run};

/// Worst instructions a tick may take in any phase: the headroom the
/// idle-time re-planner and the model task need (issue 39). The period is
/// 168,000 cycles; the sensors are read before the tick, by DMA.
pub const BUDGET_INSTR: u64 = 6_000;
/// Largest difference allowed between the target's and the host's motor
/// commands for the same inputs, N·m (both run the same f32 code: the
/// replay finds none; this leaves room for a compiler's reassociation).
pub const COMMAND_BOUND_NM: f64 = 1e-3;

/// The recordings the QEMU image replays.
#[derive(Clone, Debug)]
pub struct Recordings {
    /// The gaits' runs: `target/replay/ticks.bin`.
    pub ticks: PathBuf,
    /// The run with the idle-time re-planner on:
    /// `target/replay/replanning.bin`.
    pub replanning: PathBuf,
}

/// The recordings (made once per xtask run).
pub fn recording() -> Result<Recordings> {
    static MADE: OnceLock<std::result::Result<Recordings, String>> = OnceLock::new();
    MADE.get_or_init(|| {
        let dir = root().join("target/replay");
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let files = Recordings {
            ticks: dir.join("ticks.bin"),
            replanning: dir.join("replanning.bin"),
        };
        run(cargo()
            .args(["run", "-q", "-p", "sim", "--example", "record_ticks", "--"])
            .arg(&files.ticks)
            .arg(&files.replanning))?;
        Ok(files)
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
    check_replanning(qemu_stdout)
}

/// The re-planner's latency, ticks: every answer of the preempted replay
/// must come sooner (`exogait_device::replan::REPLAN`).
const LATENCY_TICKS: u64 = exogait_device::replan::REPLAN.latency_ticks as u64;
/// 0.5 s of the 168 MHz core: the most one re-plan may take.
const MAX_REPLAN_INSTR: u64 = 84_000_000;

/// Checks the replay with the re-planner in the tick's idle time
/// (`firmware/src/bin/qemu/preempted.rs`): re-planned steps played, each
/// answer within the latency and 0.5 s of the core, no tick overrun, the
/// commands the host's. Its `tick:` phase lines are within the budget
/// with the others.
fn check_replanning(qemu_stdout: &str) -> Result {
    // A line the image marked `FAIL ` is read as any other.
    let unmarked = |l: &str| {
        let l = l.trim();
        l.strip_prefix("FAIL ").unwrap_or(l).to_owned()
    };
    let lines: Vec<String> = qemu_stdout.lines().map(unmarked).collect();
    let summary = lines
        .iter()
        .find_map(|l| l.strip_prefix("tick: replanning replayed "))
        .ok_or("the QEMU image did not replay the re-planning run")?;
    let number = |l: &str, key: &str| -> Result<u64> {
        field(l, key)
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| format!("no {key}= in `{l}`"))
    };
    if number(summary, "differing_ticks")? != 0 || number(summary, "overruns")? != 0 {
        return Err(format!("the re-planning replay failed: {summary}"));
    }
    let replans: Vec<&str> = lines
        .iter()
        .filter_map(|l| l.strip_prefix("replan: tick="))
        .collect();
    let mut used = 0;
    for r in &replans {
        let line = format!("tick={r}");
        if number(&line, "ticks")? >= LATENCY_TICKS || number(&line, "insns")? > MAX_REPLAN_INSTR {
            return Err(format!("a re-plan took too long: replan: {line}"));
        }
        used += usize::from(field(&line, "used") == Some("replanned"));
    }
    if used == 0 {
        return Err("the re-planning replay played no re-planned step".into());
    }
    println!(
        "re-planning replay: {used} of {} steps re-planned in the tick's idle time, \
         each within {LATENCY_TICKS} ticks; no overrun; commands the host's",
        replans.len()
    );
    Ok(())
}
