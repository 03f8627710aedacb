//! Writes the recording of a patient bundle's first step that the QEMU
//! image replays (`sim::replay::record_bundle_step`):
//! `cargo run -p sim --example record_bundle_step -- <bundle> <file>`.
//! `cargo xtask qemu --bundle` runs it. Exit 2 when the bundle is refused.
#![allow(missing_docs)]

mod recording;

use std::process::ExitCode;

use gait_core::bundle::Bundle;
use recording::Stop;

fn main() -> ExitCode {
    recording::finish(run())
}

fn run() -> Result<String, Stop> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [bundle_path, out] = args.as_slice() else {
        return Err(Stop::refused(
            "usage: record_bundle_step <bundle> <file>".into(),
        ));
    };
    let device = recording::device()?;
    let bytes =
        std::fs::read(bundle_path).map_err(|e| Stop::refused(format!("{bundle_path}: {e}")))?;
    let bundle = Bundle::parse(&bytes, device.fingerprint())
        .map_err(|e| Stop::refused(format!("{bundle_path}: bundle refused: {e}")))?;
    let fitted = device
        .fitted(&bundle.patient().model)
        .map_err(|e| Stop::refused(format!("{bundle_path}: patient model: {e}")))?;
    let step = sim::replay::record_bundle_step(&fitted, &bundle, 1)
        .map_err(|e| Stop::failed(format!("recording failed: {e:?}")))?;
    let size = recording::write(out, std::slice::from_ref(&step))?;
    Ok(format!(
        "recorded one step of the bundle's first gait, {} ticks, {size} bytes: {out}",
        step.ticks.len()
    ))
}
