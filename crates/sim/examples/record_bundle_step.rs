//! Writes the recording of a patient bundle's first step that the QEMU
//! image replays (`sim::replay::record_bundle_step`):
//! `cargo run -p sim --example record_bundle_step -- <bundle> <file>`.
//! `cargo xtask qemu --bundle` runs it. Exit 2 when the bundle is refused.
#![allow(missing_docs)]

use std::process::ExitCode;

use gait_core::bundle::Bundle;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [bundle_path, out] = args.as_slice() else {
        eprintln!("usage: record_bundle_step <bundle> <file>");
        return ExitCode::from(2);
    };
    let device = match exogait_device::DeviceConfig::exogait() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("device configuration refused: {e:?}");
            return ExitCode::FAILURE;
        }
    };
    let bytes = match std::fs::read(bundle_path) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("{bundle_path}: {e}");
            return ExitCode::from(2);
        }
    };
    let bundle = match Bundle::parse(&bytes, device.fingerprint()) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("{bundle_path}: bundle refused: {e}");
            return ExitCode::from(2);
        }
    };
    let fitted = match device.fitted(&bundle.patient().model) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("{bundle_path}: patient model: {e}");
            return ExitCode::from(2);
        }
    };
    let recording = match sim::replay::record_bundle_step(&fitted, &bundle, 1) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("recording failed: {e:?}");
            return ExitCode::FAILURE;
        }
    };
    let file = sim::replay::encode(std::slice::from_ref(&recording));
    if let Err(e) = std::fs::write(out, &file) {
        eprintln!("cannot write {out}: {e}");
        return ExitCode::FAILURE;
    }
    println!(
        "recorded one step of the bundle's first gait, {} ticks, {} bytes: {out}",
        recording.ticks.len(),
        file.len()
    );
    ExitCode::SUCCESS
}
