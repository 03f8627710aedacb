//! Picks the memory layout for the board being built and passes the link
//! scripts, so host builds and `.cargo/config.toml` never carry them.
//!
//! cortex-m-rt's `link.x` says `INCLUDE memory.x`, and linkers look in their
//! working directory before the `-L` paths. Cargo links from this crate's
//! workspace root (firmware/, a workspace of its own), which holds no
//! memory.x, so the copy written to OUT_DIR here is always the one used: the
//! top-level memory.x for the STM32 board, qemu/memory.x for QEMU.
// A build script runs on the host at build time, never on the board: failing
// loudly here is the right reaction to a broken checkout.
#![allow(clippy::expect_used, clippy::panic)]

use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let qemu = env::var_os("CARGO_FEATURE_QEMU").is_some();
    let stm32 = env::var_os("CARGO_FEATURE_BOARD_STM32F405").is_some();
    if qemu && stm32 {
        panic!("features `qemu` and `board-stm32f405` are exclusive: build one board at a time");
    }
    let layout = if qemu {
        manifest.join("qemu/memory.x")
    } else {
        manifest.join("../memory.x")
    };
    fs::copy(&layout, out.join("memory.x")).expect("copy memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", layout.display());
    println!("cargo:rerun-if-changed=build.rs");
    // The QEMU image's tick replay (`tick_replay`): the recording xtask
    // names, or nothing to replay.
    // Likewise the run it replays with the idle-time re-planner on.
    for (var, name) in [
        ("EXOGAIT_TICK_RECORDS", "tick_records.bin"),
        ("EXOGAIT_REPLANNING_RECORDS", "replanning_records.bin"),
    ] {
        println!("cargo:rerun-if-env-changed={var}");
        let records = out.join(name);
        match env::var_os(var) {
            Some(path) if qemu => {
                println!("cargo:rerun-if-changed={}", PathBuf::from(&path).display());
                fs::copy(&path, &records).expect("copy the tick recording");
            }
            _ => fs::write(&records, []).expect("write an empty tick recording"),
        }
    }
    let target = env::var("TARGET").unwrap_or_default();
    if target.starts_with("thumb") {
        println!("cargo:rustc-link-arg-bins=--nmagic");
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
        if stm32 {
            println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
        }
    }
}
