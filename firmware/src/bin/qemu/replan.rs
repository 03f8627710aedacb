//! The QEMU image's benchmark of the step re-planner as the board runs it
//! (`exogait_device::replan::replan`, admission check included): one
//! re-plan of each built-in gait for a pilot leaning 3° forward, in the
//! evaluations that fit in the sequencer's latency.
//!
//! Prints `replan: gait=<name> insns=<n> evals=<k> used=<replanned|table>
//! per_sample=<n>` and fails when one evaluation costs more per sample
//! than the device's cost model assumes (`INSTRUCTIONS_PER_SAMPLE`: the
//! simulator schedules the re-planner's answer by it), or a re-plan more
//! than 0.5 s of the 168 MHz core.

use exogait_device::replan::{INSTRUCTIONS_PER_SAMPLE, REPLAN, evals_within, replan};
use firmware::board_config;
use gait_control::posture::{Side, joints_from_phi};
use gait_control::replan::{REPLAN_CAPACITY, ReplanOutcome, ReplanRequest};

use crate::{InstrCounter, Out, checked, line};

/// 0.5 s of the 168 MHz core.
const MAX_INSTRUCTIONS: u64 = 84_000_000;
/// The pilot's lean over the tables' start, rad (3°).
const LEAN_RAD: f32 = 0.052_359_88;

/// Runs the benchmark; returns the number of failures.
pub(crate) fn check(out: &mut Out, ctr: &mut InstrCounter) -> usize {
    let Ok(device) = board_config::device() else {
        out.put(&mut line("FAIL replan: device configuration refused"));
        return 1;
    };
    let tables = board_config::flash_tables();
    let mut buffer = [[0.0f32; 5]; REPLAN_CAPACITY];
    let mut failed = 0;
    for (slot, name) in [(0u8, "walk"), (1, "stair-up"), (2, "stair-down")] {
        let Some(table) = tables.slot(usize::from(slot)).copied() else {
            continue;
        };
        let start = table.first();
        let request = ReplanRequest {
            slot,
            stance: Side::Left,
            phi1_rad: start[0] + LEAN_RAD,
            joints_rad: joints_from_phi(&start, Side::Left),
            persist: REPLAN.persist,
        };
        let max_evals = evals_within(REPLAN.latency_ticks, table.len());
        let (insns, answer) =
            ctr.once(|| replan(&device, &tables, &request, &mut buffer, max_evals));
        let work = u64::from(answer.evals) * table.len() as u64;
        let per_sample = u64::from(insns).checked_div(work).unwrap_or(0);
        let used = match answer.outcome {
            ReplanOutcome::Replanned => "replanned",
            ReplanOutcome::Declined | ReplanOutcome::Refused => "table",
        };
        let over = per_sample > INSTRUCTIONS_PER_SAMPLE || u64::from(insns) > MAX_INSTRUCTIONS;
        failed += usize::from(over);
        out.put(
            checked(over, "replan: gait=")
                .str(name)
                .str(" insns=")
                .u32(insns)
                .str(" evals=")
                .u32(u32::from(answer.evals))
                .str(" used=")
                .str(used)
                .str(" per_sample=")
                .u64(per_sample),
        );
    }
    failed
}
