//! Reaching down with the swing foot: the swing leg's two links (thigh φ4,
//! shank φ5) set so that its ankle is a given depth below where a posture
//! has it, or at a given point, the hip and the stance leg unchanged.
//!
//! The controller's sequencer uses it when a step's table has ended and the
//! foot has not found the ground — a tread a few millimetres lower than
//! planned, a foot tracking a little high, a landing the foot's sensor has
//! not confirmed: the foot goes on down, slowly, until the ground is felt,
//! instead of hovering until the landing times out. And when a safe hold
//! strikes in a swing: the foot goes down to the ground below it, so the
//! hold stands on two feet.
//!
//! Two-link inverse kinematics by the law of cosines. The knee stays on the
//! posture's branch (of the two solutions, the one whose thigh angle is
//! nearer the posture's), and the depth is cut where the knee would
//! straighten past a given flexion: a leg locked straight takes the impact
//! on its stop.

use crate::kinematics::{Phi, forward_kinematics, wrap_pi};
use crate::model::BodyModel;
use crate::scalar::Real;

/// `phi` with the swing ankle lowered by `depth_m` (m) where the leg
/// reaches, by less where it would straighten the knee past
/// `min_knee_flexion_rad`; `phi` itself for a depth that is not positive
/// and finite, or a target the leg cannot reach at all.
pub fn lower_swing_ankle<T: Real>(
    model: &BodyModel<T>,
    phi: &Phi<T>,
    depth_m: T,
    min_knee_flexion_rad: T,
) -> Phi<T> {
    let zero = T::zero();
    if !(depth_m.finite() && depth_m > zero) {
        return *phi;
    }
    let [_, hip, _, _, ankle] = forward_kinematics(model, phi);
    let dx = ankle[0] - hip[0];
    let room_sq = longest_reach_sq(model, min_knee_flexion_rad) - dx * dx;
    if !(room_sq.finite() && room_sq > zero) {
        return *phi;
    }
    let lowest_y = hip[1] - room_sq.sqrt();
    let depth = depth_m.min(ankle[1] - lowest_y);
    if !(depth.finite() && depth > zero) {
        return *phi;
    }
    swing_leg_to(model, phi, hip, [ankle[0], ankle[1] - depth])
}

/// `phi` with the swing ankle at `target_m` (the stance foot's frame of
/// [`forward_kinematics`], m), the hip and the stance leg as `phi` has
/// them; a target beyond the leg's reach with the knee flexed by
/// `min_knee_flexion_rad` is taken at that reach on the line from the hip
/// towards it. `phi` itself for a target that is not finite or lies
/// nearer the hip than the folded leg.
///
/// A swing foot set down in a safe hold goes to a point fixed in the
/// world this way: the hip's IK follows the torso wherever the stance leg
/// lets it go.
pub fn place_swing_ankle<T: Real>(
    model: &BodyModel<T>,
    phi: &Phi<T>,
    target_m: [T; 2],
    min_knee_flexion_rad: T,
) -> Phi<T> {
    let [_, hip, _, _, _] = forward_kinematics(model, phi);
    place_swing_ankle_from(model, phi, hip, target_m, min_knee_flexion_rad)
}

/// [`place_swing_ankle`] with `phi`'s hip given (`hip_m`, as
/// [`forward_kinematics`] has it): a caller that places the ankle of one
/// posture tick after tick works the hip out once.
pub fn place_swing_ankle_from<T: Real>(
    model: &BodyModel<T>,
    phi: &Phi<T>,
    hip_m: [T; 2],
    target_m: [T; 2],
    min_knee_flexion_rad: T,
) -> Phi<T> {
    let hip = hip_m;
    let r = [target_m[0] - hip[0], target_m[1] - hip[1]];
    let d = (r[0] * r[0] + r[1] * r[1]).sqrt();
    let reach = longest_reach_sq(model, min_knee_flexion_rad).sqrt();
    if !(d.finite() && d > T::zero() && reach.finite()) {
        return *phi;
    }
    let scale = if d > reach { reach / d } else { T::one() };
    swing_leg_to(
        model,
        phi,
        hip,
        [hip[0] + r[0] * scale, hip[1] + r[1] * scale],
    )
}

/// The square of the hip-to-ankle distance with the knee flexed by
/// `min_knee_flexion_rad`, m².
fn longest_reach_sq<T: Real>(model: &BodyModel<T>, min_knee_flexion_rad: T) -> T {
    let [_, _, _, l4, l5] = model.lengths();
    let (_, cos_min) = min_knee_flexion_rad.sin_cos_fast();
    l4 * l4 + l5 * l5 + T::lit(2.0) * l4 * l5 * cos_min
}

/// The two-link IK: `phi`'s swing thigh and shank set so that the ankle is
/// at `target` from `hip`, on `phi`'s knee branch; `phi` where no such
/// posture exists.
fn swing_leg_to<T: Real>(
    model: &BodyModel<T>,
    phi: &Phi<T>,
    hip: [T; 2],
    target: [T; 2],
) -> Phi<T> {
    let [_, _, _, l4, l5] = model.lengths();
    let zero = T::zero();
    let r = [target[0] - hip[0], target[1] - hip[1]];
    let d = (r[0] * r[0] + r[1] * r[1]).sqrt();
    if !(d.finite() && d > zero && d >= (l4 - l5).abs()) {
        return *phi;
    }
    // Direction angles in the model's convention: a link at φ points along
    // (sin φ, cos φ), so the angle of a vector (x, y) is atan2(x, y).
    let alpha = r[0].atan2_portable(r[1]);
    let cos_beta =
        ((l4 * l4 + d * d - l5 * l5) / (T::lit(2.0) * l4 * d)).clamp(-T::one(), T::one());
    // acos by atan2 and a square root, all by the `libm` crate
    // (`Real::atan2_portable`): the same bits on the host and the target.
    let beta = (T::one() - cos_beta * cos_beta)
        .max(zero)
        .sqrt()
        .atan2_portable(cos_beta);
    let near = |angle: T, to: T| to + wrap_pi(angle - to);
    let (a, b) = (near(alpha + beta, phi[3]), near(alpha - beta, phi[3]));
    let phi4 = if (a - phi[3]).abs() <= (b - phi[3]).abs() {
        a
    } else {
        b
    };
    let (s4, c4) = phi4.sin_cos_fast();
    let knee = [hip[0] + l4 * s4, hip[1] + l4 * c4];
    let phi5 = near(
        (target[0] - knee[0]).atan2_portable(target[1] - knee[1]),
        phi[4],
    );
    [phi[0], phi[1], phi[2], phi4, phi5]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::forward_kinematics;
    use crate::model::BodyModel;

    /// A landing posture of the paper's walk: stance leg leaning forward,
    /// swing leg reaching ahead with its knee bent by 0.45 rad.
    fn landing() -> Phi<f64> {
        [
            0.25,
            0.2,
            0.05,
            core::f64::consts::PI - 0.4,
            core::f64::consts::PI + 0.05,
        ]
    }

    fn knee_flexion(phi: &Phi<f64>) -> f64 {
        // The shank turned back from the thigh: flexion positive.
        wrap_pi(phi[4] - phi[3])
    }

    #[test]
    fn the_ankle_goes_straight_down_by_the_depth_and_nothing_else_moves() {
        let model = BodyModel::<f64>::paper_table_iii();
        let phi = landing();
        let before = forward_kinematics(&model, &phi);
        for depth in [0.001, 0.005, 0.015] {
            let low = lower_swing_ankle(&model, &phi, depth, 0.05);
            let after = forward_kinematics(&model, &low);
            assert!((after[4][0] - before[4][0]).abs() < 1e-12, "{depth}");
            assert!(
                (before[4][1] - after[4][1] - depth).abs() < 1e-12,
                "{depth}"
            );
            assert_eq!(&low[..3], &phi[..3]);
            assert!((after[1][0] - before[1][0]).abs() < 1e-15);
            // Same knee branch, less flexed.
            assert!(knee_flexion(&low) > 0.0 && knee_flexion(&low) < knee_flexion(&phi));
        }
    }

    #[test]
    fn the_depth_stops_where_the_knee_would_straighten() {
        let model = BodyModel::<f64>::paper_table_iii();
        let phi = landing();
        let min = 0.05;
        let low = lower_swing_ankle(&model, &phi, 0.5, min);
        assert!(
            (knee_flexion(&low) - min).abs() < 1e-9,
            "{}",
            knee_flexion(&low)
        );
        // Deeper asks change nothing more.
        assert_eq!(low, lower_swing_ankle(&model, &phi, 1.0, min));
    }

    #[test]
    fn nothing_to_lower_gives_the_posture_back() {
        let model = BodyModel::<f64>::paper_table_iii();
        let phi = landing();
        for depth in [0.0, -0.01, f64::NAN, f64::INFINITY] {
            assert_eq!(lower_swing_ankle(&model, &phi, depth, 0.05), phi, "{depth}");
        }
        // A leg already straighter than the minimum goes no lower.
        let straight = [
            0.25,
            0.2,
            0.05,
            core::f64::consts::PI - 0.2,
            core::f64::consts::PI - 0.2,
        ];
        assert_eq!(lower_swing_ankle(&model, &straight, 0.02, 0.05), straight);
    }

    #[test]
    fn single_precision_agrees_with_double() {
        let model = BodyModel::<f64>::paper_table_iii();
        let phi = landing();
        let low = lower_swing_ankle(&model, &phi, 0.02, 0.05);
        let model32 = model.cast::<f32>();
        let phi32 = phi.map(|x| x as f32);
        let low32 = lower_swing_ankle(&model32, &phi32, 0.02, 0.05);
        for (a, b) in low.iter().zip(&low32) {
            assert!((a - f64::from(*b)).abs() < 1e-5, "{low:?} {low32:?}");
        }
    }

    #[test]
    fn a_placed_ankle_is_where_it_was_asked_and_the_rest_stays() {
        let model = BodyModel::<f64>::paper_table_iii();
        let phi = landing();
        let before = forward_kinematics(&model, &phi);
        for (dx, dy) in [
            (0.0, -0.02),
            (-0.05, 0.03),
            (-0.08, 0.02),
            (0.02, 0.05),
            (0.0, 0.0),
        ] {
            let target = [before[4][0] + dx, before[4][1] + dy];
            let placed = place_swing_ankle(&model, &phi, target, 0.05);
            let after = forward_kinematics(&model, &placed);
            assert!((after[4][0] - target[0]).abs() < 1e-12, "{dx} {dy}");
            assert!((after[4][1] - target[1]).abs() < 1e-12, "{dx} {dy}");
            assert_eq!(&placed[..3], &phi[..3]);
            assert!(knee_flexion(&placed) > 0.0, "same branch");
        }
        // Straight below, it agrees with lowering by the same depth.
        let placed = place_swing_ankle(&model, &phi, [before[4][0], before[4][1] - 0.02], 0.05);
        let lowered = lower_swing_ankle(&model, &phi, 0.02, 0.05);
        for (a, b) in placed.iter().zip(&lowered) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn a_target_out_of_reach_is_taken_at_the_reach_towards_it() {
        let model = BodyModel::<f64>::paper_table_iii();
        let phi = landing();
        let [_, hip, _, _, ankle] = forward_kinematics(&model, &phi);
        let min = 0.1;
        let target = [ankle[0], ankle[1] - 1.0];
        let placed = place_swing_ankle(&model, &phi, target, min);
        let after = forward_kinematics(&model, &placed)[4];
        assert!((knee_flexion(&placed) - min).abs() < 1e-9);
        // On the line from the hip to the target.
        let cross =
            (after[0] - hip[0]) * (target[1] - hip[1]) - (after[1] - hip[1]) * (target[0] - hip[0]);
        assert!(cross.abs() < 1e-9, "{cross}");
        // Unusable targets give the posture back.
        assert_eq!(place_swing_ankle(&model, &phi, [f64::NAN, 0.0], min), phi);
        assert_eq!(place_swing_ankle(&model, &phi, hip, min), phi);
    }
}
