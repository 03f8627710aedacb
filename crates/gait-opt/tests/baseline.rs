//! Baseline construction from the shared gait data.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use gait_core::kinematics::forward_kinematics;
use gait_core::problem::{PaperCase, PaperProblem};
use gait_opt::{BaselineError, Source, baseline, baseline_from, cost_from_phi, default_data_dir};

#[test]
fn baselines_start_and_land_on_the_case_points() {
    let dir = default_data_dir();
    for (case, src) in [
        (PaperCase::Walk, Source::Fukuchi2018Walk),
        (PaperCase::Walk, Source::WinterWalk),
        (PaperCase::Walk, Source::ViconWalk),
        (PaperCase::StairUp, Source::ReznickStairI20),
        (PaperCase::StairUp, Source::RienerStairAscent),
    ] {
        let b = baseline_from(case, src, &dir).unwrap();
        let pr = PaperProblem::<f64>::paper(case);
        assert_eq!(b.phi.len(), pr.sampling.intervals + 1);
        let p0 = forward_kinematics(&pr.model, b.phi.first().unwrap())[4];
        let pn = forward_kinematics(&pr.model, b.phi.last().unwrap())[4];
        for (got, want) in [(p0, pr.case.start_m), (pn, pr.case.landing_m)] {
            assert!(
                (got[0] - want[0]).abs() < 1e-9 && (got[1] - want[1]).abs() < 1e-9,
                "{src:?}: {got:?} vs {want:?}"
            );
        }
        // Torso upright throughout.
        assert!(b.phi.iter().all(|p| p[2] == 0.0));
        let c = b.cost.unwrap();
        assert!(c.j.is_finite() && c.j > 0.0);
        assert_eq!(cost_from_phi(&pr, &b.phi).unwrap(), c);
        // The swing is a real swing: most samples count (c_k = 1).
        assert!(
            c.swing_samples > pr.sampling.intervals / 2,
            "{src:?}: {}",
            c.swing_samples
        );
    }
}

#[test]
fn primary_baselines_and_their_costs() {
    let w = baseline(PaperCase::Walk).unwrap();
    assert_eq!(w.source, Source::Fukuchi2018Walk);
    let s = baseline(PaperCase::StairUp).unwrap();
    assert_eq!(s.source, Source::ReznickStairI20);
    // The human gaits pay far more torque than the records the optimiser beats.
    assert!(w.cost.unwrap().j > 3361.9);
    assert!(s.cost.unwrap().j > 1476.6);
}

#[test]
fn wrong_case_and_missing_data_are_errors() {
    let dir = default_data_dir();
    assert!(matches!(
        baseline_from(PaperCase::StairUp, Source::Fukuchi2018Walk, &dir),
        Err(BaselineError::WrongCase(..))
    ));
    let err = baseline_from(
        PaperCase::Walk,
        Source::Fukuchi2018Walk,
        std::path::Path::new("/nonexistent"),
    )
    .unwrap_err();
    assert!(
        err.to_string()
            .contains("fukuchi2018_walk_mean_sd_2pct.csv"),
        "{err}"
    );
}

#[test]
fn baseline_torque_has_no_interpolation_spikes() {
    // Reference curves are interpolated by a C² periodic spline; linear
    // interpolation made every 2 % knot a torque spike of tens of N·m.
    for case in [PaperCase::Walk, PaperCase::StairUp] {
        let b = baseline(case).unwrap();
        let pr = PaperProblem::<f64>::paper(case);
        let taus: Vec<f64> = gait_opt::phi_cost::phi_samples(&pr, &b.phi)
            .iter()
            .filter_map(|s| s.torque.map(|t| t[0]))
            .collect();
        let jump = taus
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max);
        println!("{case:?}: max |Δτ| = {jump}");
        assert!(jump < 5.0, "{case:?}: max |Δτ| = {jump} N·m");
    }
}
