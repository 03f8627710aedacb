//! Inverse kinematics: FK∘IK round trips over the reachable workspace, typed
//! errors (never NaN) everywhere else, and the properties of the paper's IK
//! that the optimiser must live with (kinks, jumps, the 45° stance-knee cap).

use gait_core::BodyModel;
use gait_core::ik::{IkError, IkSolver, IkTarget};
use gait_core::kinematics::{anatomical_angles, forward_kinematics, phi_from_theta};
use proptest::prelude::*;

fn solver() -> (BodyModel<f64>, IkSolver<f64>) {
    let m = BodyModel::<f64>::paper_table_iii();
    let s = IkSolver::new(&m);
    (m, s)
}

fn target(x5: f64, y5: f64, phi1: f64, phi3: f64, r2: f64) -> IkTarget<f64> {
    IkTarget {
        x5,
        y5,
        phi1,
        phi3,
        r2,
    }
}

/// Swing-ankle targets around the stance foot, as steps and stairs need.
fn workspace() -> impl Strategy<Value = IkTarget<f64>> {
    (
        -0.45f64..0.45,
        -0.15f64..0.25,
        -0.35f64..0.75,
        -0.26f64..0.26,
        0.0f64..=1.0,
    )
        .prop_map(|(x5, y5, phi1, phi3, r2)| target(x5, y5, phi1, phi3, r2))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn fk_of_ik_reaches_the_target(t in workspace()) {
        let (m, ik) = solver();
        match ik.solve(&t) {
            Ok(sol) => {
                let p = forward_kinematics(&m, &sol.phi);
                prop_assert!((p[4][0] - t.x5).abs() < 1e-9 && (p[4][1] - t.y5).abs() < 1e-9,
                    "p5 {:?} vs ({}, {})", p[4], t.x5, t.y5);
                prop_assert_eq!(sol.phi[0], t.phi1);
                prop_assert_eq!(sol.phi[2], t.phi3);
                for (a, b) in p.iter().zip(sol.points.iter()) {
                    prop_assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
                }
                // Θ and Φ describe the same posture.
                let back = phi_from_theta(&sol.theta);
                for i in 0..5 {
                    prop_assert!((back[i] - sol.phi[i]).abs() < 1e-12);
                }
                // φ2 lies in the reported range, which lies in the human range.
                let (lo, hi) = sol.phi2_range;
                prop_assert!(lo <= sol.phi[1] + 1e-12 && sol.phi[1] <= hi + 1e-12);
                prop_assert!(hi <= t.phi1 + 1e-12 && lo >= t.phi1 - core::f64::consts::FRAC_PI_4 - 1e-12);
                // The swing knee bends forward of the hip–ankle line
                // (anatomical swing-knee flexion ≥ 0).
                let anat = anatomical_angles(&sol.theta);
                prop_assert!(anat[4] >= -1e-9, "swing knee hyper-extended: {}", anat[4]);
            }
            Err(e) => {
                // Failure must be one of the geometric reasons, not garbage.
                prop_assert!(matches!(e, IkError::Unreachable | IkError::EmptyHipRange | IkError::SwingLegUnreachable), "{e:?}");
            }
        }
    }

    #[test]
    fn ik_never_returns_nan(x5 in prop::num::f64::ANY, y5 in prop::num::f64::ANY,
                            phi1 in prop::num::f64::ANY, phi3 in prop::num::f64::ANY,
                            r2 in prop::num::f64::ANY) {
        let (_, ik) = solver();
        if let Ok(sol) = ik.solve(&target(x5, y5, phi1, phi3, r2)) {
            prop_assert!(sol.phi.iter().chain(sol.theta.iter()).all(|v| v.is_finite()));
        }
    }

    #[test]
    fn f32_ik_agrees_with_f64(t in workspace()) {
        let (m, ik) = solver();
        let m32: BodyModel<f32> = m.cast();
        let ik32 = IkSolver::new(&m32);
        let t32 = IkTarget { x5: t.x5 as f32, y5: t.y5 as f32, phi1: t.phi1 as f32, phi3: t.phi3 as f32, r2: t.r2 as f32 };
        if let (Ok(a), Ok(b)) = (ik.solve(&t), ik32.solve(&t32)) {
            for i in 0..5 {
                // Near the ends of the swing leg's reach the knee angle is
                // ill-conditioned (√ of a small radicand); 2e-3 rad covers it.
                prop_assert!((f64::from(b.phi[i]) - a.phi[i]).abs() < 2e-3, "phi[{i}] {} vs {}", b.phi[i], a.phi[i]);
            }
        }
    }
}

#[test]
fn most_of_the_step_workspace_is_reachable() {
    // Guards the round-trip property against passing vacuously.
    let (_, ik) = solver();
    let mut ok = 0;
    let mut total = 0;
    for i in 0..=30 {
        for j in 0..=10 {
            let x5 = -0.3 + 0.6 * i as f64 / 30.0;
            let y5 = 0.3 * j as f64 / 10.0;
            total += 1;
            if ik.solve(&target(x5, y5, 0.1, 0.0, 0.5)).is_ok() {
                ok += 1;
            }
        }
    }
    assert!(
        ok * 10 >= total * 9,
        "only {ok} of {total} swing targets reachable"
    );
}

#[test]
fn sign_of_x5_minus_x1_not_x5() {
    // The printed sgn(x5) empties the φ2 range for this reachable target;
    // sgn(x5 − x1) solves it (the foot is behind the stance knee, x1 = 0.13).
    let (m, ik) = solver();
    let t = target(0.05, -0.05, 0.3, 0.0, 0.5);
    let sol = ik.solve(&t).unwrap();
    let p = forward_kinematics(&m, &sol.phi);
    assert!((p[4][0] - 0.05).abs() < 1e-9 && (p[4][1] + 0.05).abs() < 1e-9);
    // Reproduce the printed reading: with B2 > 0 the stretch bound becomes a
    // lower bound for φ2 that lies above φ1.
    let l = m.lengths();
    let p1 = [l[0] * 0.3f64.sin(), l[0] * 0.3f64.cos()];
    let (dx, dy) = (0.05 - p1[0], -0.05 - p1[1]);
    let dist = dx.hypot(dy);
    let leg = l[3] + l[4];
    assert!(dist + l[1] > leg, "intersection case");
    let b1 = (l[1] * l[1] - leg * leg + dist * dist) / (2.0 * dist);
    let b2 = (l[1] * l[1] - b1 * b1).sqrt(); // sgn(x5) = +1
    let (vx, vy) = (
        b1 * dx / dist - b2 * dy / dist,
        b2 * dx / dist + b1 * dy / dist,
    );
    let phi2_min_printed =
        (core::f64::consts::FRAC_PI_2 - vy.atan2(vx)).max(0.3 - core::f64::consts::FRAC_PI_4);
    assert!(
        phi2_min_printed > 0.3,
        "printed reading leaves [{phi2_min_printed}, 0.3]: empty"
    );
}

#[test]
fn typed_errors() {
    let (_, ik) = solver();
    assert_eq!(
        ik.solve(&target(f64::NAN, 0.0, 0.0, 0.0, 0.5)),
        Err(IkError::NonFinite)
    );
    assert_eq!(
        ik.solve(&target(0.1, 0.0, 0.0, 0.0, 1.5)),
        Err(IkError::RatioOutOfRange)
    );
    assert_eq!(
        ik.solve(&target(3.0, 0.0, 0.0, 0.0, 0.5)),
        Err(IkError::Unreachable)
    );
}

#[test]
fn no_intersection_case_is_tested_first() {
    // Swing foot tucked right under the hip: ‖p5 − p1‖ + l2 ≤ l4 + l5, so the
    // whole human range [φ1 − π/4, φ1] is feasible.
    let (m, ik) = solver();
    let l = m.lengths();
    let phi1: f64 = 0.1;
    let p1 = [l[0] * phi1.sin(), l[0] * phi1.cos()];
    let t = target(p1[0], p1[1] - 0.2, phi1, 0.0, 0.5);
    let sol = ik.solve(&t).unwrap();
    assert!((sol.phi2_range.0 - (phi1 - core::f64::consts::FRAC_PI_4)).abs() < 1e-15);
    assert!((sol.phi2_range.1 - phi1).abs() < 1e-15);
}

#[test]
fn stance_knee_flexion_is_capped_at_45_degrees() {
    // r2 = 0 puts φ2 at φ1 − π/4: stance knee flexion exactly 45°, never more,
    // although Table I allows 100° (a property of the paper's IK).
    let (_, ik) = solver();
    let mut worst: f64 = 0.0;
    for i in 0..=20 {
        let x5 = -0.3 + 0.03 * i as f64;
        if let Ok(sol) = ik.solve(&target(x5, 0.1, 0.2, 0.0, 0.0)) {
            let knee = anatomical_angles(&sol.theta)[1];
            worst = worst.max(knee);
        }
    }
    assert!(
        (worst - core::f64::consts::FRAC_PI_4).abs() < 1e-12,
        "max stance knee flexion {worst}"
    );
}

#[test]
fn phi2_jumps_at_the_no_intersection_boundary() {
    // Moving the foot across ‖p5 − p1‖ + l2 = l4 + l5 switches the range from
    // the stretch bound to the full human range: φ2 jumps (with r2 fixed).
    let (m, ik) = solver();
    let l = m.lengths();
    let phi1 = 0.0;
    let knee = [0.0, l[0]];
    let boundary = l[3] + l[4] - l[1];
    // Just ahead of straight below the knee, just inside and just outside:
    // at the boundary the stretch bound points the thigh straight away from
    // the foot (−0.2 rad here), inside the human range, so with r2 = 0 φ2
    // jumps from φ1 − π/4 to about −0.2 rad.
    let n = 0.2f64.hypot(0.98);
    let dir = [0.2 / n, -0.98 / n];
    let at = |r: f64| target(knee[0] + r * dir[0], knee[1] + r * dir[1], phi1, 0.0, 0.0);
    let inside = ik.solve(&at(boundary - 1e-6)).unwrap();
    let outside = ik.solve(&at(boundary + 1e-6)).unwrap();
    let jump = (inside.phi[1] - outside.phi[1]).abs();
    assert!(jump > 0.05, "expected a jump in φ2, got {jump}");
}

/// The descent's knee range: r2 is the stance knee's flexion as a share of
/// the cap, the map is continuous where the paper's jumps (the stance knee
/// passing over the swing foot with the stretch bound active), and every
/// solution still reaches its target.
mod human_knee_range {
    use super::*;
    use gait_core::ik::{IkOptions, KneeRange};

    fn descent_solver() -> (BodyModel<f64>, IkSolver<f64>) {
        let m = BodyModel::<f64>::paper_table_iii();
        let s = IkSolver::new(&m).with_options(IkOptions {
            stance_knee_max_rad: 90f64.to_radians(),
            knee_range: KneeRange::Human,
        });
        (m, s)
    }

    proptest! {
        #[test]
        fn r2_is_the_knee_flexion_and_fk_reaches_the_target(t in workspace()) {
            let (m, s) = descent_solver();
            if let Ok(sol) = s.solve(&t) {
                let knee = t.phi1 - sol.phi[1];
                prop_assert!((knee - (1.0 - t.r2) * 90f64.to_radians()).abs() < 1e-12);
                let p = forward_kinematics(&m, &sol.phi);
                prop_assert!((p[4][0] - t.x5).abs() < 1e-6 && (p[4][1] - t.y5).abs() < 1e-6);
            }
        }

        #[test]
        fn the_stance_thigh_moves_continuously_with_the_target(
            t in workspace(),
            dx in -1e-4f64..1e-4,
            dy in -1e-4f64..1e-4,
        ) {
            let (_, s) = descent_solver();
            let u = IkTarget { x5: t.x5 + dx, y5: t.y5 + dy, ..t };
            if let (Ok(a), Ok(b)) = (s.solve(&t), s.solve(&u)) {
                // φ2 does not depend on the target at all; the swing leg's
                // angles move by at most a few times the target's motion
                // (away from full stretch).
                prop_assert_eq!(a.phi[1], b.phi[1]);
                let stretch = (a.points[1][0] - t.x5).hypot(a.points[1][1] - t.y5);
                if stretch < 0.8 {
                    for i in [3, 4] {
                        prop_assert!((a.phi[i] - b.phi[i]).abs() < 0.05, "{i}");
                    }
                }
            }
        }
    }

    /// Where the paper's range jumps (descent, the stance knee over the swing
    /// foot), the human range does not.
    #[test]
    fn no_jump_where_the_papers_range_jumps() {
        let m = BodyModel::<f64>::paper_table_iii();
        let paper = IkSolver::new(&m).with_stance_knee_max(90f64.to_radians());
        let (_, human) = descent_solver();
        // The stance shank leans 37° on its toe; the swing foot comes down
        // under the knee (x1 = 0.441 sin 0.643 = 0.264 m), as in the descent
        // optimum's final approach.
        let phi1: f64 = 0.643;
        let x1 = m.lengths()[0] * phi1.sin();
        let jump = |s: &IkSolver<f64>, y: f64| -> Option<f64> {
            let before = target(x1 - 0.001, y, phi1, 0.0, 0.9);
            let after = target(x1 + 0.001, y, phi1, 0.0, 0.9);
            Some((s.solve(&before).ok()?.phi[1] - s.solve(&after).ok()?.phi[1]).abs())
        };
        let ys = (0..=40).map(|i| -0.2 + 0.005 * f64::from(i));
        let paper_max = ys
            .clone()
            .filter_map(|y| jump(&paper, y))
            .fold(0.0, f64::max);
        let human_max = ys.filter_map(|y| jump(&human, y)).fold(0.0, f64::max);
        assert!(paper_max > 0.05, "paper jump {paper_max}");
        assert!(human_max < 1e-12, "human jump {human_max}");
    }
}
