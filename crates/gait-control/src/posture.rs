//! Between the paper's 5-link description (links 1–2 = stance leg, 4–5 =
//! swing leg) and the device's joints (left/right hip and knee, left/right
//! ankle), which depends on which leg stands.
//!
//! Joint order everywhere in gait-control: 0 left hip, 1 left knee,
//! 2 right hip, 3 right knee; anatomical angles, flexion positive (rad);
//! torques on those coordinates (N·m). Ankles: 0 left, 1 right,
//! dorsiflexion positive.

use gait_core::LINKS;
use gait_core::kinematics::{Phi, anatomical_angles, theta_from_phi};

pub use crate::layout::{JOINTS, Side};

/// Puts stance/swing values (hip, knee each) into the joint order.
fn place(
    stance: Side,
    stance_hip: f32,
    stance_knee: f32,
    swing_hip: f32,
    swing_knee: f32,
) -> [f32; JOINTS] {
    let mut j = [0.0; JOINTS];
    let (s, w) = (stance.hip(), stance.other().hip());
    if let Some(x) = j.get_mut(s) {
        *x = stance_hip;
    }
    if let Some(x) = j.get_mut(s + 1) {
        *x = stance_knee;
    }
    if let Some(x) = j.get_mut(w) {
        *x = swing_hip;
    }
    if let Some(x) = j.get_mut(w + 1) {
        *x = swing_knee;
    }
    j
}

/// Joint angles (anatomical, joint order) of a 5-link posture Φ with the
/// given stance leg.
pub fn joints_from_phi(phi: &Phi<f32>, stance: Side) -> [f32; JOINTS] {
    let a = anatomical_angles(&theta_from_phi(phi));
    place(stance, a[2], a[1], a[3], a[4])
}

/// Anatomical joint torques (joint order) from the 5-link joint torques T_Θ.
///
/// A torque on an anatomical coordinate q = s·θ is s·T_θ: stance knee +T_θ2,
/// stance hip −T_θ3, swing hip +T_θ4, swing knee −T_θ5. T_θ1 (the stance
/// ankle) has no motor: the pilot supplies it through the crutches.
pub fn joint_torques_from_theta_torques(t_theta: &[f32; LINKS], stance: Side) -> [f32; JOINTS] {
    let [_, t2, t3, t4, t5] = *t_theta;
    place(stance, -t3, t2, t4, -t5)
}

/// The 5-link posture Φ from measured joint angles and the stance ankle
/// (foot flat): φ1 = dorsiflexion, φ2 = φ1 − stance knee flexion,
/// φ3 = φ2 + stance hip flexion, φ4 = π + φ3 − swing hip flexion,
/// φ5 = φ4 + swing knee flexion.
pub fn phi_from_joints(joints: &[f32; JOINTS], stance_ankle_rad: f32, stance: Side) -> Phi<f32> {
    let get = |i: usize| joints.get(i).copied().unwrap_or(0.0);
    let (s, w) = (stance.hip(), stance.other().hip());
    let phi1 = stance_ankle_rad;
    let phi2 = phi1 - get(s + 1);
    let phi3 = phi2 + get(s);
    let phi4 = core::f32::consts::PI + phi3 - get(w);
    let phi5 = phi4 + get(w + 1);
    [phi1, phi2, phi3, phi4, phi5]
}

/// An ankle reading within this of the dorsiflexion stop may be a heel
/// lifted off the ground (toe rocker): the foot is then not flat, and the
/// reading only a bound on the shank's lean, rad (0.5°).
pub const ON_STOP_TOLERANCE_RAD: f32 = 0.5 * core::f32::consts::PI / 180.0;

/// The stance shank's angle φ1 through the closed chain of double
/// support, from the other ankle's reading (its foot flat on the ground)
/// and the four joint angles: the other shank's φ5 = π + `other_ankle_rad`
/// (with every joint at 0 the shanks are parallel and both ankles read
/// the same lean), and [`phi_from_joints`] carried back from it. Why: a stance ankle whose encoder is lost leaves
/// the posture's lean unknown, and a stale reading sets the feed-forward
/// for a posture the body has left.
pub fn stance_phi1_through_other_leg(
    joints: &[f32; JOINTS],
    other_ankle_rad: f32,
    stance: Side,
) -> f32 {
    let get = |i: usize| joints.get(i).copied().unwrap_or(f32::NAN);
    let (s, w) = (stance.hip(), stance.other().hip());
    other_ankle_rad + get(s + 1) - get(s) + get(w) - get(w + 1)
}

/// The signs with which each joint (joint order) enters the closed
/// chain's angle sum, left foot to right foot: aR − aL + kL − hL + hR − kR
/// = 0 with both feet flat ([`stance_phi1_through_other_leg`] with the
/// left leg standing, rearranged).
const CHAIN_SIGNS: [f32; JOINTS] = [-1.0, 1.0, 1.0, -1.0];

/// Joint `lost`'s angle (or rate) from the other three joints' and both
/// ankles' (`ankles`: left, right) through the closed chain of double
/// support: with both feet flat on the ground (level or on treads), the
/// links' angles must come back to the ground's, so the six relative
/// angles sum to zero with [`CHAIN_SIGNS`]. Linear, so the same holds for
/// the rates. Why: a hip or knee whose encoder is lost can then still be
/// held by its drive instead of its brake. NaN if `lost` is not a joint
/// or an input is NaN.
pub fn joint_through_closed_chain(joints: &[f32; JOINTS], ankles: [f32; 2], lost: usize) -> f32 {
    let Some(&sign) = CHAIN_SIGNS.get(lost) else {
        return f32::NAN;
    };
    let [left, right] = ankles;
    let mut rest = right - left;
    for (i, (&q, &si)) in joints.iter().zip(&CHAIN_SIGNS).enumerate() {
        if i != lost {
            rest += si * q;
        }
    }
    -rest * sign
}

/// The stance shank's angle φ1 from the ankle encoder's `reading`: the
/// reading itself while the foot is flat; once the reading is at the
/// dorsiflexion `stop` (within 0.5°), the heel may be up (toe rocker,
/// `gait_core::foot`) and φ1 beyond what the encoder can see, so the larger
/// of the reading and the `planned` φ1. NaN readings stay NaN.
pub fn stance_phi1_estimate(reading: f32, stop: f32, planned: f32) -> f32 {
    if reading >= stop - ON_STOP_TOLERANCE_RAD && planned.is_finite() {
        reading.max(planned)
    } else {
        reading
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stance_phi1_follows_the_plan_only_on_the_stop() {
        let stop = 20f32.to_radians();
        // Flat: the encoder is the truth, whatever the plan says.
        assert_eq!(stance_phi1_estimate(0.1, stop, 0.7), 0.1);
        // On the stop, heel up: the plan's larger lean.
        assert_eq!(stance_phi1_estimate(stop, stop, 0.7), 0.7);
        // On the stop but the plan leans less: the encoder.
        assert_eq!(stance_phi1_estimate(stop, stop, 0.2), stop);
        // NaN stays NaN; a NaN plan is ignored.
        assert!(stance_phi1_estimate(f32::NAN, stop, 0.7).is_nan());
        assert_eq!(stance_phi1_estimate(stop, stop, f32::NAN), stop);
    }

    #[test]
    fn the_closed_chain_gives_the_stance_lean_the_other_ankle_reads() {
        // A double-support posture: stance shank leaning 0.15 rad, the
        // other foot flat with its shank at 0.32 rad (φ5 = π + 0.32).
        for side in [Side::Left, Side::Right] {
            let (phi1, other) = (0.15f32, 0.32f32);
            let phi = [phi1, -0.25, 0.1, 2.9, core::f32::consts::PI + other];
            let joints = joints_from_phi(&phi, side);
            let est = stance_phi1_through_other_leg(&joints, other, side);
            assert!((est - phi1).abs() < 1e-5, "{side:?}: {est}");
            // Forward kinematics: with that φ1 both feet are flat, the
            // other shank's direction (knee to ankle) is π + its lean.
            let back = phi_from_joints(&joints, est, side);
            assert!((back[4] - core::f32::consts::PI - other).abs() < 1e-5);
            // A different other-ankle reading moves the estimate by as much.
            let moved = stance_phi1_through_other_leg(&joints, other + 0.1, side);
            assert!((moved - phi1 - 0.1).abs() < 1e-5);
        }
    }

    #[test]
    fn the_closed_chain_gives_any_one_lost_joint() {
        // Both feet flat, the left leg standing on a shank leaning 0.15
        // rad: the right ankle reads the right shank's lean, φ5 − π.
        let phi = [0.15f32, -0.35, 0.05, 2.75, 3.45];
        let right_ankle = phi[4] - core::f32::consts::PI;
        for side in [Side::Left, Side::Right] {
            // The same posture seen with either leg as the stance leg.
            let (joints, ankles) = match side {
                Side::Left => (joints_from_phi(&phi, side), [phi[0], right_ankle]),
                Side::Right => {
                    let j = joints_from_phi(&phi, Side::Left);
                    ([j[2], j[3], j[0], j[1]], [right_ankle, phi[0]])
                }
            };
            for lost in 0..JOINTS {
                let mut blind = joints;
                blind[lost] = 99.0;
                let est = joint_through_closed_chain(&blind, ankles, lost);
                assert!((est - joints[lost]).abs() < 1e-5, "{side:?} {lost}: {est}");
            }
            // A foot turned (an ankle read 0.1 rad more) moves the estimate
            // by as much, and a NaN reading gives NaN.
            let moved = joint_through_closed_chain(&joints, [ankles[0] + 0.1, ankles[1]], 1);
            assert!((moved - joints[1] - 0.1).abs() < 1e-5);
            assert!(joint_through_closed_chain(&joints, [f32::NAN, 0.0], 0).is_nan());
        }
        assert!(joint_through_closed_chain(&[0.0; JOINTS], [0.0, 0.0], JOINTS).is_nan());
    }

    #[test]
    fn phi_joint_round_trip_both_sides() {
        let phi = [0.12, -0.2, 0.05, 2.7, 3.4];
        for side in [Side::Left, Side::Right] {
            let j = joints_from_phi(&phi, side);
            let back = phi_from_joints(&j, phi[0], side);
            for i in 0..LINKS {
                assert!((back[i] - phi[i]).abs() < 1e-5, "{side:?} {i}");
            }
        }
    }

    #[test]
    fn standing_is_all_zero() {
        let pi = core::f32::consts::PI;
        let j = joints_from_phi(&[0.0, 0.0, 0.0, pi, pi], Side::Left);
        assert!(j.iter().all(|v| v.abs() < 1e-6));
    }

    #[test]
    fn sides_swap_stance_and_swing() {
        let phi = [0.1, -0.3, 0.0, 2.6, 3.5];
        let l = joints_from_phi(&phi, Side::Left);
        let r = joints_from_phi(&phi, Side::Right);
        assert_eq!(l[0], r[2]);
        assert_eq!(l[1], r[3]);
        assert_eq!(l[2], r[0]);
        assert_eq!(l[3], r[1]);
        // Stance hip flexion 0.3 rad (thigh back, torso upright), swing hip
        // flexion π − 2.6, swing knee flexion 0.9.
        assert!((l[0] - 0.3).abs() < 1e-6);
        assert!((l[2] - (core::f32::consts::PI - 2.6)).abs() < 1e-6);
        assert!((l[3] - 0.9).abs() < 1e-6);
    }
}
