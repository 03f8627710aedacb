//! A lost hip or knee encoder's angle from the closed chain of double
//! support (part of *sense*): with both feet flat on the ground, the
//! other five encoders give it ([`crate::posture::joint_through_closed_chain`]).
//! The joint is then held by its drive; otherwise its brake holds it
//! (`FaultCode::loses_angle`). In single support nothing on the board sees
//! that angle: there is no IMU.

use gait_core::foot::StanceFoot;

use crate::layout::{Side, encoder};
use crate::posture::{JOINTS, ON_STOP_TOLERANCE_RAD, joint_through_closed_chain};

use super::{BLIND_AFTER_FRAMES, Controller};

/// Consecutive ticks the chain must have closed before its estimate is
/// used: a foot that has just touched may still be turning flat under its
/// load, and a brake released and engaged again every few ticks helps no
/// one (50 ms).
pub(super) const CHAIN_SETTLE_TICKS: u16 = 50;

/// The estimate being formed for one joint.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ChainEstimate {
    /// The joint estimated.
    joint: usize,
    /// Consecutive ticks the chain has closed (0: open).
    ticks: u16,
    /// The estimate, rad, and its low-passed rate, rad/s.
    angle_rad: f32,
    rate_rad_s: f32,
    /// Each foot (left, right) on the ground: since its sensor last read
    /// a contact, with its leg not swinging and its sensor not reading
    /// under [`UNLOADED_N`] for [`UNLOADED_TICKS`] since. A foot standing
    /// flat may carry little (the sensor of a foot with most of the body
    /// on the other reads 0–200 N), yet it still closes the chain; one
    /// that has carried nothing for a while may have left the ground.
    feet_down: [bool; 2],
    /// Consecutive ticks each foot's sensor has read under [`UNLOADED_N`].
    unloaded_ticks: [u16; 2],
}

/// A foot reading less than this is unloaded, N (the sensors' noise is a
/// few newtons).
const UNLOADED_N: f32 = 20.0;
/// Ticks unloaded after which a foot is no longer taken as down (20 ms).
const UNLOADED_TICKS: u16 = 20;

impl Controller<'_> {
    /// Forms the estimate of the one hip or knee whose angle control
    /// cannot read (`lost`: the supervisor's lost encoders; or untaken
    /// frames), and once the chain has stayed closed for
    /// [`CHAIN_SETTLE_TICKS`] puts it in place of the joint's angle and
    /// rate. Returns the joints whose angle comes from the chain this tick,
    /// and, on the tick the estimate settles, the joint and angle a hold
    /// is to keep it at from then on (`SeqInput::hold_joint_at`).
    pub(super) fn close_chain(
        &mut self,
        forces_n: &[f32],
        lost: &[bool; JOINTS],
        alpha: f32,
    ) -> ([bool; JOINTS], Option<(usize, f32)>) {
        let mut closed = [false; JOINTS];
        let swinging = self.seq_status.swing_leg;
        let contact = self.cfg.sequencer.landing_contact_n;
        let feet = [Side::Left, Side::Right].into_iter();
        let c = &mut self.chain;
        for ((side, down), unloaded) in feet.zip(&mut c.feet_down).zip(&mut c.unloaded_ticks) {
            let load = forces_n.get(side.foot()).copied().unwrap_or(f32::NAN);
            *unloaded = if load < UNLOADED_N {
                unloaded.saturating_add(1)
            } else {
                0
            };
            if swinging == Some(side) || !load.is_finite() || *unloaded >= UNLOADED_TICKS {
                *down = false;
            } else if load >= contact {
                *down = true;
            }
        }
        let Some((joint, estimate)) = self.chain_estimate(lost) else {
            self.chain.ticks = 0;
            return (closed, None);
        };
        let c = &mut self.chain;
        if c.ticks == 0 || c.joint != joint {
            c.joint = joint;
            c.angle_rad = estimate;
            c.rate_rad_s = 0.0;
        }
        let raw_rate = (estimate - c.angle_rad) / self.cfg.dt_s;
        c.rate_rad_s += alpha * (raw_rate - c.rate_rad_s);
        c.angle_rad = estimate;
        c.ticks = c.ticks.saturating_add(1);
        let (angle, rate, ticks) = (c.angle_rad, c.rate_rad_s, c.ticks);
        let hold = (ticks == CHAIN_SETTLE_TICKS).then_some((joint, angle));
        if ticks >= CHAIN_SETTLE_TICKS {
            if let (Some(a), Some(r), Some(f)) = (
                self.last_angle.get_mut(joint),
                self.rate.get_mut(joint),
                closed.get_mut(joint),
            ) {
                *a = angle;
                *r = rate;
                *f = true;
            }
        }
        (closed, hold)
    }

    /// The joint to estimate and its angle, when exactly one hip or knee
    /// is lost, both ankles read, both feet are down and lie flat (an
    /// ankle on its dorsiflexion stop may be a heel up), and the estimate
    /// lies within the joint's range.
    fn chain_estimate(&self, lost: &[bool; JOINTS]) -> Option<(usize, f32)> {
        let blind = |i: usize| self.untaken.get(i).is_none_or(|&n| n >= BLIND_AFTER_FRAMES);
        // Every encoder read (nearly every tick): nothing to estimate.
        if *lost == [false; JOINTS] && !(0..JOINTS).any(blind) {
            return None;
        }
        if !self.chain.feet_down.iter().all(|&d| d) {
            return None;
        }
        let mut lost_joints =
            (0..JOINTS).filter(|&i| blind(i) || lost.get(i).copied().unwrap_or(true));
        let (Some(joint), None) = (lost_joints.next(), lost_joints.next()) else {
            return None;
        };
        let flat_below =
            StanceFoot::for_model(&self.cfg.model).heel_off_rad - ON_STOP_TOLERANCE_RAD;
        let ankles = encoder::OF_ANKLES.map(|i| {
            if blind(i) {
                f32::NAN
            } else {
                self.last_angle.get(i).copied().unwrap_or(f32::NAN)
            }
        });
        if !ankles.iter().all(|&a| a < flat_below) {
            return None;
        }
        let mut joints = [0.0; JOINTS];
        for (j, a) in joints.iter_mut().zip(&self.last_angle) {
            *j = *a;
        }
        let estimate = joint_through_closed_chain(&joints, ankles, joint);
        let range = self.supervisor.config().joint_range.get(joint)?;
        range.contains(estimate).then_some((joint, estimate))
    }
}
