//! A lost hip or knee encoder's angle from the closed chain of double
//! support (part of *sense*): with both feet flat on the ground, the
//! other five encoders give it ([`crate::posture::joint_through_closed_chain`]);
//! with one foot flat and the other on its toe, where that toe was when
//! every encoder still read pins it ([`crate::posture::joint_through_toe`]).
//! The joint is then held by its drive; otherwise its brake holds it
//! (`FaultCode::loses_angle`). In single support nothing on the board sees
//! that angle: there is no IMU.

use gait_core::foot::StanceFoot;
use gait_core::kinematics::Point;

use crate::layout::Side;
use crate::posture::{
    JOINTS, ON_STOP_TOLERANCE_RAD, joint_through_closed_chain, joint_through_toe,
    other_toe_from_flat_foot,
};

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
    /// Each foot on the ground as in `feet_down`, swinging or not: a
    /// descent's trailing foot stands on its toe and carries the body early
    /// in the sequencer's swing.
    on_ground: [bool; 2],
    /// Where the toe stood when the joint was lost, if a foot stood on it.
    toe: Option<ToeAnchor>,
    /// Every hip and knee was read last tick: a joint blind now has just
    /// been lost, and the others' readings with its last one still
    /// describe the posture.
    all_read: bool,
}

/// The toe that pins the chain of a lost joint ([`joint_through_toe`]).
#[derive(Debug, Clone, Copy)]
struct ToeAnchor {
    /// The joint lost.
    joint: usize,
    /// The foot standing flat, from whose ankle the toe is measured.
    base: Side,
    /// The other foot's toe pivot from the base ankle, m.
    at_m: Point<f32>,
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
    /// rate. Returns the joints whose angle comes from the chain this tick.
    pub(super) fn close_chain(
        &mut self,
        forces_n: &[f32],
        lost: &[bool; JOINTS],
        alpha: f32,
    ) -> [bool; JOINTS] {
        let mut closed = [false; JOINTS];
        let swinging = self.seq.swing_leg();
        let contact = self.cfg.sequencer.landing_contact_n;
        let feet = [Side::Left, Side::Right].into_iter();
        let c = &mut self.chain;
        let per_foot = c.feet_down.iter_mut().zip(&mut c.on_ground);
        for ((side, (down, ground)), unloaded) in feet.zip(per_foot).zip(&mut c.unloaded_ticks) {
            let load = forces_n.get(side.foot()).copied().unwrap_or(f32::NAN);
            *unloaded = if load < UNLOADED_N {
                unloaded.saturating_add(1)
            } else {
                0
            };
            if !load.is_finite() || *unloaded >= UNLOADED_TICKS {
                *ground = false;
            } else if load >= contact {
                *ground = true;
            }
            *down = *ground && swinging != Some(side);
        }
        let lost_joint = self.lost_joint(lost);
        let c = &mut self.chain;
        let just_lost = c.all_read;
        c.all_read = lost_joint == LostJoints::None;
        let LostJoints::One(joint) = lost_joint else {
            c.toe = None;
            c.ticks = 0;
            return closed;
        };
        if just_lost {
            let anchor = self.toe_anchor(joint);
            self.chain.toe = anchor;
        }
        let Some(estimate) = self
            .flat_chain_estimate(joint)
            .or_else(|| self.toe_chain_estimate(joint))
        else {
            self.chain.ticks = 0;
            return closed;
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
        if ticks == CHAIN_SETTLE_TICKS {
            self.seq.hold_joint_at(joint, angle);
        }
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
        closed
    }

    /// Whether a hip or knee is lost (`lost`: the supervisor's lost
    /// encoders; or untaken frames), and which.
    fn lost_joint(&self, lost: &[bool; JOINTS]) -> LostJoints {
        let mut lost_joints =
            (0..JOINTS).filter(|&i| self.blind(i) || lost.get(i).copied().unwrap_or(true));
        match (lost_joints.next(), lost_joints.next()) {
            (None, _) => LostJoints::None,
            (Some(joint), None) => LostJoints::One(joint),
            _ => LostJoints::Many,
        }
    }

    /// Encoder `i` (joints, then ankles) has not been taken for
    /// [`BLIND_AFTER_FRAMES`] frames.
    pub(super) fn blind(&self, i: usize) -> bool {
        self.untaken.get(i).is_none_or(|&n| n >= BLIND_AFTER_FRAMES)
    }

    /// Both ankles' readings (left, right); NaN for a blind one.
    fn ankle_readings(&self) -> [f32; 2] {
        [JOINTS, JOINTS + 1].map(|i| {
            if self.blind(i) {
                f32::NAN
            } else {
                self.last_angle.get(i).copied().unwrap_or(f32::NAN)
            }
        })
    }

    /// An ankle reading below this has its foot flat (on the stop, the heel
    /// may be up), rad.
    fn flat_below(&self) -> f32 {
        StanceFoot::for_model(&self.cfg.model).heel_off_rad - ON_STOP_TOLERANCE_RAD
    }

    /// Joint `joint`'s angle through the flat chain, when both feet are
    /// down and lie flat (an ankle on its dorsiflexion stop may be a heel
    /// up), and it lies within the joint's range.
    fn flat_chain_estimate(&self, joint: usize) -> Option<f32> {
        if !self.chain.feet_down.iter().all(|&d| d) {
            return None;
        }
        let ankles = self.ankle_readings();
        let flat_below = self.flat_below();
        if !ankles.iter().all(|&a| a < flat_below) {
            return None;
        }
        let estimate = joint_through_closed_chain(&self.joint_angles(), ankles, joint);
        self.within_range(joint, estimate)
    }

    /// Where the other foot's toe lies from a flat foot, taken on the tick
    /// `joint` is lost with its last reading, when both feet are on the
    /// ground and one (the one carrying more, if both) lies flat.
    fn toe_anchor(&self, joint: usize) -> Option<ToeAnchor> {
        let c = &self.chain;
        if !c.on_ground.iter().all(|&g| g) {
            return None;
        }
        let ankles = self.ankle_readings();
        let flat_below = self.flat_below();
        let [left_flat, right_flat] = ankles.map(|a| a < flat_below);
        let base = match (left_flat, right_flat) {
            (true, false) => Side::Left,
            (false, true) => Side::Right,
            (true, true) if c.unloaded_ticks == [0, 0] => Side::Left,
            _ => return None,
        };
        let model = &self.cfg.model;
        let foot = StanceFoot::for_model(model);
        let at_m = other_toe_from_flat_foot(model, &foot, &self.joint_angles(), ankles, base);
        (at_m[0].is_finite() && at_m[1].is_finite()).then_some(ToeAnchor { joint, base, at_m })
    }

    /// Joint `joint`'s angle through the toe anchored when it was lost,
    /// while both feet stay on the ground, the base foot flat, and it lies
    /// within the joint's range.
    fn toe_chain_estimate(&self, joint: usize) -> Option<f32> {
        let c = &self.chain;
        let anchor = c.toe.filter(|t| t.joint == joint)?;
        if !c.on_ground.iter().all(|&g| g) {
            return None;
        }
        let ankles = self.ankle_readings();
        let base_flat = match anchor.base {
            Side::Left => ankles[0] < self.flat_below(),
            Side::Right => ankles[1] < self.flat_below(),
        };
        if !base_flat {
            return None;
        }
        let model = &self.cfg.model;
        let foot = StanceFoot::for_model(model);
        let estimate = joint_through_toe(
            model,
            &foot,
            &self.joint_angles(),
            ankles,
            anchor.base,
            anchor.at_m,
            joint,
        );
        self.within_range(joint, estimate)
    }

    /// `estimate` if it lies within the joint's range (NaN does not).
    fn within_range(&self, joint: usize, estimate: f32) -> Option<f32> {
        let range = self.supervisor.config().joint_range.get(joint)?;
        range.contains(estimate).then_some(estimate)
    }
}

/// How many hips and knees control cannot read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LostJoints {
    None,
    One(usize),
    Many,
}
