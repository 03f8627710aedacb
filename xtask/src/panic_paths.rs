//! Proves that a linked firmware image holds no panic.
//!
//! The image is disassembled (`arm-none-eabi-objdump -d -C`) into a call
//! graph: each function and the functions its calls and jumps reach, and
//! the functions whose address it loads from its literal pool (taken to be
//! called). A *panic entry* is one of core's panic functions
//! (`core::panicking::*`, unwrap/expect failures, slice and str index
//! failures, `RefCell` borrow failures) or a branch to the panic handler.
//! Two rules, checked on both boards' release images, with no exception:
//!
//! 1. Nothing reachable from the image's entry points — every handler in
//!    its vector table (Reset and through it `main`, the exceptions, the
//!    interrupts) — reaches a panic entry. The control tick
//!    (`Controller::tick`, kept out of line) must be among what is reached,
//!    or the check would prove nothing.
//! 2. No panic entry is left in the image at all, and nothing branches to
//!    the panic handler. This covers what rule 1 cannot follow: calls
//!    through function pointers (counted and printed).
//!
//! `docs/safety.md` ("No panic path") says what keeps the images so.

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

/// The panic handler's symbol (`#[panic_handler]`).
const PANIC_HANDLER: &str = "rust_begin_unwind";

/// The control tick, which rule 1 must reach.
const TICK: &str = "gait_control::controller::Controller>::tick";

/// The image's call graph.
struct CallGraph {
    /// Function → the functions its direct branches and literal-pool
    /// addresses reach.
    edges: BTreeMap<String, BTreeSet<String>>,
    /// Function → its indirect calls (`blx rN`).
    indirect: BTreeMap<String, usize>,
    /// Entry points: the vector table's handlers.
    roots: BTreeSet<String>,
}

fn is_panic_entry(name: &str) -> bool {
    let bare = name.trim_start_matches('<');
    PANIC_ENTRIES.iter().any(|p| bare.starts_with(p))
}

fn is_panic_handler(name: &str) -> bool {
    name.ends_with(PANIC_HANDLER)
}

/// "08000200 <name>:" → (0x08000200, name).
fn function_header(line: &str) -> Option<(u32, &str)> {
    let (addr, rest) = line.split_once(" <")?;
    let name = rest.strip_suffix(">:")?;
    Some((u32::from_str_radix(addr, 16).ok()?, name))
}

/// The 32-bit words of a section from `objdump -s` ("Contents of section
/// …" then lines "addr w0 w1 w2 w3  ascii"), little-endian.
fn section_words(dump: &str) -> Vec<u32> {
    let mut words = Vec::new();
    for line in dump.lines().filter(|l| l.starts_with(' ')) {
        for field in line.split_whitespace().skip(1).take(4) {
            if field.len() != 8 {
                break;
            }
            let Ok(raw) = u32::from_str_radix(field, 16) else {
                break;
            };
            words.push(raw.swap_bytes());
        }
    }
    words
}

impl CallGraph {
    fn of(elf: &Path) -> Result<Self> {
        let text = output(
            Command::new("arm-none-eabi-objdump")
                .args(["-d", "--no-show-raw-insn", "-C"])
                .arg(elf),
        )?;
        let vectors = output(
            Command::new("arm-none-eabi-objdump")
                .args(["-s", "-j", ".vector_table"])
                .arg(elf),
        )?;
        Self::parse(&text, &vectors).map_err(|e| format!("{}: {e}", elf.display()))
    }

    /// The graph of a disassembly (`objdump -d --no-show-raw-insn -C`) and
    /// a dump of the vector table (`objdump -s -j .vector_table`).
    fn parse(text: &str, vector_dump: &str) -> Result<Self> {
        let starts: BTreeMap<u32, String> = text
            .lines()
            .filter_map(function_header)
            .map(|(a, n)| (a, n.to_owned()))
            .collect();
        let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        let mut indirect: BTreeMap<String, usize> = BTreeMap::new();
        let mut current: Option<String> = None;
        for line in text.lines() {
            if let Some((_, name)) = function_header(line) {
                current = Some(name.to_owned());
                edges.entry(name.to_owned()).or_default();
                continue;
            }
            let Some(from) = &current else { continue };
            let mut fields = line.split_whitespace().skip(1);
            let Some(mnemonic) = fields.next() else {
                continue;
            };
            // A literal-pool word holding a function's address (Thumb bit
            // set): the function is loaded to be called or stored.
            if mnemonic == ".word" {
                let target = fields
                    .next()
                    .and_then(|w| u32::from_str_radix(w.trim_start_matches("0x"), 16).ok())
                    .filter(|w| w & 1 == 1)
                    .and_then(|w| starts.get(&(w & !1)));
                if let (Some(t), Some(set)) = (target, edges.get_mut(from)) {
                    if t != from {
                        set.insert(t.clone());
                    }
                }
                continue;
            }
            if mnemonic.starts_with("blx") && !line.contains(" <") {
                *indirect.entry(from.clone()).or_default() += 1;
                continue;
            }
            let branches = mnemonic.starts_with('b') && !mnemonic.starts_with("bic")
                || mnemonic.starts_with("cb");
            if !branches {
                continue;
            }
            // "... <target>" or "... <target+0x12>": the function the branch
            // lands in. A jump (`b`, `b<cond>`, `cb(n)z`) into the middle of
            // another function is no call: it is the alignment padding
            // between functions (0xd4d4) decoded as `bmi.n`. Calls (`bl`)
            // count wherever they land.
            let Some(target) = line
                .rsplit_once(" <")
                .and_then(|(_, t)| t.strip_suffix('>'))
                .and_then(|t| match t.split_once("+0x") {
                    None => Some(t),
                    Some((f, _)) if mnemonic.starts_with("bl") => Some(f),
                    Some(_) => None,
                })
            else {
                continue;
            };
            if target != from {
                if let Some(set) = edges.get_mut(from) {
                    set.insert(target.to_owned());
                }
            }
        }
        // The vector table: word 0 is the initial stack pointer, every
        // other non-zero word a handler's address with the Thumb bit.
        let vectors = section_words(vector_dump);
        let mut roots: BTreeSet<String> = BTreeSet::new();
        for &v in vectors.iter().skip(1).filter(|&&v| v != 0) {
            let name = starts
                .get(&(v & !1))
                .ok_or_else(|| format!("vector 0x{v:08x} is not the start of a function"))?;
            roots.insert(name.clone());
        }
        if let Some(main) = edges.keys().find(|f| f.as_str() == "main") {
            roots.insert(main.clone());
        }
        if roots.is_empty() {
            return Err("no vector table found".into());
        }
        Ok(Self {
            edges,
            indirect,
            roots,
        })
    }

    /// Everything the entry points reach, with the edge each was found by
    /// (for the chain to print).
    fn reachable(&self) -> BTreeMap<&str, Option<&str>> {
        let mut prev: BTreeMap<&str, Option<&str>> =
            self.roots.iter().map(|r| (r.as_str(), None)).collect();
        let mut queue: VecDeque<&str> = self.roots.iter().map(String::as_str).collect();
        while let Some(f) = queue.pop_front() {
            for to in self.edges.get(f).into_iter().flatten() {
                if !prev.contains_key(to.as_str()) {
                    prev.insert(to.as_str(), Some(f));
                    queue.push_back(to.as_str());
                }
            }
        }
        prev
    }

    /// Functions that branch to `target`.
    fn callers_of(&self, target: &str) -> Vec<&str> {
        self.edges
            .iter()
            .filter(|(_, tos)| tos.iter().any(|t| t == target))
            .map(|(f, _)| f.as_str())
            .collect()
    }
}

fn short(name: &str) -> String {
    let s: String = name.chars().take(140).collect();
    if s.len() < name.len() {
        format!("{s}…")
    } else {
        s
    }
}

/// Checks the two rules on `elf`; `Err` names what is left and how it is
/// reached.
pub fn check(elf: &Path) -> Result {
    let graph = CallGraph::of(elf)?;
    let reached = check_graph(&graph).map_err(|e| format!("{}: {e}", elf.display()))?;
    println!(
        "panic paths: {}: {} functions reachable from {} entry points (the vector \
         table), none reaches a panic; no panic entry left in the image; {} indirect \
         call(s) in reachable code (they cannot reach one: none is left)",
        elf.display(),
        reached.functions,
        graph.roots.len(),
        reached.indirect_calls
    );
    Ok(())
}

/// What the entry points reach, when the rules hold.
struct Reached {
    functions: usize,
    indirect_calls: usize,
}

fn check_graph(graph: &CallGraph) -> Result<Reached> {
    let reach = graph.reachable();
    if !reach.keys().any(|f| f.contains(TICK)) {
        return Err(
            "the entry points do not reach `Controller::tick` (inlined, or the \
                    vector table misread): the check would prove nothing"
                .into(),
        );
    }
    // Rule 1: a shortest chain from an entry point to a panic entry.
    if let Some(&hit) = reach
        .keys()
        .find(|&&f| is_panic_entry(f) || is_panic_handler(f))
    {
        let mut chain = vec![hit];
        let mut at = hit;
        while let Some(&Some(p)) = reach.get(at) {
            chain.push(p);
            at = p;
        }
        chain.reverse();
        let shown: Vec<String> = chain.iter().map(|f| short(f)).collect();
        return Err(format!(
            "a panic is reachable from the entry points:\n    {}",
            shown.join("\n -> ")
        ));
    }
    // Rule 2: nothing of a panic left in the image.
    let mut left: Vec<String> = Vec::new();
    for f in graph.edges.keys() {
        if is_panic_entry(f) {
            let callers: Vec<String> = graph.callers_of(f).iter().map(|c| short(c)).collect();
            left.push(format!(
                "{} (called from: {})",
                short(f),
                if callers.is_empty() {
                    "nothing direct".to_owned()
                } else {
                    callers.join(", ")
                }
            ));
        } else if is_panic_handler(f) {
            for c in graph.callers_of(f) {
                left.push(format!("{} calls the panic handler", short(c)));
            }
        }
    }
    if !left.is_empty() {
        return Err(format!(
            "panic code is left in the image (reached through a function \
             pointer or from code the entry points do not reach):\n    {}",
            left.join("\n    ")
        ));
    }
    Ok(Reached {
        functions: reach.len(),
        indirect_calls: reach.keys().filter_map(|f| graph.indirect.get(*f)).sum(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vector table: initial SP, Reset at 0x100, SysTick at 0x140.
    const VECTORS: &str = "
x.elf:     file format elf32-littlearm

Contents of section .vector_table:
 0000 00000220 01010000 00000000 00000000  ... ............
 0010 41010000                             A...
";

    fn disassembly(systick_body: &str) -> String {
        format!(
            "
00000100 <Reset>:
     100:\tbl\t120 <main>
     104:\tb.n\t104 <Reset+0x4>
     106:\tbmi.n\t1e4 <core::panicking::panic_fmt+0x4>

00000120 <main>:
     120:\tbl\t180 <<gait_control::controller::Controller>::tick::<X>>
     124:\tldr\tr0, [pc, #0]
     126:\tblx\tr0
     128:\t.word\t0x000001a1

00000140 <SysTick>:
{systick_body}
00000180 <<gait_control::controller::Controller>::tick::<X>>:
     180:\tbx\tlr

000001a0 <helper>:
     1a0:\tbx\tlr

000001c0 <core::panicking::panic_bounds_check>:
     1c0:\tbl\t1e0 <core::panicking::panic_fmt>

000001e0 <core::panicking::panic_fmt>:
     1e0:\tbl\t200 <__rustc::rust_begin_unwind>

00000200 <__rustc::rust_begin_unwind>:
     200:\tb.n\t200 <__rustc::rust_begin_unwind>
"
        )
    }

    const QUIET: &str = "     140:\tbx\tlr\n";

    #[test]
    fn the_vector_table_gives_the_roots_and_padding_is_no_call() {
        let g = CallGraph::parse(&disassembly(QUIET), VECTORS).unwrap();
        let roots: Vec<&str> = g.roots.iter().map(String::as_str).collect();
        assert_eq!(roots, ["Reset", "SysTick", "main"]);
        // `bmi.n` into the middle of panic_fmt is padding, not a call.
        assert!(!g.edges["Reset"].iter().any(|t| is_panic_entry(t)));
        // The literal pool's function address is an edge.
        assert!(g.edges["main"].contains("helper"));
        assert_eq!(g.indirect["main"], 1);
    }

    #[test]
    fn panic_code_nobody_reaches_directly_still_fails() {
        let g = CallGraph::parse(&disassembly(QUIET), VECTORS).unwrap();
        let e = check_graph(&g).err().unwrap();
        assert!(e.contains("panic code is left"), "{e}");
        assert!(e.contains("panic_bounds_check"), "{e}");
    }

    #[test]
    fn a_panic_in_an_exception_handler_is_found_with_its_chain() {
        let body = "     140:\tbl\t1c0 <core::panicking::panic_bounds_check>\n";
        let g = CallGraph::parse(&disassembly(body), VECTORS).unwrap();
        let e = check_graph(&g).err().unwrap();
        assert!(e.contains("reachable from the entry points"), "{e}");
        assert!(
            e.contains("SysTick\n -> core::panicking::panic_bounds_check"),
            "{e}"
        );
    }

    #[test]
    fn an_image_without_panic_code_passes() {
        let text = disassembly(QUIET);
        // The same image with the panic functions gone (headers only
        // matched: Reset's padding still names one).
        let clean: Vec<&str> = text
            .split("\n\n")
            .filter(|f| {
                let header = f.trim_start().lines().next().unwrap_or_default();
                !header.contains("core::panicking") && !header.contains(PANIC_HANDLER)
            })
            .collect();
        let g = CallGraph::parse(&clean.join("\n\n"), VECTORS).unwrap();
        let r = check_graph(&g).unwrap();
        assert_eq!(r.functions, 5);
        assert_eq!(r.indirect_calls, 1);
    }

    #[test]
    fn a_vector_into_the_middle_of_a_function_is_refused() {
        let bad = VECTORS.replace("41010000", "45010000");
        let e = CallGraph::parse(&disassembly(QUIET), &bad).err().unwrap();
        assert!(e.contains("0x00000145"), "{e}");
    }
}
