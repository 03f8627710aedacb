//! Standing and waiting for the pilot: a gait starts only from the
//! standing posture it was planned from (within a tolerance), only with a
//! verified table, never while a step is in progress; the swing begins
//! once the pilot is ready (both crutches loaded, weight on the feet, the
//! stance shank at the table's planned lean).

use crate::ahead::AheadSlot;
use crate::posture::{Side, joints_from_phi};

use crate::replan::{ReplanOutcome, ReplanRequest, ReplanResult, SlotView};

use super::{
    JOINTS, Phase, RefuseReason, Selection, Sensed, SeqEvent, SeqEvents, Sequencer, StepTable,
    gait_of_kind,
};

impl<'t> Sequencer<'t> {
    /// A start of the `selected` gait: accepted only when standing, with a
    /// verified table, from that table's start posture (either leg may be
    /// the stance leg: the one whose mapping matches is chosen).
    pub(super) fn request_start(&mut self, selected: impl Selection, sensed: &Sensed) -> SeqEvent {
        if self.phase != Phase::Standing || self.new_steps_blocked {
            return SeqEvent::StartRefused(RefuseReason::Busy);
        }
        let Some((slot, table)) = selected
            .slot_in(&self.tables)
            .and_then(|i| Some((i, *self.tables.slot(i)?)))
        else {
            return SeqEvent::StartRefused(RefuseReason::NoTable);
        };
        let gait = gait_of_kind(table.kind());
        let first = table.first();
        let tol = self.cfg.start_tolerance_rad;
        for stance in [self.stance, self.stance.other()] {
            let start = joints_from_phi(&first, stance);
            let close = start
                .iter()
                .zip(&sensed.joints_rad)
                .all(|(a, b)| (a - b).abs() <= tol);
            if close {
                self.withdraw_replan();
                self.gait = gait;
                self.slot = slot;
                self.table = Some(table);
                self.stance = stance;
                self.stop_requested = false;
                self.begin_blend(start);
                self.phase = Phase::WaitingReady { stance };
                return SeqEvent::StartAccepted(gait, stance);
            }
        }
        SeqEvent::StartRefused(RefuseReason::NotInStartPosture)
    }

    /// A tick waiting for the pilot: stop if asked, begin the swing once
    /// ready, else hold the start posture.
    pub(super) fn wait_ready(
        &mut self,
        sensed: &Sensed,
        stance: Side,
        dt_s: f32,
        ahead: Option<&AheadSlot>,
        events: &mut SeqEvents,
    ) -> [f32; JOINTS] {
        if self.stop_requested {
            self.withdraw_replan();
            self.phase = Phase::Standing;
            events.push(SeqEvent::Stopped);
            return self.blend_to;
        }
        let Some(step) = self.step_to_start(sensed, stance, events) else {
            return self.blend_to;
        };
        self.step = Some(step);
        // The generator measured the gait's figure on its table's step; a
        // re-planned step is checked against the device's limit.
        self.stance_hip_residual_nm = match step {
            StepTable::Planned(table) => table.stance_hip_residual_nm(),
            StepTable::Replanned { .. } => f32::NAN,
        };
        self.phase = Phase::Swing { stance, t_s: 0.0 };
        let start = step.at_time(0.0);
        let lands_first_from_s = self.lands_first_from_s();
        self.swing.begin(lands_first_from_s, start[0]);
        if let Some(slot) = ahead {
            self.ask_swing(slot, dt_s);
        }
        events.push(SeqEvent::SwingStarted(self.gait, stance));
        joints_from_phi(&start, stance)
    }

    /// The step to start now, if the pilot is ready: both crutches loaded,
    /// the feet carrying the body, and the stance ankle at the table's
    /// planned lean (within `start_ankle_tolerance_rad`). With a
    /// re-planner, an ankle off the plan by more than its
    /// `min_offset_rad` (and up to its `ankle_tolerance_rad`) has the
    /// step re-planned from where it is, which starts once the answer is
    /// due.
    fn step_to_start(
        &mut self,
        sensed: &Sensed,
        stance: Side,
        events: &mut SeqEvents,
    ) -> Option<StepTable<'t>> {
        let c = self.cfg;
        let table = self.table?;
        let crutches = sensed.crutches_n.iter().all(|&f| f >= c.crutch_ready_n);
        // A NaN (faulted sensor) makes the sum NaN: never ready.
        let [left, right] = sensed.feet_n;
        let loaded = crutches && left + right >= c.feet_ready_n;
        let ankle = sensed
            .ankles_rad
            .get(stance.ankle())
            .copied()
            .unwrap_or(f32::NAN);
        let off = (ankle - table.first()[0]).abs();
        let planned =
            (loaded && off <= c.start_ankle_tolerance_rad).then_some(StepTable::Planned(table));
        let Some((slot, rc)) = self.replanner else {
            return planned;
        };
        if !loaded {
            self.withdraw_replan();
            return None;
        }
        match self.replan_wait {
            // On the plan: the table, at once.
            None if off <= rc.min_offset_rad => planned,
            None => {
                // NaN off: no request.
                if off <= rc.ankle_tolerance_rad {
                    slot.request(&ReplanRequest {
                        slot: u8::try_from(self.slot).unwrap_or(u8::MAX),
                        stance,
                        phi1_rad: ankle,
                        joints_rad: sensed.joints_rad,
                        persist: rc.persist,
                    });
                    self.replan_from = ankle;
                    self.replan_wait = Some(0);
                }
                None
            }
            Some(n) if n.saturating_add(1) < rc.latency_ticks => {
                self.replan_wait = Some(n + 1);
                None
            }
            Some(_) => {
                self.replan_wait = None;
                let result = match slot.view() {
                    SlotView::Done(outcome) => ReplanResult::Answered(outcome),
                    SlotView::Pending => ReplanResult::Late,
                };
                events.push(SeqEvent::Replan(result));
                let still = (ankle - self.replan_from).abs() <= rc.ankle_drift_rad;
                if result == ReplanResult::Answered(ReplanOutcome::Replanned) && still {
                    if let Some(len) = slot.take() {
                        // It starts from the posture measured at the
                        // request, not the held one: the reference moves
                        // there in this tick with no rate (the difference
                        // is the joints' tracking error, not a motion).
                        if let Some(first) = slot.sample(0) {
                            self.reference = joints_from_phi(&first, stance);
                        }
                        return Some(StepTable::Replanned { slot, len, table });
                    }
                }
                slot.release();
                // The table, where the ankle allows it; else asked again
                // from where the ankle is then.
                planned
            }
        }
    }

    /// Withdraws a re-plan asked for and not yet started.
    pub(super) fn withdraw_replan(&mut self) {
        if let (Some(_), Some((slot, _))) = (self.replan_wait.take(), self.replanner) {
            slot.release();
        }
    }
}
