//! Standing and waiting for the pilot: a gait starts only from the
//! standing posture it was planned from (within a tolerance), only with a
//! verified table, never while a step is in progress; the swing begins
//! once the pilot is ready (both crutches loaded, weight on the feet, the
//! stance shank at the table's planned lean).

use gait_core::kinematics::Posture;

use crate::posture::{Side, joints_from_phi};

use super::{
    JOINTS, Phase, RefuseReason, Selection, Sensed, SeqEvent, SeqEvents, Sequencer, gait_of_kind,
};

impl Sequencer<'_> {
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
        events: &mut SeqEvents,
    ) -> [f32; JOINTS] {
        if self.stop_requested {
            self.phase = Phase::Standing;
            events.push(SeqEvent::Stopped);
            self.blend_to
        } else if self.ready(sensed, stance) {
            self.phase = Phase::Swing { stance, t_s: 0.0 };
            let start = self.table.as_ref().map(|tb| tb.at_time(0.0));
            let start_m = self
                .planned_swing_toe(start.map(|p| Posture::new(&p)).as_ref())
                .unwrap_or([0.0; 2]);
            let lands_first_from_s = self.lands_first_from_s();
            self.swing.begin(start_m, lands_first_from_s);
            events.push(SeqEvent::SwingStarted(self.gait, stance));
            start.map_or(self.reference, |p| joints_from_phi(&p, stance))
        } else {
            self.blend_to
        }
    }

    fn ready(&self, sensed: &Sensed, stance: Side) -> bool {
        let c = self.cfg;
        let crutches = sensed.crutches_n.iter().all(|&f| f >= c.crutch_ready_n);
        // A NaN (faulted sensor) makes the sum NaN: never ready.
        let [left, right] = sensed.feet_n;
        let foot = left + right >= c.feet_ready_n;
        let planned = self.table.as_ref().map(|t| t.first()[0]);
        let ankle = match (planned, sensed.ankles_rad.get(stance.ankle())) {
            (Some(p), Some(&a)) => (a - p).abs() <= c.start_ankle_tolerance_rad,
            _ => false,
        };
        crutches && foot && ankle
    }
}
