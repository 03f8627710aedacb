//! `cargo xtask profile`: where the replayed ticks' instructions go. QEMU
//! runs the image with its execution log (`-d in_asm,exec,nochain`)
//! streamed to this task, which counts each translation block's executions
//! from the firmware's `replay_starts` on, weighs them by the block's
//! instructions, and attributes each block, through
//! `arm-none-eabi-addr2line -i`, to the innermost project source file it
//! was inlined from. The figure per file is instructions per replayed tick.

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::process::{Command, Stdio};

use crate::{Result, root};

/// The firmware function whose first execution starts the count.
const MARKER: &str = "replay_starts";

/// Translation blocks: instructions per block start, executions per block
/// start (from the marker on).
#[derive(Debug, Default, PartialEq)]
pub struct ExecLog {
    /// Instructions in the block starting at each address.
    pub sizes: HashMap<u32, u64>,
    /// Executions of the block starting at each address.
    pub runs: HashMap<u32, u64>,
}

impl ExecLog {
    /// Reads QEMU's `in_asm,exec,nochain` log line by line.
    pub fn read(log: impl BufRead) -> std::io::Result<Self> {
        let mut out = Self::default();
        let mut block: Option<(Option<u32>, u64)> = None;
        let mut counting = false;
        for line in log.lines() {
            let line = line?;
            if line.starts_with("IN:") {
                block = Some((None, 0));
            } else if let Some((start, n)) = block.as_mut() {
                if let Some(addr) = line.strip_prefix("0x").and_then(|l| l.split(':').next()) {
                    if start.is_none() {
                        *start = u32::from_str_radix(addr, 16).ok();
                    }
                    *n += 1;
                } else if line.trim().is_empty() {
                    if let Some(s) = *start {
                        out.sizes.insert(s, *n);
                    }
                    block = None;
                }
            } else if let Some(rest) = line.strip_prefix("Trace ") {
                counting |= rest.contains(MARKER);
                if counting {
                    // "0: 0x7f.. [flags/PC/flags/flags] symbol"
                    let pc = rest
                        .split('[')
                        .nth(1)
                        .and_then(|f| f.split('/').nth(1))
                        .and_then(|pc| u32::from_str_radix(pc, 16).ok());
                    if let Some(pc) = pc {
                        *out.runs.entry(pc).or_insert(0) += 1;
                    }
                }
            }
        }
        Ok(out)
    }

    /// Instructions executed in the block starting at each address.
    pub fn instructions(&self) -> impl Iterator<Item = (u32, u64)> + '_ {
        self.runs
            .iter()
            .map(|(pc, n)| (*pc, n * self.sizes.get(pc).copied().unwrap_or(0)))
    }
}

/// The innermost project file of each address in `addr2line -i -a`'s
/// output (an address line, then its frames innermost first), relative to
/// the repository; frames outside the project (core, libm, builtins) are
/// skipped, and an address with none is "other (core, libm, builtins)".
pub fn files_of(addr2line: &str, repo: &str) -> HashMap<u32, String> {
    let mut out = HashMap::new();
    let mut current: Option<u32> = None;
    for line in addr2line.lines() {
        if let Some(hex) = line.strip_prefix("0x") {
            current = u32::from_str_radix(hex.trim(), 16).ok();
            if let Some(a) = current {
                out.insert(a, OTHER.to_string());
            }
            continue;
        }
        let Some(a) = current else { continue };
        let file = line.split(':').next().unwrap_or_default();
        let ours = file
            .strip_prefix(repo)
            .map(|f| f.trim_start_matches('/'))
            .filter(|f| f.starts_with("crates/") || f.starts_with("firmware/"));
        if let (Some(f), Some(slot)) = (ours, out.get_mut(&a)) {
            if slot == OTHER {
                *slot = f.to_string();
            }
        }
    }
    out
}

const OTHER: &str = "other (core, libm, builtins)";

/// Runs the QEMU image `elf` with its execution log and prints the
/// instructions per replayed tick by source file, largest first.
pub fn profile(elf: &Path) -> Result {
    let mut child = Command::new("qemu-system-arm")
        .args(["-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic"])
        .args(["-monitor", "none", "-serial", "none"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(["-icount", "shift=0"])
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
    let pcs: Vec<String> = log.runs.keys().map(|pc| format!("0x{pc:08x}")).collect();
    let lines = Command::new("arm-none-eabi-addr2line")
        .args(["-i", "-a", "-e"])
        .arg(elf)
        .args(&pcs)
        .output()
        .map_err(|e| format!("cannot run arm-none-eabi-addr2line: {e}"))?;
    let repo = root().display().to_string();
    let files = files_of(&String::from_utf8_lossy(&lines.stdout), &repo);
    let mut by_file: HashMap<&str, u64> = HashMap::new();
    for (pc, n) in log.instructions() {
        let f = files.get(&pc).map_or(OTHER, String::as_str);
        *by_file.entry(f).or_insert(0) += n;
    }
    let total: u64 = by_file.values().sum();
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
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn blocks_count_from_the_marker_on_weighed_by_their_instructions() {
        let log = ExecLog::read(LOG.as_bytes()).unwrap();
        assert_eq!(log.sizes.get(&0x2000), Some(&3));
        // Reset's first run was before the marker.
        assert_eq!(log.runs.get(&0x400), Some(&1));
        assert_eq!(log.runs.get(&0x2000), Some(&2));
        let mut ins: Vec<_> = log.instructions().collect();
        ins.sort();
        assert_eq!(ins, vec![(0x400, 1), (0x1000, 1), (0x2000, 6)]);
    }

    #[test]
    fn an_address_goes_to_the_innermost_file_of_the_project() {
        let out = "\
0x00002000
/rustc/abc/library/core/src/slice/mod.rs:100
/repo/crates/gait-core/src/scalar.rs:140
/repo/crates/gait-control/src/controller.rs:12
0x00000400
/rustc/abc/library/core/src/ptr/mod.rs:9
";
        let files = files_of(out, "/repo");
        assert_eq!(files[&0x2000], "crates/gait-core/src/scalar.rs");
        assert_eq!(files[&0x400], OTHER);
    }
}
