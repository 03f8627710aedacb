//! The e-stop's stop (part of *guard*): category 0 (IEC 60204-1) but in
//! a swing, where it is category 1. Standing or in a weight transfer both
//! feet are down, and the drives are disabled at once: their dynamic
//! brakes hold the joints. In a swing the foot is in the air, and a body
//! braked stiff on one leg tips over it (a stair descent's mid-swing fell
//! so, `docs/safety.md`): the drives first set the swing foot down, as the
//! safe hold does, and are disabled once its sensor feels the ground, or
//! after `SequencerConfig::set_down_s` (0.8 s) whatever happens. Every
//! other check stays armed meanwhile: a joint whose drive a fault brakes
//! stays braked.

use crate::faults::{InSwing, Reaction};
use crate::posture::JOINTS;
use crate::sequencer::Phase;
use crate::supervisor::Verdict;

use super::Controller;

/// Where the e-stop's stop is.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct EStopStop {
    /// The e-stop has been seen since it last cleared.
    seen: bool,
    /// Ticks left for the swing foot's set-down before the drives are
    /// disabled (0: none under way).
    set_down_ticks: u16,
}

/// The longest set-down the e-stop allows, ticks (5 s at 1 kHz; the
/// configured `set_down_s` is far shorter).
const MAX_SET_DOWN_TICKS: f32 = 5000.0;

impl Controller<'_> {
    /// Turns the verdict's `DisableMotors` into a safe hold while the
    /// e-stop's set-down of a swing foot lasts (see the module
    /// documentation); the hold starts, with its set-down, on the tick the
    /// e-stop is first seen in a swing.
    pub(super) fn stop_for_estop(&mut self, verdict: &mut Verdict, measured: &[f32; JOINTS]) {
        if verdict.reaction != Reaction::DisableMotors {
            self.estop = EStopStop::default();
            return;
        }
        if !self.estop.seen {
            self.estop.seen = true;
            if matches!(self.seq.phase(), Phase::Swing { .. }) {
                self.seq.enter_safe_hold(measured, InSwing::HoldNow);
                let ticks = self.cfg.sequencer.set_down_s / self.cfg.dt_s;
                self.estop.set_down_ticks = if ticks.is_finite() {
                    ticks.clamp(0.0, MAX_SET_DOWN_TICKS) as u16
                } else {
                    0
                };
            }
        }
        if self.estop.set_down_ticks > 0 && self.seq.set_down_pending() {
            self.estop.set_down_ticks -= 1;
            verdict.reaction = Reaction::SafeHold;
        } else {
            self.estop.set_down_ticks = 0;
        }
    }
}
