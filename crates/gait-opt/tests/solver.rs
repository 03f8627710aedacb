//! Solver tests. The record-beating ones run the full default budget
//! (20,000 evaluations, ~1.7 s per case in release, ~30 s in debug), so
//! they are release-only: `cargo test --release -p gait-opt`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use gait_core::problem::{PaperCase, PaperProblem};
use gait_opt::report::step_samples;
use gait_opt::{OptimizeConfig, OptimizeResult, cost_from_phi, optimize};

/// The independent scipy implementation's best J (DE + Powell, ~200 s).
const RECORD_WALK: f64 = 3361.9;
const RECORD_STAIR: f64 = 1476.6;

fn solve(case: PaperCase, seed: u64, max_evals: usize) -> OptimizeResult {
    let mut cfg = OptimizeConfig::new(case);
    cfg.seed = seed;
    cfg.max_evals = max_evals;
    let mut reports = 0usize;
    let r = optimize(&cfg, &mut |p| {
        reports += 1;
        assert!(p.evaluations <= max_evals);
    })
    .unwrap();
    assert!(reports > 0, "progress was never reported");
    assert!(
        r.evaluations <= max_evals,
        "{} > {max_evals}",
        r.evaluations
    );
    let problem = PaperProblem::<f64>::paper(case);
    problem.check_feasible(&r.control_points).unwrap();
    let again = problem.cost(&r.control_points).unwrap();
    assert_eq!(again.j.to_bits(), r.cost.j.to_bits());
    r
}

fn beats(case: PaperCase, record: f64) {
    let r = solve(case, 1, OptimizeConfig::new(case).max_evals);
    assert!(
        r.cost.j < record,
        "{case:?}: J = {} does not beat {record}",
        r.cost.j
    );
    // The evaluator from Φ samples agrees on the optimised step.
    let problem = PaperProblem::<f64>::paper(case);
    let phi: Vec<_> = step_samples(&problem, &r.control_points)
        .unwrap()
        .iter()
        .map(|s| s.phi_rad)
        .collect();
    let c = cost_from_phi(&problem, &phi).unwrap();
    assert!(
        (c.j - r.cost.j).abs() <= 1e-9 * r.cost.j,
        "{} vs {}",
        c.j,
        r.cost.j
    );
}

// The workspace builds gait-core and gait-opt with opt-level 3 in test
// builds too (root Cargo.toml), so the full 20,000-evaluation budget runs in
// seconds without --release.
#[test]
fn beats_the_record_walk() {
    beats(PaperCase::Walk, RECORD_WALK);
}

#[test]
fn beats_the_record_stair() {
    beats(PaperCase::StairUp, RECORD_STAIR);
}

#[test]
fn same_seed_gives_bitwise_the_same_p() {
    for case in [PaperCase::Walk, PaperCase::StairUp] {
        let a = solve(case, 7, 500);
        let b = solve(case, 7, 500);
        for (x, y) in a
            .control_points
            .iter()
            .flatten()
            .zip(b.control_points.iter().flatten())
        {
            assert_eq!(x.to_bits(), y.to_bits(), "{case:?}");
        }
        assert_eq!(a.evaluations, b.evaluations);
        // A small budget already improves on the initial guess.
        let j0 = PaperProblem::<f64>::paper(case)
            .cost(&PaperProblem::<f64>::paper(case).initial_guess())
            .unwrap()
            .j;
        assert!(a.cost.j < j0, "{case:?}: {} !< {j0}", a.cost.j);
    }
}

#[test]
fn seed_changes_the_search() {
    let a = solve(PaperCase::Walk, 1, 500);
    let b = solve(PaperCase::Walk, 2, 500);
    assert_ne!(a.control_points, b.control_points);
}

#[test]
fn bad_config_is_refused() {
    let mut cfg = OptimizeConfig::new(PaperCase::Walk);
    cfg.max_evals = 10;
    assert!(optimize(&cfg, &mut |_| {}).is_err());
    let mut cfg = OptimizeConfig::new(PaperCase::Walk);
    cfg.polish_share = 2.0;
    assert!(optimize(&cfg, &mut |_| {}).is_err());
}

#[test]
fn phi_evaluator_agrees_with_paper_cost() {
    // On a (briefly) optimised P and on the initial guess, for both cases.
    for case in [PaperCase::Walk, PaperCase::StairUp] {
        let problem = PaperProblem::<f64>::paper(case);
        let opt = solve(case, 3, 300).control_points;
        for p in [opt, problem.initial_guess()] {
            let reference = problem.cost(&p).unwrap();
            let phi: Vec<_> = step_samples(&problem, &p)
                .unwrap()
                .iter()
                .map(|s| s.phi_rad)
                .collect();
            let c = cost_from_phi(&problem, &phi).unwrap();
            let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
            assert!(
                rel(c.j, reference.j) < 1e-9,
                "{case:?}: {} vs {}",
                c.j,
                reference.j
            );
            assert!(rel(c.torque, reference.torque) < 1e-9);
            assert!(rel(c.velocity, reference.velocity) < 1e-9);
            assert!(rel(c.tau_peak_nm, reference.tau_peak_nm) < 1e-9);
            assert_eq!(c.swing_samples, reference.swing_samples);
        }
        // Wrong length is an error, not a panic.
        assert!(cost_from_phi(&problem, &[[0.0; 5]; 3]).is_err());
    }
}
