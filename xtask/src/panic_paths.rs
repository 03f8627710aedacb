//! Finds the panic paths left in a linked firmware image.
//!
//! The image is disassembled (`arm-none-eabi-objdump -d -C`) into a call
//! graph: each function and the functions its direct branches reach. A
//! *panic entry* is one of core's panic functions (`core::panicking::*`,
//! unwrap/expect failures, slice and str index failures, `RefCell` borrow
//! failures). Two rules, checked on both boards' release images:
//!
//! 1. Nothing the control tick (`Controller::tick`) reaches may reach a panic
//!    entry.
//! 2. No function of our crates (gait-core, gait-control, the device
//!    configuration, the firmware's wiring apart from the boot code in `main`)
//!    may branch into a panic path.
//!
//! What remains is printed: vendor boot code and the log transport, listed in
//! `docs/safety.md` ("No panic path") with the reason each is still there.
//! Calls through function pointers are not followed (the drivers are generic,
//! so the tick's calls are direct; the check prints how many it saw).

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::Path;
use std::process::Command;

use crate::{Result, output};

/// Functions whose call is a panic.
const PANIC_ENTRIES: [&str; 8] = [
    "core::panicking::",
    "core::option::unwrap_failed",
    "core::option::expect_failed",
    "core::result::unwrap_failed",
    "core::cell::panic_already",
    "core::slice::index::slice_",
    "core::str::slice_error_fail",
    "core::panic::",
];

/// Crates whose code must not branch into a panic path anywhere.
const OURS: [&str; 4] = [
    "gait_core::",
    "gait_control::",
    "exogait_device::",
    "firmware::",
];

/// The image's call graph: function → functions its direct branches reach.
struct CallGraph {
    edges: BTreeMap<String, BTreeSet<String>>,
    indirect_calls: usize,
}

fn is_panic_entry(name: &str) -> bool {
    let bare = name.trim_start_matches('<');
    PANIC_ENTRIES.iter().any(|p| bare.starts_with(p)) || name.ends_with("rust_begin_unwind")
}

/// Our crates' code, not counting derived `Debug`/`Display` impls: those
/// only run for the QEMU image's semihosting prints, inside core's
/// formatting machinery (whose panic paths are core's).
fn is_ours(name: &str) -> bool {
    OURS.iter().any(|c| name.contains(c)) && !name.contains(" as core::fmt::")
}

impl CallGraph {
    fn of(elf: &Path) -> Result<Self> {
        let text = output(
            Command::new("arm-none-eabi-objdump")
                .args(["-d", "--no-show-raw-insn", "-C"])
                .arg(elf),
        )?;
        let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        let mut current: Option<String> = None;
        let mut indirect_calls = 0;
        for line in text.lines() {
            // "08000200 <name>:" opens a function.
            if let Some(name) = line
                .split_once(" <")
                .filter(|(addr, _)| addr.chars().all(|c| c.is_ascii_hexdigit()))
                .and_then(|(_, rest)| rest.strip_suffix(">:"))
            {
                current = Some(name.to_owned());
                edges.entry(name.to_owned()).or_default();
                continue;
            }
            let Some(from) = &current else { continue };
            let mut fields = line.split_whitespace().skip(1);
            let Some(mnemonic) = fields.next() else {
                continue;
            };
            if mnemonic.starts_with("blx") {
                indirect_calls += 1;
                continue;
            }
            let branches = mnemonic.starts_with('b') && !mnemonic.starts_with("bic")
                || mnemonic.starts_with("cb");
            if !branches {
                continue;
            }
            // "... <target+0x12>": the function the branch lands in.
            let Some(target) = line
                .rsplit_once(" <")
                .and_then(|(_, t)| t.strip_suffix('>'))
                .map(|t| t.split_once("+0x").map_or(t, |(f, _)| f))
            else {
                continue;
            };
            if target != from {
                if let Some(set) = edges.get_mut(from) {
                    set.insert(target.to_owned());
                }
            }
        }
        Ok(Self {
            edges,
            indirect_calls,
        })
    }

    /// Every function that can reach a panic entry (panic entries included).
    fn may_panic(&self) -> BTreeSet<&str> {
        let mut callers: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
        for (from, tos) in &self.edges {
            for to in tos {
                callers.entry(to.as_str()).or_default().push(from.as_str());
            }
        }
        let mut seen: BTreeSet<&str> = self
            .edges
            .keys()
            .map(String::as_str)
            .filter(|f| is_panic_entry(f))
            .collect();
        let mut queue: VecDeque<&str> = seen.iter().copied().collect();
        while let Some(f) = queue.pop_front() {
            for &c in callers.get(f).into_iter().flatten() {
                if seen.insert(c) {
                    queue.push_back(c);
                }
            }
        }
        seen
    }

    /// A shortest call chain from a function matching `root` to a panic entry.
    fn panic_chain_from(&self, root: &str) -> Option<Vec<String>> {
        let mut prev: BTreeMap<&str, &str> = BTreeMap::new();
        let mut queue: VecDeque<&str> = self
            .edges
            .keys()
            .map(String::as_str)
            .filter(|f| f.contains(root))
            .collect();
        let mut seen: BTreeSet<&str> = queue.iter().copied().collect();
        while let Some(f) = queue.pop_front() {
            if is_panic_entry(f) {
                let mut chain = vec![f.to_owned()];
                let mut at = f;
                while let Some(&p) = prev.get(at) {
                    chain.push(p.to_owned());
                    at = p;
                }
                chain.reverse();
                return Some(chain);
            }
            for to in self.edges.get(f).into_iter().flatten() {
                if seen.insert(to.as_str()) {
                    prev.insert(to.as_str(), f);
                    queue.push_back(to.as_str());
                }
            }
        }
        None
    }
}

/// Checks the two rules on `elf`; `Err` names the offending call chain. On
/// success, the functions outside core that still branch into a panic path.
pub fn check(elf: &Path) -> Result<Vec<String>> {
    let graph = CallGraph::of(elf)?;
    let ticks = graph
        .edges
        .keys()
        .filter(|f| f.contains("gait_control::controller::Controller>::tick"))
        .count();
    if ticks == 0 {
        return Err(format!(
            "{}: no `Controller::tick` in the image (inlined?): the check would prove nothing",
            elf.display()
        ));
    }
    if let Some(chain) = graph.panic_chain_from("gait_control::controller::Controller>::tick") {
        return Err(format!(
            "{}: the control tick reaches a panic:\n    {}",
            elf.display(),
            chain.join("\n -> ")
        ));
    }
    let may_panic = graph.may_panic();
    let frontier: Vec<String> = graph
        .edges
        .iter()
        .filter(|(f, _)| !f.trim_start_matches('<').starts_with("core::") && !is_panic_entry(f))
        .filter(|(_, tos)| {
            tos.iter().any(|t| {
                is_panic_entry(t)
                    || t.trim_start_matches('<').starts_with("core::")
                        && may_panic.contains(t.as_str())
            })
        })
        .map(|(f, _)| f.clone())
        .collect();
    if let Some(ours) = frontier.iter().find(|f| is_ours(f)) {
        let chain = graph.panic_chain_from(ours).unwrap_or_default();
        return Err(format!(
            "{}: our code branches into a panic path:\n    {}",
            elf.display(),
            chain.join("\n -> ")
        ));
    }
    println!(
        "panic paths: {}: the control tick ({ticks} instance(s)) reaches none; \
         {} indirect call(s) not followed; left outside our crates ({}):",
        elf.display(),
        graph.indirect_calls,
        frontier.len()
    );
    for f in &frontier {
        let short: String = f.chars().take(110).collect();
        println!("    {short}");
    }
    Ok(frontier)
}
