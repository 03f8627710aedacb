//! Writes the tick recording the QEMU image replays (`sim::replay`):
//! `cargo run -p sim --example record_ticks -- <file>`. `cargo xtask qemu`
//! runs it before building the QEMU image.
#![allow(missing_docs)]

mod recording;

use std::process::ExitCode;

use recording::Stop;

fn main() -> ExitCode {
    recording::finish(run())
}

fn run() -> Result<String, Stop> {
    let Some(path) = std::env::args().nth(1) else {
        return Err(Stop::refused("usage: record_ticks <file>".into()));
    };
    let device = recording::device()?;
    let recordings = sim::replay::record_gaits(&device)
        .map_err(|e| Stop::failed(format!("recording failed: {e:?}")))?;
    let bytes = recording::write(&path, &recordings)?;
    let ticks: usize = recordings.iter().map(|r| r.ticks.len()).sum();
    Ok(format!(
        "recorded {} runs, {ticks} ticks, {bytes} bytes: {path}",
        recordings.len()
    ))
}
