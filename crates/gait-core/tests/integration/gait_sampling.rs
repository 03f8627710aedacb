//! Bézier gait description, time sampling, derivatives and the paper-mode
//! cost: properties that hold for any control points, and the paper's
//! definitions checked one by one.

use gait_core::BodyModel;
use gait_core::bezier::Bezier;
use gait_core::gait::{
    ControlPoints, Curve, Differences, GaitError, Sampling, StanceAnkleProfile, Step, StepEvent,
    contact_weight, evaluate_step,
};
use gait_core::problem::{Infeasible, PaperCase, PaperProblem};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]

    #[test]
    fn bezier_interpolates_ends_and_stays_in_hull(
        pts in prop::array::uniform5(prop::array::uniform2(-10.0f64..10.0)),
        u in 0.0f64..=1.0,
    ) {
        let c = Bezier::new(pts);
        let a = c.eval(0.0);
        let b = c.eval(1.0);
        prop_assert!((a[0] - pts[0][0]).abs() < 1e-12 && (a[1] - pts[0][1]).abs() < 1e-12);
        prop_assert!((b[0] - pts[4][0]).abs() < 1e-11 && (b[1] - pts[4][1]).abs() < 1e-11);
        let v = c.eval(u);
        for d in 0..2 {
            let lo = pts.iter().map(|p| p[d]).fold(f64::INFINITY, f64::min);
            let hi = pts.iter().map(|p| p[d]).fold(f64::NEG_INFINITY, f64::max);
            prop_assert!(v[d] >= lo - 1e-11 && v[d] <= hi + 1e-11, "{v:?} outside [{lo}, {hi}]");
        }
        let w = c.eval_de_casteljau(u);
        prop_assert!((v[0] - w[0]).abs() < 1e-11 && (v[1] - w[1]).abs() < 1e-11);
    }

}

/// f32 and f64 agree on the cost of smooth gaits. (Near the IK's jumps a
/// rounding difference can put one sample on the other branch, and backward
/// second differences turn that into a torque spike: f32 is for running
/// precomputed tables on the board, not for searching P.)
#[test]
fn f32_cost_agrees_with_f64() {
    for case in [PaperCase::Walk, PaperCase::StairUp] {
        for r2 in [0.6, 0.8, 0.95] {
            let pb = PaperProblem::<f64>::paper(case);
            let mut p = pb.initial_guess();
            for row in p.iter_mut().take(5).skip(1) {
                row[1] = r2;
            }
            let pb32 = PaperProblem::<f32>::paper(case);
            let p32: ControlPoints<f32> = p.map(|r| r.map(|v| v as f32));
            let a = pb.cost_unchecked(&p).unwrap();
            let b = pb32.cost_unchecked(&p32).unwrap();
            assert!(
                (f64::from(b.j) - a.j).abs() < 1e-3 * a.j,
                "{case:?} r2={r2}: {} vs {}",
                b.j,
                a.j
            );
        }
    }
}

fn linear_step(ts: f64, values: [f64; 5]) -> Step<f64> {
    let pb = PaperProblem::<f64>::paper(PaperCase::Walk);
    let mut p = pb.initial_guess();
    for (i, v) in values.iter().enumerate() {
        p[i] = [ts * i as f64 / 4.0, *v];
    }
    Step {
        control: p,
        stance: pb.case.stance,
        sampling: Sampling::paper(ts),
        foot: None,
        ik: gait_core::ik::IkOptions::paper(),
    }
}

#[test]
fn sampling_hits_the_uniform_time_grid_and_the_end_points() {
    let step = linear_step(2.24, [0.9, 0.1, 0.7, 0.2, 0.4]);
    let curve = Bezier::new([
        [0.0, 0.9],
        [0.56, 0.1],
        [1.12, 0.7],
        [1.68, 0.2],
        [2.24, 0.4],
    ]);
    let mut seen = Vec::new();
    step.for_each_sample::<GaitError>(|s| {
        seen.push(*s);
        Ok(())
    })
    .unwrap();
    assert_eq!(seen.len(), 225);
    assert_eq!(seen[0].r2, 0.9);
    assert!((seen[224].r2 - 0.4).abs() < 1e-12);
    for s in &seen {
        assert!((s.t_s - s.k as f64 * 0.01).abs() < 1e-15);
        // Evenly spaced time control points make t(u) = ts·u, so the exact
        // value is the curve at u = t/ts; linear interpolation on 2,001
        // points is accurate to O(Δu²).
        let exact = curve.eval(s.t_s / 2.24)[1];
        assert!(
            (s.r2 - exact).abs() < 1e-5,
            "k={} {} vs {}",
            s.k,
            s.r2,
            exact
        );
    }
}

#[test]
fn time_running_backwards_is_an_error() {
    let mut step = linear_step(2.24, [0.9, 0.5, 0.5, 0.5, 0.5]);
    // Interior time control points far out of order make t(u) decrease.
    step.control[5] = [0.0, 0.0];
    step.control[6] = [2.2, 0.0];
    step.control[7] = [0.0, 0.0];
    step.control[8] = [0.0, 0.0];
    step.control[9] = [2.24, 0.0];
    let r = step.for_each_sample::<GaitError>(|_| Ok(()));
    assert_eq!(r, Err(GaitError::TimeNotMonotonic(Curve::Phi3)));
}

#[test]
fn bad_sampling_and_non_finite_points_are_errors() {
    let mut step = linear_step(2.24, [0.9, 0.5, 0.5, 0.5, 0.5]);
    step.sampling.dt_s = 0.0;
    assert_eq!(
        step.for_each_sample::<GaitError>(|_| Ok(())),
        Err(GaitError::BadSampling)
    );
    let mut step = linear_step(2.24, [0.9, 0.5, 0.5, 0.5, 0.5]);
    step.control[12][0] = f64::NAN;
    assert_eq!(
        step.for_each_sample::<GaitError>(|_| Ok(())),
        Err(GaitError::NonFinite)
    );
}

#[test]
fn contact_indicator_uses_two_millimetres() {
    let s = [-0.3, 0.0];
    let l = [0.3, 0.0];
    assert_eq!(contact_weight([-0.3, 0.0019], s, l, 0.002), 0.0);
    assert_eq!(contact_weight([0.3019, 0.0], s, l, 0.002), 0.0);
    assert_eq!(contact_weight([-0.3, 0.0021], s, l, 0.002), 1.0);
}

#[test]
fn logistic_stance_profile() {
    let p: StanceAnkleProfile<f64> = StanceAnkleProfile {
        a_rad: -0.3335,
        b_rad: 0.7564,
        k_per_s: 0.5638,
        t_c_s: 2.24,
    };
    assert!((p.at(2.24) - (-0.3335 + 0.7564) / 2.0).abs() < 1e-12);
    let t0 = -0.3335 + (0.7564 + 0.3335) / (1.0 + (0.5638f64 * 2.24).exp());
    assert!((p.at(0.0) - t0).abs() < 1e-12);
}

#[test]
fn backward_and_central_differences_agree_on_a_smooth_step() {
    let pb = PaperProblem::<f64>::paper(PaperCase::StairUp);
    let step = pb.step(&pb.initial_guess());
    let m = BodyModel::<f64>::paper_table_iii();
    let collect = |d: Differences| {
        let mut out = Vec::new();
        let mut acc = Vec::new();
        evaluate_step::<f64, GaitError>(&m, &step, d, |ev| {
            if let StepEvent::Dynamics(s) = ev {
                out.push((s.gait.k, s.dphi));
                acc.push((s.gait.k, s.ddphi));
            }
            Ok(())
        })
        .unwrap();
        (out, acc)
    };
    let (back, back_acc) = collect(Differences::Backward);
    let (cent, cent_acc) = collect(Differences::Central);
    for (kc, ac) in &cent_acc {
        if let Some((_, ab)) = back_acc.iter().find(|(k, _)| *k == kc + 1) {
            for i in 0..5 {
                assert!((ac[i] - ab[i]).abs() < 1e-6 * (1.0 + ab[i].abs()), "k={kc}");
            }
        }
    }
    assert_eq!(
        back.first().unwrap().0,
        2,
        "backward differences start at k = 2"
    );
    assert_eq!(
        cent.first().unwrap().0,
        1,
        "central differences start at k = 1"
    );
    assert_eq!(back.last().unwrap().0, 228);
    assert_eq!(cent.last().unwrap().0, 227);
    // Exact identities, true whatever the smoothness of Φ (the IK has
    // kinks): central Φ̇(k) is the mean of backward Φ̇(k) and Φ̇(k+1), and
    // central Φ̈(k) equals backward Φ̈(k+1).
    let mut checked = 0;
    for (kc, dc) in &cent {
        let (Some(b0), Some(b1)) = (
            back.iter().find(|(k, _)| k == kc),
            back.iter().find(|(k, _)| *k == kc + 1),
        ) else {
            continue;
        };
        for i in 0..5 {
            let mean = 0.5 * (b0.1[i] + b1.1[i]);
            assert!((dc[i] - mean).abs() < 1e-9 * (1.0 + mean.abs()), "k={kc}");
        }
        checked += 1;
    }
    assert!(checked > 200);
}

#[test]
fn paper_bounds_and_feasibility() {
    for case in [PaperCase::Walk, PaperCase::StairUp] {
        let pb = PaperProblem::<f64>::paper(case);
        let (lo, hi) = pb.bounds();
        let p = pb.initial_guess();
        pb.check_feasible(&p).unwrap();
        // Millimetres converted: lift ≥ start + 0.3 m, ceiling 0.6 m.
        assert!((lo[11][1] - (pb.case.start_m[1] + 0.3)).abs() < 1e-15);
        assert_eq!(hi[12][1], 0.6);
        assert!((hi[6][1] - core::f64::consts::PI / 12.0).abs() < 1e-15);
        let mut bad = p;
        bad[12][1] = 0.7;
        assert_eq!(
            pb.check_feasible(&bad),
            Err(Infeasible::Bound { row: 12, col: 1 })
        );
        let mut bad = p;
        bad[2][0] = 0.1;
        bad[1][0] = 0.2;
        assert_eq!(
            pb.check_feasible(&bad),
            Err(Infeasible::TimeOrder { row: 2 })
        );
        let c = pb.cost(&p).unwrap();
        assert!(c.j.is_finite() && c.j > 0.0);
        assert!((c.j - c.torque - c.velocity).abs() < 1e-9 * c.j);
        // The stance foot's contact samples at both ends are masked.
        assert!(c.swing_samples < pb.sampling.intervals - 1);
        assert!(c.swing_samples > pb.sampling.intervals / 2);
    }
}

#[test]
fn velocity_term_is_the_peak_ankle_speed() {
    // Pace control points (ts, 0), (ts, 1) give t = ts (1 − (1−u)³) and
    // z = 3u² − 2u³: dz/dt grows without bound as u → 1, so the ankle rushes
    // onto the landing point and the velocity term must say so.
    let pb = PaperProblem::<f64>::paper(PaperCase::Walk);
    let mut p = pb.initial_guess();
    let c_slow = pb.cost(&p).unwrap();
    p[16] = [2.24, 0.0];
    p[17] = [2.24, 1.0];
    let c_fast = pb.cost(&p).unwrap();
    assert!(c_fast.peak_ankle_speed_m_s > 2.0 * c_slow.peak_ankle_speed_m_s);
    assert!((c_fast.velocity - 1000.0 * c_fast.peak_ankle_speed_m_s).abs() < 1e-9);
}
