//! The safe hold: the reference ramps to the posture measured when a fatal
//! fault struck and stays there until a clinician reset; a swing it
//! strikes in sets its foot down first (or, late in the swing, lands the
//! step: [`Sequencer::in_swing_now`](super::Sequencer)). The verdict's
//! orders ([`Orders`]) are obeyed here.

use crate::faults::InSwing;
use crate::posture::{Side, joints_from_phi};

use crate::ahead::AheadSlot;

use super::swing::SEARCH_MIN_KNEE_FLEXION_RAD;
use super::{JOINTS, Measured, Order, Orders, Phase, Sensed, Sequencer, pick_finite, smoothstep};

/// A swing foot being set down in a safe hold: from where its ankle was
/// when the hold struck, straight down, a point fixed in the world that
/// the swing leg's IK reaches from wherever the measured stance leg and
/// torso are, until the foot's sensor feels the ground.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct SetDown {
    /// The leg that carries the body.
    pub(super) stance: Side,
    /// The posture held (Φ, the stance shank as the table planned it).
    from: [f32; gait_core::LINKS],
    /// The hip and the swing ankle of `from` (stance foot's frame), m:
    /// worked out on the hold's first tick (the tick the fault struck has
    /// played a swing already, and has no room left for it).
    hip_and_ankle_m: Option<([f32; 2], [f32; 2])>,
    /// The swing hip and knee references (joint angles), rad: the IK's
    /// last answer, kept once the foot has found the ground.
    swing_rad: [f32; 2],
    /// The foot has found the ground (or its sensor cannot tell).
    pub(super) done: bool,
}

impl SetDown {
    /// The set-down of the swing leg from the posture `held` (joint
    /// angles), its stance shank at `phi1`.
    fn from_hold(held: &[f32; JOINTS], phi1: f32, stance: Side) -> Option<Self> {
        let w = stance.other().hip();
        Some(Self {
            stance,
            from: crate::posture::phi_from_joints(held, phi1, stance),
            hip_and_ankle_m: None,
            swing_rad: [held.get(w).copied()?, held.get(w + 1).copied()?],
            done: false,
        })
    }
}

impl Sequencer<'_> {
    /// The last verdict's orders, in the order the guard gave them: the
    /// e-stop's hold, the joints to hold where they are, the reaction.
    pub(super) fn obey(&mut self, orders: &Orders, braked: &[bool; JOINTS]) {
        if orders.order == Order::Carry && !orders.estop_hold && orders.rehold == [false; JOINTS] {
            return;
        }
        let measured = &orders.measured.joints_rad;
        if orders.estop_hold {
            self.enter_safe_hold(measured, InSwing::HoldNow);
        }
        for (i, (&re, &m)) in orders.rehold.iter().zip(measured).enumerate() {
            if re {
                self.rehold_joint(i, m);
            }
        }
        match orders.order {
            Order::Carry => {}
            Order::FinishStepThenHold => self.block_new_steps(),
            Order::HoldWhereFound => self.enter_safe_hold_after_restart(measured, &orders.measured),
            // Held already (every tick of a hold): nothing to decide.
            Order::SafeHold(_) if matches!(self.phase, Phase::SafeHold { .. }) => {}
            Order::SafeHold(asked) => {
                let in_swing = self.status().in_swing_now(asked, braked);
                self.enter_safe_hold(measured, in_swing);
            }
            Order::FollowMeasured => self.follow_measured(measured),
        }
    }

    /// The supervisor's non-fatal reaction: finish the step, then hold; no
    /// new steps until a reset.
    fn block_new_steps(&mut self) {
        self.new_steps_blocked = true;
        self.stop_requested = true;
    }

    /// A tick of the hold `t_s` into it: the ramp, with the set-down (its
    /// next tick's IK asked of the model task through `ahead`).
    pub(super) fn hold_tick(
        &mut self,
        sensed: &Sensed,
        t_s: f32,
        dt_s: f32,
        ahead: Option<&AheadSlot>,
    ) -> [f32; JOINTS] {
        let cfg = self.cfg;
        let t = t_s + dt_s;
        let frac = if cfg.hold_ramp_s > 0.0 {
            t / cfg.hold_ramp_s
        } else {
            1.0
        };
        self.phase = Phase::SafeHold {
            t_s: t.min(cfg.hold_ramp_s.max(cfg.set_down_s).max(0.0) + 1.0),
        };
        let mut held = self.blended(frac.min(1.0));
        self.set_down(sensed, t, dt_s, ahead, &mut held);
        self.level_torso(sensed, dt_s, &mut held);
        // The next tick's set-down, at its time as it will work it out.
        if let (Some(slot), Phase::SafeHold { t_s: now }, Some(sd)) =
            (ahead, self.phase, self.set_down)
        {
            if let (false, Some((hip_m, start_m))) = (sd.done, sd.hip_and_ankle_m) {
                let target = self.set_down_target(start_m, now + dt_s);
                slot.request_place(&sd.from, hip_m, target);
            }
        }
        held
    }

    /// Where the set-down puts the swing ankle `t_s` into the hold: the
    /// eased depth below where it was, m.
    fn set_down_target(&self, start_m: [f32; 2], t_s: f32) -> [f32; 2] {
        let cfg = &self.cfg;
        let frac = if cfg.set_down_s > 0.0 {
            t_s / cfg.set_down_s
        } else {
            1.0
        };
        let depth = cfg.set_down_depth_m * smoothstep(frac);
        [start_m[0], start_m[1] - depth]
    }

    /// The supervisor's fatal reaction: ramp to `measured` and hold; in a
    /// swing, first play the step to its landing if `in_swing` says so,
    /// otherwise set the swing foot down where it is while holding the
    /// rest ([`SequencerConfig::set_down_depth_m`]).
    fn enter_safe_hold(&mut self, measured: &[f32; JOINTS], in_swing: InSwing) {
        if matches!(self.phase, Phase::SafeHold { .. }) {
            return;
        }
        // A re-plan asked for is withdrawn: its answer must not start a
        // step after the hold.
        self.withdraw_replan();
        let swinging = match self.phase {
            Phase::Swing { stance, .. } => Some(stance),
            _ => None,
        };
        if swinging.is_some() && in_swing == InSwing::LandFirst {
            // A foot in the air is not a posture to hold: the step goes on
            // to its landing (sensed, or on the table's own timing when the
            // foot's sensor is lost), the sequencer stands there, and the
            // next call holds what it measures then.
            self.block_new_steps();
            return;
        }
        let target = pick_finite(measured, &self.reference);
        self.level_rad = 0.0;
        self.torso_at_brake = f32::NAN;
        self.blend_from = self.reference;
        self.blend_to = target;
        self.phase = Phase::SafeHold { t_s: 0.0 };
        self.set_down = swinging
            .filter(|_| self.model.is_some() && in_swing == InSwing::HoldNow)
            .and_then(|stance| SetDown::from_hold(&target, self.swing.phi1, stance));
    }

    /// The hold after a restart (0x0603): the step the board was playing is
    /// lost, so which foot is up is read from the feet's sensors. With one
    /// foot carrying a contact and the other not, the loaded one is the
    /// stance leg (the feed-forward's model, too) and the other is set down
    /// as after a fault in a swing, the stance shank from its ankle's
    /// reading; otherwise a hold of `measured` as [`Sequencer::enter_safe_hold`].
    fn enter_safe_hold_after_restart(&mut self, measured: &[f32; JOINTS], sensed: &Measured) {
        self.withdraw_replan();
        if matches!(self.phase, Phase::SafeHold { .. }) {
            return;
        }
        self.enter_safe_hold(measured, InSwing::HoldNow);
        let Some(stance) = super::input::restart_stance(sensed, self.cfg.landing_contact_n) else {
            return;
        };
        let phi1 = sensed
            .ankles_rad
            .get(stance.ankle())
            .copied()
            .unwrap_or(f32::NAN);
        if self.model.is_none() {
            return;
        }
        if let Some(sd) = SetDown::from_hold(&self.blend_to, phi1, stance) {
            self.stance = stance;
            self.set_down = Some(sd);
        }
    }

    /// The set-down `t_s` into the hold: `held` (the hold's ramp) with the
    /// swing hip and knee placing the ankle the eased depth below where it
    /// was in the posture held, while the swing foot's sensor reads less
    /// than a contact; from the first contact (or a sensor that cannot
    /// tell) on, where they were then. A contact (or such a sensor) on the
    /// hold's first tick drops the set-down: the leg ramps with the others.
    /// `held` itself without a set-down.
    fn set_down(
        &mut self,
        sensed: &Sensed,
        t_s: f32,
        dt_s: f32,
        ahead: Option<&AheadSlot>,
        held: &mut [f32; JOINTS],
    ) {
        let cfg = self.cfg;
        let (Some(mut sd), Some(model)) = (self.set_down, self.model.as_ref()) else {
            return;
        };
        let foot = sensed
            .feet_n
            .get(sd.stance.other().foot())
            .copied()
            .unwrap_or(f32::NAN);
        if foot >= cfg.landing_contact_n || !foot.is_finite() {
            if !sd.done && sd.hip_and_ankle_m.is_none() {
                // Carrying on the hold's first tick (early in a descent's
                // swing the trailing toe still lowers the body), or a
                // sensor that cannot tell: nothing to set down, and the
                // leg ramps to its hold as the others do. Held at once
                // where it was measured, its loaded knee lost the
                // reference's push in a tick and sank.
                self.set_down = None;
                return;
            }
            sd.done = true;
        }
        if !sd.done && sd.hip_and_ankle_m.is_none() {
            let [_, hip, _, _, ankle] = gait_core::kinematics::forward_kinematics(model, &sd.from);
            if hip.iter().chain(&ankle).all(|v| v.is_finite()) {
                sd.hip_and_ankle_m = Some((hip, ankle));
            } else {
                sd.done = true;
            }
        } else if let (false, Some((hip_m, start_m))) = (sd.done, sd.hip_and_ankle_m) {
            // Asked of the model task last tick (the same IK on the same
            // posture and target, bit for bit), else worked out now.
            let target = self.set_down_target(start_m, t_s);
            let placed = ahead
                .and_then(|slot| slot.placed(&sd.from, hip_m, target))
                .unwrap_or_else(|| {
                    gait_core::reach::place_swing_ankle_from(
                        model,
                        &sd.from,
                        hip_m,
                        target,
                        SEARCH_MIN_KNEE_FLEXION_RAD,
                    )
                });
            let joints = joints_from_phi(&placed, sd.stance);
            let w = sd.stance.other().hip();
            if let (Some(&hip), Some(&knee)) = (joints.get(w), joints.get(w + 1)) {
                if hip.is_finite() && knee.is_finite() {
                    // The IK's answer, at most the set-down's joint speed
                    // away: near a straight knee a steady fall of the
                    // ankle asks the knee for any speed.
                    let step = (cfg.set_down_joint_speed_rad_s * dt_s).max(0.0);
                    for (now, to) in sd.swing_rad.iter_mut().zip([hip, knee]) {
                        *now += (to - *now).clamp(-step, step);
                    }
                }
            }
        }
        let w = sd.stance.other().hip();
        if let Some(h) = held.get_mut(w) {
            *h = sd.swing_rad[0];
        }
        if let Some(k) = held.get_mut(w + 1) {
            *k = sd.swing_rad[1];
        }
        self.set_down = Some(sd);
    }

    /// In a safe hold, holds joint `joint` at `angle_rad` from now on
    /// instead of where the hold found it: a joint braked while nothing
    /// told its angle has moved since, and its drive, back on, must hold
    /// it where it is, not pull the body back. Nothing outside a hold.
    pub(super) fn hold_joint_at(&mut self, joint: usize, angle_rad: f32) {
        if !matches!(self.phase, Phase::SafeHold { .. }) || !angle_rad.is_finite() {
            return;
        }
        let angle_rad = self.before_levelling(joint, angle_rad);
        for posture in [
            &mut self.blend_from,
            &mut self.blend_to,
            &mut self.reference,
        ] {
            if let Some(a) = posture.get_mut(joint) {
                *a = angle_rad;
            }
        }
        if let Some(sd) = self.set_down.as_mut() {
            let w = sd.stance.other().hip();
            if let Some(offset) = joint.checked_sub(w) {
                if let Some(a) = sd.swing_rad.get_mut(offset) {
                    *a = angle_rad;
                }
            }
        }
    }

    /// While the motors are disabled the joints move freely: the reference
    /// follows the measured posture (so no tracking error builds up and
    /// nothing jumps when the motors come back after a reset).
    fn follow_measured(&mut self, measured: &[f32; JOINTS]) {
        self.withdraw_replan();
        let target = pick_finite(measured, &self.reference);
        self.reference = target;
        self.blend_from = target;
        self.blend_to = target;
        self.set_down = None;
        self.level_rad = 0.0;
        self.phase = Phase::SafeHold {
            t_s: self.cfg.hold_ramp_s.max(0.0),
        };
    }

    /// After a clinician reset: stand where the reference is, allow steps.
    pub(super) fn reset_after_faults(&mut self) {
        self.withdraw_replan();
        self.new_steps_blocked = false;
        self.stop_requested = false;
        self.blend_to = self.reference;
        self.blend_from = self.reference;
        self.set_down = None;
        self.level_rad = 0.0;
        self.phase = Phase::Standing;
    }

    /// Holds joint `i` (joint order) at `measured` from now on, in a hold
    /// (the supervisor's [`Verdict::rehold_joints`](crate::supervisor::Verdict)):
    /// its blend starts and ends there. Nothing outside a hold, or for a
    /// non-finite angle.
    fn rehold_joint(&mut self, i: usize, measured: f32) {
        if !matches!(self.phase, Phase::SafeHold { .. }) {
            return;
        }
        if !measured.is_finite() {
            return;
        }
        let measured = self.before_levelling(i, measured);
        if let (Some(f), Some(t)) = (self.blend_from.get_mut(i), self.blend_to.get_mut(i)) {
            *f = measured;
            *t = measured;
        }
    }
}
