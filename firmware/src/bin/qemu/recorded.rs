//! The QEMU image's replay of the ticks recorded in the simulator
//! (`firmware::tick_replay`): each tick's instructions by phase, the model
//! task's between them and the acquisitions' before them, and how far the
//! target's motor commands are from the host's.

use core::hint::black_box;

use cortex_m::peripheral::SYST;
use firmware::{board_config, tick_replay};

use crate::{INSTR_PER_TICK, InstrCounter, Out, SYST_MAX, device_error, line};

/// Replays the ticks recorded in the simulator (`firmware::tick_replay`)
/// and prints, per phase, `tick: phase=<name> avg=<instructions>
/// worst=<instructions> ticks=<n>`, then how far the target's motor
/// commands are from the host's. xtask checks the budget and the bound.
pub(crate) fn check(out: &mut Out, ctr: &mut InstrCounter) -> usize {
    let device = match board_config::device() {
        Ok(d) => d,
        Err(e) => {
            let mut l = line("FAIL replay: device configuration refused: ");
            device_error(&mut l, &e);
            out.put(&mut l);
            return 1;
        }
    };
    let base = ctr.once(|| black_box(0u32)).0;
    let result = tick_replay::replay(
        &device,
        |tick| {
            let (instr, report) = ctr.once(tick);
            (instr.saturating_sub(base), report)
        },
        |model| {
            let start = SYST::get_current();
            model();
            let ticks = start.wrapping_sub(SYST::get_current()) & SYST_MAX;
            ticks.saturating_mul(INSTR_PER_TICK).saturating_sub(base)
        },
    );
    match result {
        Ok(r) if r.segments == 0 => {
            out.put(&mut line(
                "tick: no recording built in (cargo xtask qemu records one)",
            ));
            0
        }
        Ok(r) => {
            print_phases(out, "tick: phase=", &r);
            out.put(
                line("model: between ticks avg=")
                    .u64(r.model.average())
                    .str(" worst=")
                    .u32(r.model.worst)
                    .str(" answers=")
                    .u32(r.model.ticks),
            );
            out.put(
                line("acquisition: before ticks avg=")
                    .u64(r.acquisition.average())
                    .str(" worst=")
                    .u32(r.acquisition.worst)
                    .str(" (the rig's parts, frame by frame in the DMA's order; DMA on the board)"),
            );
            out.put(
                line("tick: replayed runs=")
                    .u32(r.segments)
                    .str(" ticks=")
                    .u32(r.ticks)
                    .str(" max_command_diff_nm=")
                    .exp(r.max_command_diff_nm)
                    .str(" differing_ticks=")
                    .u32(r.differing_ticks),
            );
            if let Some((run, tick, target, host)) = r.first_differing {
                let mut l = line("tick: first differing: run=");
                l.u32(run).str(" tick=").u32(tick).str(" target/host N·m:");
                for (t, h) in target.iter().zip(&host) {
                    l.str(" ").exp(*t).str("/").exp(*h);
                }
                out.put(&mut l);
            }
            0
        }
        Err(e) => {
            out.put(&mut line(match e {
                tick_replay::ReplayError::File(exogait_device::tick_record::FileError::Header) => {
                    "FAIL replay: the recording's header is bad"
                }
                tick_replay::ReplayError::File(exogait_device::tick_record::FileError::Segment) => {
                    "FAIL replay: a segment of the recording is bad"
                }
                tick_replay::ReplayError::Config => {
                    "FAIL replay: the controller or its drivers were refused"
                }
            }));
            1
        }
    }
}

/// Prints a replay's phases, one line each starting with `prefix`:
/// `<prefix><name> avg=<n> worst=<n> ticks=<n> worst_at=<run>:<tick>`.
pub(crate) fn print_phases(out: &mut Out, prefix: &str, r: &tick_replay::Replay) {
    for (name, p) in tick_replay::PHASES.iter().zip(r.phases) {
        if p.ticks > 0 {
            out.put(
                line(prefix)
                    .str(name)
                    .str(" avg=")
                    .u64(p.average())
                    .str(" worst=")
                    .u32(p.worst)
                    .str(" ticks=")
                    .u32(p.ticks)
                    .str(" worst_at=")
                    .u32(p.worst_at.0)
                    .str(":")
                    .u32(p.worst_at.1),
            );
        }
    }
}
