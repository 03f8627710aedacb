//! Writes the tick recording the QEMU image replays (`sim::replay`):
//! `cargo run -p sim --example record_ticks -- <file>`. `cargo xtask qemu`
//! runs it before building the QEMU image.
#![allow(missing_docs)]

use std::process::ExitCode;

fn main() -> ExitCode {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: record_ticks <file>");
        return ExitCode::from(2);
    };
    let device = match exogait_device::DeviceConfig::exogait() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("device configuration refused: {e:?}");
            return ExitCode::FAILURE;
        }
    };
    let recordings = match sim::replay::record_gaits(&device) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("recording failed: {e:?}");
            return ExitCode::FAILURE;
        }
    };
    let bytes = sim::replay::encode(&recordings);
    if let Err(e) = std::fs::write(&path, &bytes) {
        eprintln!("cannot write {path}: {e}");
        return ExitCode::FAILURE;
    }
    let ticks: usize = recordings.iter().map(|r| r.ticks.len()).sum();
    println!(
        "recorded {} runs, {ticks} ticks, {} bytes: {path}",
        recordings.len(),
        bytes.len()
    );
    ExitCode::SUCCESS
}
