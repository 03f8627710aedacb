//! The e-stop's stop (part of *guard*): category 0 (IEC 60204-1) but in
//! a swing, where it is category 1. Standing or in a weight transfer both
//! feet are down, and the drives are disabled at once: their dynamic
//! brakes hold the joints. In a swing the foot is in the air, and a body
//! braked stiff on one leg tips over it (a stair descent's mid-swing fell
//! so, `docs/safety.md`): the drives first set the swing foot down, as the
//! safe hold does (or go on with a safe hold's set-down already under
//! way), and are disabled once its sensor feels the ground, or after
//! `SequencerConfig::set_down_s` (0.8 s; 1 s at most whatever the
//! configuration) whatever happens. Every other check stays armed
//! meanwhile: a joint whose drive a fault brakes stays braked. Drives
//! already off stay off.

use crate::faults::Reaction;
use crate::sequencer::SeqStatus;
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

/// The longest set-down the e-stop allows whatever the configuration,
/// s (the configured `set_down_s` is 0.8).
const MAX_SET_DOWN_S: f32 = 1.0;

impl Controller<'_> {
    /// Turns the verdict's `DisableMotors` into a safe hold while the
    /// e-stop's set-down of a swing foot lasts (see the module
    /// documentation): from the tick the e-stop is first seen, in a swing
    /// (the hold and its set-down start then) or in a safe hold whose
    /// set-down is under way (it goes on), with the drives on. Never turns
    /// a drive on: with the drives off the e-stop disables at once.
    /// `status`: the sequencer's after this tick's update. Returns whether
    /// the sequencer is to hold now and begin the set-down.
    pub(super) fn stop_for_estop(&mut self, verdict: &mut Verdict, status: &SeqStatus) -> bool {
        if verdict.reaction != Reaction::DisableMotors {
            self.estop = EStopStop::default();
            return false;
        }
        let mut hold = false;
        // A hold struck in a swing begins its set-down (the controller's
        // sequencer always has the model it needs).
        let mut set_down_pending = status.set_down_pending();
        if !self.estop.seen {
            self.estop.seen = true;
            if self.motors_enabled && status.swinging() {
                hold = true;
                set_down_pending = true;
            }
            if self.motors_enabled && set_down_pending {
                let s = self.cfg.sequencer.set_down_s.min(MAX_SET_DOWN_S);
                let ticks = s / self.cfg.dt_s;
                self.estop.set_down_ticks = if ticks.is_finite() {
                    ticks.clamp(0.0, f32::from(u16::MAX)) as u16
                } else {
                    0
                };
            }
        }
        if self.estop.set_down_ticks > 0 && self.motors_enabled && set_down_pending {
            self.estop.set_down_ticks -= 1;
            verdict.reaction = Reaction::SafeHold;
        } else {
            self.estop.set_down_ticks = 0;
        }
        hold
    }
}
