//! The board's second priority: the step re-planner, run in the time the
//! 1 kHz tick leaves free. Both images schedule the same way:
//!
//! | priority | context | work |
//! |---|---|---|
//! | high | the tick timer's interrupt | one control tick (`Controller::tick`), every 1 ms |
//! | low | thread mode (`main`'s loop) | [`IdleReplanner::serve`] when the sequencer asked, else `WFI` |
//!
//! The tick preempts the re-planner whenever its period comes round, and
//! the two share only the [`ReplanSlot`], whose words are atomics: the tick
//! never waits and takes no lock. The sequencer reads the answer a fixed
//! latency after asking (`ReplanConfig::latency_ticks`); an answer not
//! published by then is late (fault 0x0606) and the step plays its table.

use exogait_device::DeviceConfig;
use exogait_device::replan::{Answer, REPLAN, evals_within, replan};
use gait_control::replan::{REPLAN_CAPACITY, ReplanSlot};
use gait_control::sequencer::GaitTables;
use gait_core::LINKS;

/// The re-planner's side of the slot, with its own sample buffer (what it
/// works on until it publishes).
pub struct IdleReplanner<'t> {
    slot: &'t ReplanSlot,
    device: DeviceConfig,
    tables: GaitTables<'t>,
    buffer: [[f32; LINKS]; REPLAN_CAPACITY],
}

impl<'t> IdleReplanner<'t> {
    /// Over `slot`, for the controller running `device` with `tables`
    /// (the same ones: a request names a table by its slot).
    #[must_use]
    pub const fn new(slot: &'t ReplanSlot, device: DeviceConfig, tables: GaitTables<'t>) -> Self {
        Self {
            slot,
            device,
            tables,
            buffer: [[0.0; LINKS]; REPLAN_CAPACITY],
        }
    }

    /// Works on the request waiting in the slot, if there is one, in the
    /// evaluations the latency's idle time buys; publishes the answer (not
    /// if the tick withdrew the request meanwhile). `None`: nothing asked.
    pub fn serve(&mut self) -> Option<Answer> {
        let (request, ticket) = self.slot.take_request()?;
        let len = self
            .tables
            .slot(usize::from(request.slot))
            .map_or(0, |t| t.len());
        let max_evals = evals_within(REPLAN.latency_ticks, len);
        let answer = replan(
            &self.device,
            &self.tables,
            &request,
            &mut self.buffer,
            max_evals,
        );
        let samples = self.buffer.get(..answer.samples).unwrap_or(&[]);
        let _ = self.slot.publish(ticket, answer.outcome, samples);
        Some(answer)
    }
}
