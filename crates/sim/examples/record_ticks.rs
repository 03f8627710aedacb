//! Writes the tick recordings the QEMU image replays (`sim::replay`):
//! `cargo run -p sim --example record_ticks -- <file> <replanning-file>`,
//! the gaits' runs and the run with the idle-time re-planner on. `cargo
//! xtask qemu` runs it before building the QEMU image.
#![allow(missing_docs)]

mod recording;

use std::process::ExitCode;

use recording::Stop;

/// Steps of the re-planning run: two re-planned steps.
const REPLANNING_STEPS: usize = 2;

fn main() -> ExitCode {
    recording::finish(run())
}

fn run() -> Result<String, Stop> {
    let (Some(path), Some(replanning_path)) = (std::env::args().nth(1), std::env::args().nth(2))
    else {
        return Err(Stop::refused(
            "usage: record_ticks <file> <replanning-file>".into(),
        ));
    };
    let device = recording::device()?;
    let recordings = sim::replay::record_gaits(&device)
        .map_err(|e| Stop::failed(format!("recording failed: {e:?}")))?;
    let bytes = recording::write(&path, &recordings)?;
    let ticks: usize = recordings.iter().map(|r| r.ticks.len()).sum();
    let (replanning, replans) = sim::replay::record_replanning(&device, REPLANNING_STEPS)
        .map_err(|e| Stop::failed(format!("recording the re-planning run failed: {e:?}")))?;
    let used = replans
        .iter()
        .filter(|r| r.answer.outcome == gait_control::replan::ReplanOutcome::Replanned)
        .count();
    let replanning_bytes = recording::write(&replanning_path, std::slice::from_ref(&replanning))?;
    Ok(format!(
        "recorded {} runs, {ticks} ticks, {bytes} bytes: {path}\n\
         recorded the re-planning run, {} ticks, {} re-plans ({used} re-planned), \
         {replanning_bytes} bytes: {replanning_path}",
        recordings.len(),
        replanning.ticks.len(),
        replans.len(),
    ))
}
