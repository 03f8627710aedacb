//! The board's idle-time re-planner in the simulation: between two ticks
//! it takes the sequencer's request from the slot, re-plans the step as the
//! board does ([`exogait_device::replan::replan`]), and publishes the
//! answer once the idle time the board would have spent on it has passed
//! ([`exogait_device::replan::Answer::ticks`]): the answer reaches the
//! sequencer on the tick it would on the board.

use exogait_device::DeviceConfig;
use exogait_device::replan::{Answer, REPLAN, evals_within, replan};
use gait_control::replan::{REPLAN_CAPACITY, ReplanOutcome, ReplanSlot, Ticket};
use gait_control::sequencer::GaitTables;

use crate::closed_loop::Rig;
use crate::inject::Kind;

/// One re-plan: when it was asked for, when the board would have had it,
/// and what it came to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReplanRecord {
    /// Tick of the request.
    pub asked_at: u64,
    /// Tick after which the answer is in the slot.
    pub ready_at: u64,
    /// The answer.
    pub answer: Answer,
}

/// The simulated board's idle-time task.
#[derive(Debug)]
pub(crate) struct SimReplanner<'t> {
    slot: &'t ReplanSlot,
    pending: Option<(u64, Ticket, Answer)>,
    buffer: Vec<[f32; 5]>,
    /// Every re-plan so far.
    pub(crate) log: Vec<ReplanRecord>,
    /// An injected failure of the next re-plan: no answer in time
    /// (`replan-timeout`) or the admission check's refusal
    /// (`replan-refused`).
    pub(crate) sabotage: Option<Kind>,
}

impl<'t> SimReplanner<'t> {
    pub(crate) fn new(slot: &'t ReplanSlot) -> Self {
        Self {
            slot,
            pending: None,
            buffer: vec![[0.0; 5]; REPLAN_CAPACITY],
            log: Vec::new(),
            sabotage: None,
        }
    }

    pub(crate) const fn slot(&self) -> &'t ReplanSlot {
        self.slot
    }

    /// The idle time after tick `now`.
    pub(crate) fn idle(&mut self, now: u64, device: &DeviceConfig, tables: &GaitTables<'_>) {
        if let Some((request, ticket)) = self.slot.take_request() {
            let len = tables
                .slot(usize::from(request.slot))
                .map_or(0, |t| t.len());
            let max_evals = evals_within(REPLAN.latency_ticks, len);
            let mut answer = replan(device, tables, &request, &mut self.buffer, max_evals);
            let mut ready_at = now + answer.ticks();
            match self.sabotage.take() {
                Some(Kind::ReplanTimeout) => ready_at = u64::MAX,
                Some(Kind::ReplanRefused) => answer.outcome = ReplanOutcome::Refused,
                _ => {}
            }
            self.log.push(ReplanRecord {
                asked_at: now,
                ready_at,
                answer,
            });
            self.pending = Some((ready_at, ticket, answer));
        }
        if let Some((ready_at, ticket, answer)) = self.pending
            && now + 1 >= ready_at
        {
            self.pending = None;
            let samples = self.buffer.get(..answer.samples).unwrap_or(&[]);
            // Withdrawn meanwhile: nothing is published.
            let _ = self.slot.publish(ticket, answer.outcome, samples);
        }
    }
}

impl<'t> Rig<'t> {
    /// Runs the board's idle-time re-planner on `slot` (the controller
    /// asks it before each step) from the next tick on.
    pub fn replan_with(&mut self, slot: &'t ReplanSlot) {
        self.controller.set_replanner(slot, REPLAN);
        self.replanner = Some(SimReplanner::new(slot));
    }

    /// Every re-plan so far (none without a re-planner).
    pub fn replans(&self) -> &[ReplanRecord] {
        self.replanner.as_ref().map_or(&[], |r| r.log.as_slice())
    }
}
