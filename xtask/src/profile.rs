//! `cargo xtask profile`: where the replayed ticks' instructions go. QEMU
//! runs the image with its execution log (`-d in_asm,exec,nochain`)
//! streamed to this task, which counts each translation block's executions
//! from the firmware's `replay_starts` on, and attributes each executed
//! instruction, through `arm-none-eabi-addr2line -i`, to the innermost
//! project source line it was inlined from. The figures, per file and then
//! for the costliest lines, are instructions per replayed tick; then, per
//! phase, the files of its costliest tick (the firmware marks where each
//! replayed tick starts and the phase it ended in).

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::process::{Command, Stdio};

use crate::{Result, root};

/// The firmware function whose first execution starts the count.
const MARKER: &str = "replay_starts";

/// Marks the firmware's replay runs before each tick (`tick_replay::marks`).
const TICK_STARTS: &str = "tick_starts";
/// Marks after a tick, followed by the phase it ended in.
const TICK_ENDED: &str = "tick_ended_";

/// A translation block: QEMU's host code pointer and its guest start.
type Block = (u64, u32);

/// Translation blocks: each block's instruction addresses and its runs
/// from the marker on. A block is known by QEMU's host code pointer and its
/// guest start: QEMU may translate the same guest address into blocks of
/// different lengths (under `-icount`), and each is counted as itself.
#[derive(Debug, Default, PartialEq)]
pub struct ExecLog {
    /// Each block's instruction addresses.
    pub blocks: HashMap<Block, Vec<u32>>,
    /// Runs of each block.
    pub runs: HashMap<Block, u64>,
    /// The marker was executed.
    pub marked: bool,
    /// The costliest marked tick of each phase (by the marker's name).
    pub worst: HashMap<String, WorstTick>,
}

/// A phase's costliest tick: its instructions and its blocks' runs.
#[derive(Debug, Default, PartialEq)]
pub struct WorstTick {
    /// Ticks marked with the phase.
    pub ticks: u64,
    /// The costliest one's instructions.
    pub instructions: u64,
    /// Its blocks' runs.
    pub runs: HashMap<Block, u64>,
}

impl ExecLog {
    /// Reads QEMU's `in_asm,exec,nochain` log line by line: a translation
    /// ("IN:", its instructions, a blank line) is followed by its block's
    /// first run ("Trace 0: <host pointer> [flags/<guest pc>/..] symbol").
    pub fn read(log: impl BufRead) -> std::io::Result<Self> {
        let mut out = Self::default();
        let mut reading: Option<Vec<u32>> = None;
        let mut translated: Option<Vec<u32>> = None;
        // The blocks of the marked tick running now.
        let mut tick: Option<HashMap<Block, u64>> = None;
        for line in log.lines() {
            let line = line?;
            if line.starts_with("IN:") {
                reading = Some(Vec::new());
            } else if let Some(addrs) = reading.as_mut() {
                if let Some(addr) = line.strip_prefix("0x").and_then(|l| l.split(':').next()) {
                    if let Ok(a) = u32::from_str_radix(addr, 16) {
                        addrs.push(a);
                    }
                } else if line.trim().is_empty() {
                    translated = reading.take();
                }
            } else if let Some(rest) = line.strip_prefix("Trace ") {
                let Some(key) = block_key(rest) else { continue };
                if let Some(addrs) = translated.take_if(|a| a.first() == Some(&key.1)) {
                    out.blocks.insert(key, addrs);
                }
                out.marked |= rest.contains(MARKER);
                if out.marked {
                    *out.runs.entry(key).or_insert(0) += 1;
                }
                if rest.contains(TICK_STARTS) {
                    tick = Some(HashMap::new());
                } else if let Some(phase) = marked_phase(rest) {
                    if let Some(runs) = tick.take() {
                        out.end_tick(phase, runs);
                    }
                } else if let Some(runs) = tick.as_mut() {
                    *runs.entry(key).or_insert(0) += 1;
                }
            }
        }
        Ok(out)
    }

    /// A marked tick of `phase` ran the blocks `runs`: kept if it is the
    /// phase's costliest so far.
    fn end_tick(&mut self, phase: &str, runs: HashMap<Block, u64>) {
        let instructions: u64 = runs
            .iter()
            .map(|(key, n)| n * self.blocks.get(key).map_or(0, |a| a.len() as u64))
            .sum();
        let worst = self.worst.entry(phase_name(phase)).or_default();
        worst.ticks += 1;
        if instructions > worst.instructions {
            worst.instructions = instructions;
            worst.runs = runs;
        }
    }

    /// Instructions executed at each address.
    pub fn instructions(&self) -> HashMap<u32, u64> {
        self.instructions_of(&self.runs)
    }

    /// Instructions executed at each address by the blocks' `runs`.
    pub fn instructions_of(&self, runs: &HashMap<Block, u64>) -> HashMap<u32, u64> {
        let mut out = HashMap::new();
        for (key, n) in runs {
            for a in self.blocks.get(key).into_iter().flatten() {
                *out.entry(*a).or_insert(0) += n;
            }
        }
        out
    }
}

/// The phase a trace line's tick-end marker names ("…tick_ended_swing").
fn marked_phase(trace: &str) -> Option<&str> {
    let (_, after) = trace.split_once(TICK_ENDED)?;
    let end = after
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(after.len());
    after.get(..end).filter(|p| !p.is_empty())
}

/// A marker's phase as the `tick:` lines name it ("safe_hold" → "safe-hold").
fn phase_name(marked: &str) -> String {
    marked.replace('_', "-")
}

/// A trace line's block: "0: 0x<host> [flags/<pc>/flags/flags] symbol".
fn block_key(trace: &str) -> Option<(u64, u32)> {
    let host = trace.split_whitespace().nth(1)?.strip_prefix("0x")?;
    let pc = trace.split('[').nth(1)?.split('/').nth(1)?;
    Some((
        u64::from_str_radix(host, 16).ok()?,
        u32::from_str_radix(pc, 16).ok()?,
    ))
}

/// Where an instruction came from: the innermost project source line it
/// was inlined from, or, outside the project, [`OTHER`] and the innermost
/// library line.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Source {
    pub file: String,
    pub line: u32,
}

/// The innermost project source line of each address in `addr2line -i -a`'s
/// output (an address line, then its frames innermost first, each
/// `path:line`, perhaps followed by ` (discriminator n)`), the path
/// relative to the repository; frames outside the project (core, libm,
/// builtins) are skipped, and an address with none is [`OTHER`] with its
/// innermost library frame.
pub fn sources_of(addr2line: &str, repo: &str) -> HashMap<u32, Source> {
    let other = || Source {
        file: OTHER.to_string(),
        line: 0,
    };
    let mut out = HashMap::new();
    let mut current: Option<u32> = None;
    for line in addr2line.lines() {
        if let Some(hex) = line.strip_prefix("0x") {
            current = u32::from_str_radix(hex.trim(), 16).ok();
            if let Some(a) = current {
                out.insert(a, other());
            }
            continue;
        }
        let Some(a) = current else { continue };
        let frame = line.split(" (").next().unwrap_or_default();
        let (file, number) = frame.rsplit_once(':').unwrap_or((frame, ""));
        let number = number.trim().parse().unwrap_or(0);
        if let Some(slot) = out.get_mut(&a).filter(|s| s.file == OTHER && s.line == 0) {
            // The innermost frame outside the project names it, until a
            // project frame takes over.
            *slot = Source {
                file: format!("{OTHER}: {}", outside_path(file)),
                line: number,
            };
        }
        let ours = file
            .strip_prefix(repo)
            .map(|f| f.trim_start_matches('/'))
            .filter(|f| f.starts_with("crates/") || f.starts_with("firmware/"));
        if let (Some(f), Some(slot)) = (ours, out.get_mut(&a)) {
            if slot.file.starts_with(OTHER) {
                *slot = Source {
                    file: f.to_string(),
                    line: number,
                };
            }
        }
    }
    out
}

/// A path outside the project, from its crate on (`core/src/ptr/mod.rs`,
/// `compiler_builtins-0.1.x/src/mem/mod.rs`): which library's code it is.
fn outside_path(file: &str) -> &str {
    ["/library/", "/registry/src/", "/src/"]
        .iter()
        .find_map(|marker| file.rsplit_once(marker).map(|(_, rest)| rest))
        .map_or(file, |rest| match rest.split_once('/') {
            // A registry path starts with its index's directory.
            Some((index, crate_path)) if index.starts_with("index.") => crate_path,
            _ => rest,
        })
}

const OTHER: &str = "other (core, libm, builtins)";

/// Source lines listed after the files, the costliest first.
const TOP_LINES: usize = 40;

/// Runs the QEMU image `elf` with its execution log and prints the
/// instructions per replayed tick by source file, largest first.
pub fn profile(elf: &Path) -> Result {
    let mut child = Command::new("qemu-system-arm")
        .args(["-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic"])
        .args(["-monitor", "none", "-serial", "none"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(["-icount", "shift=0,sleep=off"])
        .args(["-d", "in_asm,exec,nochain"])
        .arg("-kernel")
        .arg(elf)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start qemu-system-arm: {e}"))?;
    let mut stdout = child.stdout.take().ok_or("no QEMU stdout")?;
    let printed = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stdout.read_to_string(&mut s);
        s
    });
    let stderr = child.stderr.take().ok_or("no QEMU log")?;
    let log = ExecLog::read(BufReader::new(stderr)).map_err(|e| format!("QEMU log: {e}"))?;
    if !log.marked {
        return Err(format!("the image never ran `{MARKER}`: nothing counted"));
    }
    let status = child.wait().map_err(|e| format!("QEMU: {e}"))?;
    let printed = printed.join().unwrap_or_default();
    if !status.success() {
        return Err(format!("QEMU self-test failed ({status})"));
    }
    let ticks: u64 = printed
        .lines()
        .find_map(|l| l.strip_prefix("tick: replayed "))
        .and_then(|l| l.split_whitespace().find_map(|w| w.strip_prefix("ticks=")))
        .and_then(|n| n.parse().ok())
        .filter(|&n| n > 0)
        .ok_or("the image replayed no ticks")?;
    let instructions = log.instructions();
    let pcs: Vec<String> = instructions.keys().map(|a| format!("0x{a:08x}")).collect();
    let lines = Command::new("arm-none-eabi-addr2line")
        .args(["-i", "-a", "-e"])
        .arg(elf)
        .args(&pcs)
        .output()
        .map_err(|e| format!("cannot run arm-none-eabi-addr2line: {e}"))?;
    let repo = root().display().to_string();
    let sources = sources_of(&String::from_utf8_lossy(&lines.stdout), &repo);
    let mut by_file: HashMap<&str, u64> = HashMap::new();
    let mut by_line: HashMap<(&str, u32), u64> = HashMap::new();
    for (a, n) in &instructions {
        let (file, line) = sources
            .get(a)
            .map_or((OTHER, 0), |s| (s.file.as_str(), s.line));
        *by_file.entry(file).or_insert(0) += n;
        *by_line.entry((file, line)).or_insert(0) += n;
    }
    let total: u64 = by_file.values().sum();
    if total == 0 {
        return Err("no instruction counted after the marker".into());
    }
    let mut rows: Vec<(&str, u64)> = by_file.into_iter().collect();
    rows.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
    println!(
        "profile: ticks={ticks} instr_per_tick={} (the replay's harness included)",
        total / ticks
    );
    for (f, n) in rows {
        println!(
            "profile: {:>6} {:>5.1} % {f}",
            n / ticks,
            100.0 * n as f64 / total.max(1) as f64
        );
    }
    let mut lines: Vec<((&str, u32), u64)> = by_line.into_iter().collect();
    lines.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    for ((f, line), n) in lines.into_iter().take(TOP_LINES) {
        println!("profile-line: {:>6} {f}:{line}", n / ticks);
    }
    print_worst_ticks(&log, &sources);
    Ok(())
}

/// Files listed for each phase's costliest tick.
const TOP_WORST_FILES: usize = 60;

/// The tick's stages as the README's "Performance" table groups them, by
/// what a source file's path holds (the first stage that matches; what
/// none does is shared: clamps, copies, compiler builtins).
const STAGES: [(&str, &[&str]); 8] = [
    ("rig", &["qemu_rig.rs"]),
    ("timer-reads", &["tick_replay.rs", "bin/qemu"]),
    (
        "sense",
        &[
            "controller/sense.rs",
            "as5048a.rs",
            "mcp3208.rs",
            "buttons.rs",
            "controller/chain.rs",
            "controller/estop.rs",
            "acquisition",
        ],
    ),
    (
        "plan",
        &[
            "sequencer",
            "ahead",
            "operator.rs",
            "reference.rs",
            "tables.rs",
            "kinematics.rs",
            "posture.rs",
            "reach.rs",
            "model.rs",
            "foot.rs",
            "ik.rs",
        ],
    ),
    (
        "act",
        &[
            "controller/act.rs",
            "position_loop.rs",
            "feedforward.rs",
            "dynamics",
        ],
    ),
    (
        "guard",
        &[
            "supervisor",
            "controller/guard.rs",
            "check_slot.rs",
            "faults",
            "ring_log.rs",
        ],
    ),
    (
        "write",
        &[
            "controller/write.rs",
            "motor.rs",
            "status.rs",
            "crutch_load.rs",
        ],
    ),
    ("shared", &[]),
];

/// The stage of [`STAGES`] `file` belongs to.
fn stage_of(file: &str) -> &'static str {
    STAGES
        .iter()
        .find(|(_, parts)| parts.iter().any(|p| file.contains(p)))
        .map_or("shared", |&(stage, _)| stage)
}

/// Per phase, its costliest marked tick by stage and source file (and, for the
/// costliest phase, by line): what the `tick:` lines' worst figures are made
/// of (plus the few instructions of the replay's timer reads).
fn print_worst_ticks(log: &ExecLog, sources: &HashMap<u32, Source>) {
    let mut phases: Vec<(&String, &WorstTick)> = log.worst.iter().collect();
    phases.sort_by(|a, b| b.1.instructions.cmp(&a.1.instructions).then(a.0.cmp(b.0)));
    for (k, (phase, worst)) in phases.into_iter().enumerate() {
        println!(
            "profile-phase: {phase} ticks={} worst={}",
            worst.ticks, worst.instructions
        );
        let mut by_file: HashMap<&str, u64> = HashMap::new();
        let mut by_line: HashMap<(&str, u32), u64> = HashMap::new();
        for (a, n) in log.instructions_of(&worst.runs) {
            let (file, line) = sources
                .get(&a)
                .map_or((OTHER, 0), |s| (s.file.as_str(), s.line));
            *by_file.entry(file).or_insert(0) += n;
            *by_line.entry((file, line)).or_insert(0) += n;
        }
        let mut by_stage: Vec<(&str, u64)> = STAGES.iter().map(|&(s, _)| (s, 0)).collect();
        for (f, n) in &by_file {
            let stage = stage_of(f);
            if let Some(row) = by_stage.iter_mut().find(|(s, _)| *s == stage) {
                row.1 += n;
            }
        }
        for (stage, n) in by_stage {
            println!("profile-stage: {phase} {stage} {n}");
        }
        let mut rows: Vec<(&str, u64)> = by_file.into_iter().collect();
        rows.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
        for (f, n) in rows.into_iter().take(TOP_WORST_FILES) {
            println!("profile-worst: {phase} {n:>6} {f}");
        }
        if k == 0 {
            let mut lines: Vec<((&str, u32), u64)> = by_line.into_iter().collect();
            lines.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
            for ((f, line), n) in lines.into_iter().take(TOP_LINES) {
                println!("profile-worst-line: {phase} {n:>6} {f}:{line}");
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_file_goes_to_its_stage() {
        for (file, stage) in [
            ("crates/gait-control/src/controller/sense.rs", "sense"),
            ("crates/gait-control/src/drivers/as5048a.rs", "sense"),
            ("crates/gait-control/src/sequencer/swing.rs", "plan"),
            ("crates/gait-control/src/ahead/swing.rs", "plan"),
            ("crates/gait-core/src/dynamics/pinned.rs", "act"),
            ("crates/gait-control/src/supervisor/tracks.rs", "guard"),
            ("crates/gait-control/src/drivers/motor.rs", "write"),
            ("crates/gait-core/src/scalar.rs", "shared"),
            ("firmware/src/qemu_rig.rs", "rig"),
            ("firmware/src/bin/qemu/recorded.rs", "timer-reads"),
        ] {
            assert_eq!(stage_of(file), stage, "{file}");
        }
    }

    const LOG: &str = "\
----------------
IN: Reset
0x00000400:  f017 f8f6  bl       #0x175f0

Trace 0: 0x7f4bc4000100 [00800408/00000400/00000110/ff020200] Reset
----------------
IN: _RNvNtCs1_8firmware11tick_replay13replay_starts
0x00001000:  4770       bx       lr

Trace 0: 0x7f4bc4000200 [00800408/00001000/00000110/ff020200] _RNvNtCs1_8firmware11tick_replay13replay_starts
----------------
IN: tick
0x00002000:  b580       push     {r7, lr}
0x00002002:  466f       mov      r7, sp
0x00002004:  bd80       pop      {r7, pc}

Trace 0: 0x7f4bc4000300 [00800408/00002000/00000110/ff020200] tick
Trace 0: 0x7f4bc4000300 [00800408/00002000/00000110/ff020200] tick
Trace 0: 0x7f4bc4000100 [00800408/00000400/00000110/ff020200] Reset
";

    #[test]
    fn instructions_count_from_the_marker_on_block_by_block() {
        let log = ExecLog::read(LOG.as_bytes()).unwrap();
        assert!(log.marked);
        assert_eq!(
            log.blocks.get(&(0x7f4b_c400_0300, 0x2000)).map(Vec::len),
            Some(3)
        );
        let ins = log.instructions();
        // Reset's first run was before the marker, its second after.
        assert_eq!(ins.get(&0x400), Some(&1));
        assert_eq!(ins.get(&0x1000), Some(&1));
        for a in [0x2000, 0x2002, 0x2004] {
            assert_eq!(ins.get(&a), Some(&2), "{a:x}");
        }
        // The same address translated again, shorter (as under -icount):
        // each block counts its own instructions.
        let again = LOG.to_string()
            + "----------------\nIN: tick\n0x00002000:  b580       push     {r7, lr}\n\n\
               Trace 0: 0x7f4bc4000400 [00800408/00002000/00000110/ff020200] tick\n";
        let ins = ExecLog::read(again.as_bytes()).unwrap().instructions();
        assert_eq!(ins.get(&0x2000), Some(&3));
        assert_eq!(ins.get(&0x2002), Some(&2));
        // A marked tick: counted under its phase, markers left out; the
        // costlier of two is kept.
        let marked = LOG.to_string()
            + "----------------\nIN: _RNvNtNtCs1_8firmware11tick_replay5marks11tick_starts\n\
               0x00003000:  4770       bx       lr\n\n\
               Trace 0: 0x7f4bc4000500 [00800408/00003000/00000110/ff020200] \
               _RNvNtNtCs1_8firmware11tick_replay5marks11tick_starts\n\
               Trace 0: 0x7f4bc4000300 [00800408/00002000/00000110/ff020200] tick\n\
               ----------------\nIN: _RNvNtNtCs1_8firmware11tick_replay5marks16tick_ended_swing\n\
               0x00003100:  4770       bx       lr\n\n\
               Trace 0: 0x7f4bc4000600 [00800408/00003100/00000110/ff020200] \
               _RNvNtNtCs1_8firmware11tick_replay5marks16tick_ended_swing\n\
               Trace 0: 0x7f4bc4000100 [00800408/00000400/00000110/ff020200] Reset\n\
               Trace 0: 0x7f4bc4000500 [00800408/00003000/00000110/ff020200] tick_starts\n\
               Trace 0: 0x7f4bc4000100 [00800408/00000400/00000110/ff020200] Reset\n\
               Trace 0: 0x7f4bc4000600 [00800408/00003100/00000110/ff020200] tick_ended_swing\n";
        let log = ExecLog::read(marked.as_bytes()).unwrap();
        let swing = &log.worst["swing"];
        assert_eq!((swing.ticks, swing.instructions), (2, 3));
        assert_eq!(swing.runs.len(), 1);
        assert_eq!(log.worst.len(), 1);
        assert_eq!(marked_phase("x 20tick_ended_safe_hold"), Some("safe_hold"));
        assert_eq!(phase_name("safe_hold"), "safe-hold");
        // No marker, nothing counted.
        let unmarked = LOG.replace("replay_starts", "something_else");
        let log = ExecLog::read(unmarked.as_bytes()).unwrap();
        assert!(!log.marked);
        assert!(log.instructions().is_empty());
    }

    #[test]
    fn an_address_goes_to_the_innermost_line_of_the_project() {
        let out = "\
0x00002000
/rustc/abc/library/core/src/slice/mod.rs:100
/repo/crates/gait-core/src/scalar.rs:140 (discriminator 3)
/repo/crates/gait-control/src/controller.rs:12
0x00000400
/rustc/abc/library/core/src/ptr/mod.rs:9
0x00000402
/repo/firmware/src/qemu_rig.rs:?
";
        let sources = sources_of(out, "/repo");
        assert_eq!(
            sources[&0x2000],
            Source {
                file: "crates/gait-core/src/scalar.rs".into(),
                line: 140
            }
        );
        // Outside the project, the innermost frame names the library.
        assert_eq!(
            sources[&0x400],
            Source {
                file: format!("{OTHER}: core/src/ptr/mod.rs"),
                line: 9
            }
        );
        // A line addr2line cannot tell still names its file.
        assert_eq!(
            sources[&0x402],
            Source {
                file: "firmware/src/qemu_rig.rs".into(),
                line: 0
            }
        );
    }
}
