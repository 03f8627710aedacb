//! Periodic step cases: the landing posture, seen from the new stance foot,
//! is the start posture, so consecutive steps chain without moving a joint
//! in the weight transfer. Checked against the IK and FK independently of
//! how `StepCase::periodic` computes it.
#![allow(clippy::expect_used, clippy::indexing_slicing)]

use gait_core::BodyModel;
use gait_core::ik::{IkSolver, IkTarget};
use gait_core::kinematics::{forward_kinematics, swap_legs, wrap_pi};
use gait_core::problem::{PaperProblem, PeriodicError, PeriodicStep, StepCase};
use proptest::prelude::*;

fn landing_and_start(case: &StepCase<f64>, m: &BodyModel<f64>) -> ([f64; 5], [f64; 5]) {
    let ik = IkSolver::new(m);
    let end = case.end_posture.expect("periodic cases fix the landing");
    let landing = ik
        .solve(&IkTarget {
            x5: case.landing_m[0],
            y5: case.landing_m[1],
            phi1: case.stance.at(case.step_time_s),
            phi3: end.phi3_rad,
            r2: end.r2,
        })
        .expect("landing solves");
    let start = ik
        .solve(&IkTarget {
            x5: case.start_m[0],
            y5: case.start_m[1],
            phi1: case.stance.at(0.0),
            phi3: case.phi3_start_rad,
            r2: case.r2_start,
        })
        .expect("start solves");
    (landing.phi, start.phi)
}

fn assert_chains(case: &StepCase<f64>, m: &BodyModel<f64>) {
    let (landing, start) = landing_and_start(case, m);
    let next = swap_legs(&landing);
    for (a, b) in next.iter().zip(&start) {
        assert!(wrap_pi(a - b).abs() < 1e-7, "{next:?} vs {start:?}");
    }
    // Same joints in the world: the new stance foot is where the swing
    // foot landed.
    let p = forward_kinematics(m, &landing);
    assert!((p[4][0] - case.landing_m[0]).abs() < 1e-9);
    assert!((p[4][1] - case.landing_m[1]).abs() < 1e-9);
}

#[test]
fn device_walk_and_stair_ascent_chain_into_the_next_step() {
    let m = BodyModel::<f64>::paper_table_iii();
    for p in [PeriodicStep::walk(), PeriodicStep::stair_up()] {
        let case = StepCase::periodic(&p, &m).expect("periodic case");
        assert!((case.stance.at(0.0) - p.phi1_start_rad).abs() < 1e-9);
        assert_chains(&case, &m);
        // The bounds pin the landing's r2 and φ3; the initial guess is
        // feasible and has a finite cost.
        let problem = PaperProblem::new(case, m);
        let (lo, hi) = problem.bounds();
        let end = case.end_posture.expect("fixed");
        assert_eq!((lo[4][1], hi[4][1]), (end.r2, end.r2));
        assert_eq!((lo[9][1], hi[9][1]), (end.phi3_rad, end.phi3_rad));
        let guess = problem.initial_guess();
        let cost = problem.cost(&guess).expect("initial guess feasible");
        assert!(cost.j.is_finite() && cost.j > 0.0);
    }
}

#[test]
fn device_walk_keeps_the_ankle_inside_table_i() {
    // Both double-support postures: the front ankle at the start (φ1(0))
    // and the trailing ankle at the landing (φ1(ts)) stay within Table I's
    // 20° of dorsiflexion with room for the supervisor's 2° margin.
    let m = BodyModel::<f64>::paper_table_iii();
    for p in [PeriodicStep::walk(), PeriodicStep::stair_up()] {
        let case = StepCase::periodic(&p, &m).expect("periodic case");
        let end = case.stance.at(case.step_time_s);
        assert!(end < 16f64.to_radians(), "{end}");
        // Inside the device's ankle envelope (heel rocker less the 2°
        // margin), where the supervisor lets the pilot stand ready.
        let heel = gait_core::model::HEEL_ROCKER_PLANTARFLEXION_DEG - 2.0;
        assert!(case.stance.at(0.0) > -heel.to_radians());
    }
}

#[test]
fn a_flat_profile_is_refused() {
    let m = BodyModel::<f64>::paper_table_iii();
    let p = PeriodicStep {
        k_per_s: 0.0,
        ..PeriodicStep::walk()
    };
    assert_eq!(StepCase::periodic(&p, &m), Err(PeriodicError::FlatProfile));
}

#[test]
fn an_unreachable_start_is_refused() {
    let m = BodyModel::<f64>::paper_table_iii();
    let p = PeriodicStep {
        spacing_m: [2.0, 0.0],
        ..PeriodicStep::walk()
    };
    assert!(matches!(
        StepCase::periodic(&p, &m),
        Err(PeriodicError::Start(_))
    ));
}

/// A flat-footed reciprocal stair descent at the paper's stair (tread
/// 0.275 m, rise 0.0935 m) cannot keep the trailing ankle within Table I's
/// 20° of dorsiflexion in double support, whatever the start posture, and
/// even if the IK let the stance knee bend to 90° instead of 45°
/// (docs/model.md, "Stair descent"). Checked here on the IK alone: every
/// double-support posture with the upper (trailing) foot 0.275 m behind
/// and 0.0935 m above the lower one.
#[test]
fn paper_stair_descent_needs_more_ankle_than_table_i_allows() {
    let m = BodyModel::<f64>::paper_table_iii();
    let limit = m.limits().ankle_dorsiflexion_rad;
    for cap_deg in [45.0f64, 90.0] {
        let ik = IkSolver::new(&m).with_stance_knee_max(cap_deg.to_radians());
        let mut found = 0;
        let mut least_trailing = f64::INFINITY;
        for i in 0..=60 {
            for j in 0..=20 {
                // Seen from the lower (front) foot: the trailing foot is
                // behind and above; φ1 is the front shank.
                let target = IkTarget {
                    x5: -0.275,
                    y5: 0.0935,
                    // The front ankle within its range (12° heel rocker
                    // plantarflexion … 20° dorsiflexion).
                    phi1: -0.21 + 0.0093 * f64::from(i),
                    phi3: 0.0,
                    r2: f64::from(j) / 20.0,
                };
                let Ok(s) = ik.solve(&target) else { continue };
                found += 1;
                // The trailing ankle's dorsiflexion is its shank's lean
                // (the trailing shank seen as a stance shank).
                let trailing = swap_legs(&s.phi)[0];
                least_trailing = least_trailing.min(trailing);
            }
        }
        assert!(found > 100, "cap {cap_deg}: only {found} postures");
        assert!(
            least_trailing > limit,
            "cap {cap_deg}: trailing ankle {least_trailing} rad"
        );
    }
    // With the IK's human range the periodic case from the stair-ascent
    // start posture does not exist: the trailing knee would bend past 45°.
    let p = PeriodicStep {
        spacing_m: [0.275, -0.0935],
        ..PeriodicStep::stair_up()
    };
    assert_eq!(
        StepCase::periodic(&p, &m),
        Err(PeriodicError::LandingOutsideHumanRange)
    );
}

proptest! {
    #[test]
    fn periodic_cases_chain_wherever_they_exist(
        phi1 in -0.2f64..0.2,
        r2 in 0.0f64..=1.0,
        stride in 0.3f64..0.7,
        rise in -0.05f64..0.12,
    ) {
        let m = BodyModel::<f64>::paper_table_iii();
        let p = PeriodicStep {
            spacing_m: [stride, rise],
            phi1_start_rad: phi1,
            r2_start: r2,
            ..PeriodicStep::walk()
        };
        let case = StepCase::periodic(&p, &m);
        // Too many rejections fail the test: it cannot pass vacuously.
        prop_assume!(case.is_ok());
        if let Ok(case) = case {
            assert_chains(&case, &m);
        }
    }
}

#[test]
fn periodic_cases_start_and_end_at_rest() {
    // r2, φ3 and the pace z have zero rate at both ends: their second and
    // second-to-last control values are pinned to the end values.
    let m = BodyModel::<f64>::paper_table_iii();
    let case = StepCase::periodic(&PeriodicStep::walk(), &m).expect("case");
    assert!(case.rest_at_ends);
    let problem = PaperProblem::new(case, m);
    let (lo, hi) = problem.bounds();
    let end = case.end_posture.expect("fixed");
    for (row, v) in [
        (1, case.r2_start),
        (3, end.r2),
        (6, case.phi3_start_rad),
        (8, end.phi3_rad),
        (16, 0.0),
        (17, 1.0),
    ] {
        assert_eq!((lo[row][1], hi[row][1]), (v, v), "row {row}");
    }
    // So the swing ankle leaves and arrives with (nearly) zero speed.
    let step = problem.step(&problem.initial_guess());
    let mut p5 = Vec::new();
    step.for_each_sample::<gait_core::gait::GaitError>(|s| {
        p5.push(s.p5);
        Ok(())
    })
    .expect("samples");
    let dt = problem.sampling.dt_s;
    let speed = |a: [f64; 2], b: [f64; 2]| (b[0] - a[0]).hypot(b[1] - a[1]) / dt;
    let n = p5.len();
    assert!(speed(p5[0], p5[1]) < 0.01, "{}", speed(p5[0], p5[1]));
    assert!(speed(p5[n - 2], p5[n - 1]) < 0.01);
    // The paper's cases are unchanged.
    assert!(!StepCase::<f64>::paper(gait_core::problem::PaperCase::Walk).rest_at_ends);
}

#[test]
fn the_joint_motion_term_counts_only_excess_and_every_sample_adds_torque() {
    use gait_core::problem::JointMotionLimit;
    let l: JointMotionLimit<f64> = JointMotionLimit {
        speed_rad_s: 3.0,
        speed_weight: 2.0,
        accel_rad_s2: 30.0,
        accel_weight: 0.5,
    };
    // Φ̇ moving only the torso: θ̇3 = φ̇3 − φ̇2 and θ̇4 = φ̇4 − φ̇3 both see it.
    let calm: [f64; 5] = [0.1, 0.1, 1.0, 0.1, 0.1];
    assert_eq!(l.penalty(&calm, Some(&[0.0; 5])), 0.0);
    let fast: [f64; 5] = [0.0, 0.0, 4.0, 0.0, 0.0];
    // Two joints 1 rad/s over: 2 · (1² + 1²).
    assert!((l.penalty(&fast, None) - 4.0).abs() < 1e-12);
    let jerk: [f64; 5] = [0.0, 0.0, 0.0, 0.0, 40.0];
    // Only the swing knee θ5 = φ5 − φ4: 10 rad/s² over.
    assert!((l.penalty(&[0.0; 5], Some(&jerk)) - 0.5 * 100.0).abs() < 1e-9);

    // The term and c_k = 1 both only add to J.
    let m = BodyModel::<f64>::paper_table_iii();
    let case = StepCase::periodic(&PeriodicStep::walk(), &m).expect("case");
    let mut problem = PaperProblem::new(case, m);
    let p = problem.initial_guess();
    let plain = problem.cost(&p).expect("cost");
    assert_eq!(plain.joint_motion, 0.0);
    problem.count_every_sample = true;
    let all = problem.cost(&p).expect("cost");
    assert!(all.torque > plain.torque && all.swing_samples > plain.swing_samples);
    problem.joint_motion_limit = Some(JointMotionLimit {
        speed_rad_s: 0.1,
        ..l
    });
    let limited = problem.cost(&p).expect("cost");
    assert!(limited.joint_motion > 0.0);
}
