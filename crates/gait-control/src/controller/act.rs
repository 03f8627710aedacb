//! *act*: per joint, PID plus the model's feed-forward (its answer to the
//! last tick's request, [`crate::feedforward`]), with the other foot's
//! load closed on its sensor in double support; and the model's request
//! for this tick's reference.

use gait_core::foot::StanceFoot;
use gait_core::model::GRAVITY_M_S2;

use crate::feedforward::{FeedForward, ModelRequest, ModelSlot, feedforward};
use crate::position_loop::Setpoint;
use crate::posture::{JOINTS, phi_from_joints};
use crate::reference::Reference;

use super::Controller;
use super::sense::Senses;

/// What *act* decided: the commands before the guard, and the feed-forward
/// in them.
pub(super) struct Actuation {
    /// Motor commands, joint order, N·m.
    pub command_nm: [f32; JOINTS],
    /// The feed-forward part, N·m.
    pub feedforward_nm: [f32; JOINTS],
}

/// How much of its position feedback the other leg gives up while its foot
/// is planned to carry the whole body (0: none, 1: all of it).
const DOUBLE_SUPPORT_COMPLIANCE: f32 = 0.8;

/// Proportional gain of the other foot's load loop (share of the error
/// pushed at once).
const OTHER_FOOT_KP: f32 = 0.5;
/// Its integral gain, 1/s, and the integral's clamp, N.
const OTHER_FOOT_KI_PER_S: f32 = 5.0;
const OTHER_FOOT_INTEGRAL_N: f32 = 200.0;
/// Largest correction of the other foot's load, N (a sensor reading far
/// from the plan, as right after power-up, must not drive the leg to its
/// limit).
const OTHER_FOOT_PUSH_N: f32 = 200.0;

impl Controller<'_> {
    /// Stage 3.
    #[inline(always)]
    pub(super) fn act(&mut self, s: &Senses, r: &Reference) -> Actuation {
        let weight = self.cfg.model.total_mass_kg() * GRAVITY_M_S2 as f32;
        let planned = self.model_answer();
        self.ask_model(s, r, weight);
        let mut feedforward = planned.torques_nm;
        let other_share = r.other_foot_share.unwrap_or(0.0).clamp(0.0, 1.0);
        self.push_other_foot(s, r, &planned, other_share, &mut feedforward);
        // In double support the chain is closed: the stance leg and the
        // pilot set the posture, and the other leg's torques set how much
        // of the body its foot carries. Stiff position loops on both legs
        // would fight each other through the ground and decide that share
        // by their tracking errors; the other leg's loop is softened by the
        // share of the body its foot is planned to carry (stiff again as the
        // plan unloads it before a lift-off), so its feed-forward, which
        // plans that load, is what it applies.
        let carried = if other_share > 0.0 && weight > 0.0 {
            (planned.other_foot_n / weight).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let dt = self.cfg.dt_s;
        let mut command = [0.0f32; JOINTS];
        for (i, c) in command.iter_mut().enumerate() {
            let (Some(lp), Some(g)) = (self.loops.get_mut(i), self.cfg.gains.get(i)) else {
                continue;
            };
            let sp = Setpoint {
                angle_rad: r.angle_rad.get(i).copied().unwrap_or(f32::NAN),
                rate_rad_s: r.rate_rad_s.get(i).copied().unwrap_or(0.0),
                feedforward_nm: feedforward.get(i).copied().unwrap_or(0.0),
            };
            // A joint whose encoder is lost is not driven by PID on its
            // stale angle: the model's torque for the reference alone,
            // unless the closed chain gives its angle.
            let lost = self
                .untaken
                .get(i)
                .is_some_and(|&n| n >= super::BLIND_AFTER_FRAMES)
                || s.lost.get(i).copied().unwrap_or(false);
            let blind = lost && !s.chain_closed.get(i).copied().unwrap_or(false);
            let adjusted;
            let (g, measured, rate) = if blind {
                adjusted = g.without_feedback();
                (&adjusted, sp.angle_rad, sp.rate_rad_s)
            } else if r.stance.other().has_joint(i) && carried > 0.0 {
                adjusted = g.with_stiffness(1.0 - DOUBLE_SUPPORT_COMPLIANCE * carried);
                (
                    &adjusted,
                    s.sensed.joints_rad.get(i).copied().unwrap_or(f32::NAN),
                    self.rate.get(i).copied().unwrap_or(0.0),
                )
            } else {
                (
                    g,
                    s.sensed.joints_rad.get(i).copied().unwrap_or(f32::NAN),
                    self.rate.get(i).copied().unwrap_or(0.0),
                )
            };
            let out = lp.update(g, &sp, measured, rate, dt);
            *c = out.command_nm;
        }
        Actuation {
            command_nm: command,
            feedforward_nm: feedforward,
        }
    }

    /// The other foot's load in double support: measured against the plan,
    /// the difference pushed by the other leg (proportional and integral),
    /// so that the share the plan gives it is what it carries. Without it
    /// the share is a free internal force of the closed chain that the
    /// legs' position loops and the pilot settle between them.
    #[inline(always)]
    fn push_other_foot(
        &mut self,
        s: &Senses,
        r: &Reference,
        planned: &FeedForward,
        other_share: f32,
        feedforward: &mut [f32; JOINTS],
    ) {
        let measured = s
            .forces_n
            .get(r.stance.other().foot())
            .copied()
            .unwrap_or(f32::NAN);
        if !(other_share > 0.0 && measured.is_finite() && self.motors_enabled) {
            self.other_foot_integral_n = 0.0;
            return;
        }
        let error = planned.other_foot_n - measured;
        let integral = (self.other_foot_integral_n + OTHER_FOOT_KI_PER_S * error * self.cfg.dt_s)
            .clamp(-OTHER_FOOT_INTEGRAL_N, OTHER_FOOT_INTEGRAL_N);
        let push = |integral: f32| {
            other_share
                * (OTHER_FOOT_KP * error + integral).clamp(-OTHER_FOOT_PUSH_N, OTHER_FOOT_PUSH_N)
        };
        // Anti-windup: the integral moves only while the other leg's
        // feed-forward stays inside its loops' limits.
        let within = |push_n: f32| {
            feedforward
                .iter()
                .zip(&planned.per_other_foot_newton)
                .zip(&self.cfg.gains)
                .enumerate()
                .all(|(i, ((&f, &per), g))| {
                    !r.stance.other().has_joint(i) || (f + push_n * per).abs() <= g.torque_limit_nm
                })
        };
        if within(push(integral)) {
            self.other_foot_integral_n = integral;
        }
        let push_n = push(self.other_foot_integral_n);
        for (i, (f, &per)) in feedforward
            .iter_mut()
            .zip(&planned.per_other_foot_newton)
            .enumerate()
        {
            if r.stance.other().has_joint(i) {
                *f += push_n * per;
            }
        }
    }

    /// The model's answer to the last tick's request
    /// ([`crate::feedforward`]): from the model task through the slot when
    /// the board runs one (the one before kept if none came).
    #[inline(always)]
    fn model_answer(&mut self) -> FeedForward {
        if let Some(ff) = self.model_slot.and_then(ModelSlot::answer_to_last_request) {
            self.model_ff = ff;
        }
        self.model_ff
    }

    /// Asks the model for the torques along this tick's reference, for the
    /// next tick: while a table plays, its Φ, Φ̇ and Φ̈; otherwise the
    /// statics of the reference posture. In both, the other foot takes up
    /// to the load it may carry where that lowers the effort
    /// (`dynamics::share_load`): the share the plan gives it (the whole
    /// body between steps; along a swing what the table plans for its swing
    /// foot, so a table can shift the weight in double support before it
    /// lifts the foot). Not from the foot's sensor during a swing: a swing
    /// foot brushing the ground then switched the model's load on and off,
    /// and the feed-forward bounced the foot. In a safe hold, what the
    /// sensor reads (NaN: nothing).
    #[inline(always)]
    fn ask_model(&mut self, s: &Senses, r: &Reference, weight: f32) {
        let other_load_n = match r.other_foot_share {
            Some(share) => weight * share.clamp(0.0, 1.0),
            None => {
                let other_foot = s
                    .forces_n
                    .get(r.stance.other().foot())
                    .copied()
                    .unwrap_or(f32::NAN);
                if other_foot.is_finite() {
                    other_foot.max(0.0).min(weight)
                } else {
                    0.0
                }
            }
        };
        let req = match r.motion {
            Some(m) => ModelRequest {
                phi: m.phi,
                motion: Some((m.dphi, m.ddphi)),
                other_load_n,
                stance: r.stance,
            },
            None => ModelRequest {
                phi: phi_from_joints(&r.angle_rad, self.static_stance_phi1(s, r), r.stance),
                motion: None,
                other_load_n,
                stance: r.stance,
            },
        };
        // Without a task, the answer is worked out now and kept for the
        // next tick: the same torques the task would give it.
        match self.model_slot {
            Some(slot) => {
                slot.request(&req);
            }
            None => self.model_ff = feedforward(&self.cfg.model, &req),
        }
    }

    /// The stance shank's angle φ1 for a static posture.
    ///
    /// While control takes the stance ankle's frames: its reading, or, when
    /// it reads the dorsiflexion stop (within 0.5°: the heel may be up and
    /// φ1 beyond what the encoder can see), the larger of it and the
    /// planned φ1. Once that encoder is blind (lost, 0x0207), its last
    /// reading is stale: held from a swing, it set a stair descent's
    /// landing posture 0.3 rad off, the stance knee's feed-forward wrong by
    /// some 60 N·m, the torque residual (0x0404) braked the knee and the
    /// body sank. Then the closed chain gives it, when the other foot
    /// carries load flat on the ground (its ankle off the stop); else the
    /// plan.
    fn static_stance_phi1(&self, s: &Senses, r: &Reference) -> f32 {
        let stop = StanceFoot::for_model(&self.cfg.model).heel_off_rad;
        let on_stop = stop - crate::posture::ON_STOP_TOLERANCE_RAD;
        let stance = JOINTS + r.stance.ankle();
        let other = JOINTS + r.stance.other().ankle();
        let blind = |i: usize| {
            self.untaken
                .get(i)
                .is_none_or(|&n| n >= super::BLIND_AFTER_FRAMES)
        };
        let reading = |i: usize| self.last_angle.get(i).copied().unwrap_or(f32::NAN);
        let planned = r
            .ankle_plan_rad
            .get(r.stance.ankle())
            .copied()
            .unwrap_or(f32::NAN);
        if !blind(stance) {
            return crate::posture::stance_phi1_estimate(reading(stance), stop, planned);
        }
        let other_load = s
            .forces_n
            .get(r.stance.other().foot())
            .copied()
            .unwrap_or(f32::NAN);
        let other_flat = reading(other) < on_stop;
        if !blind(other) && other_flat && other_load >= self.cfg.sequencer.landing_contact_n {
            crate::posture::stance_phi1_through_other_leg(
                &s.sensed.joints_rad,
                reading(other),
                r.stance,
            )
        } else if planned.is_finite() {
            planned
        } else {
            reading(stance)
        }
    }
}
