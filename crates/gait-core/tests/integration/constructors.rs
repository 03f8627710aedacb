//! gait-core's checked constructors (what a report or a caller may hand in)
//! and the names of P's rows.

use gait_core::foot::{FootError, StanceFoot};
use gait_core::gait::{
    Differences, MAX_SAMPLES, PACE_ROWS, PATH_ROWS, PHI3_ROWS, R2_ROWS, Sampling, SamplingError,
};
use gait_core::ik::{IkOptions, IkOptionsError, KneeRange};
use gait_core::model::JointLimits;
use gait_core::problem::{JointRangeLimit, LimitError, PaperCase, PaperProblem, TIME_ORDERED_ROWS};

#[test]
fn rows_have_the_papers_numbers() {
    assert_eq!(
        (R2_ROWS.start(), R2_ROWS.second(), R2_ROWS.end()),
        (0, 1, 4)
    );
    assert_eq!(
        (PHI3_ROWS.second(), PHI3_ROWS.second_last(), PHI3_ROWS.end()),
        (6, 8, 9)
    );
    assert_eq!((PATH_ROWS.start(), PATH_ROWS.end()), (10, 14));
    assert_eq!(
        (PACE_ROWS.second(), PACE_ROWS.second_last(), PACE_ROWS.end()),
        (16, 17, 18)
    );
    assert_eq!(TIME_ORDERED_ROWS, [[0, 5], [5, 10], [15, 19]]);
}

#[test]
fn foot_is_checked() {
    let f = StanceFoot::<f64>::table_i();
    assert_eq!(
        StanceFoot::new(f.toe_m, f.ankle_height_m, f.heel_off_rad),
        Ok(f)
    );
    assert_eq!(StanceFoot::new(0.0, 0.07, 0.35), Err(FootError::Toe));
    assert_eq!(
        StanceFoot::new(0.14, -0.01, 0.35),
        Err(FootError::AnkleHeight)
    );
    assert_eq!(StanceFoot::new(0.14, 0.07, 2.0), Err(FootError::HeelOff));
    assert_eq!(
        StanceFoot::new(0.14, 0.07, f64::NAN),
        Err(FootError::HeelOff)
    );
}

#[test]
fn ik_options_are_checked() {
    let paper = IkOptions::<f64>::paper();
    assert_eq!(
        IkOptions::new(paper.stance_knee_max_rad, KneeRange::Reach),
        Ok(paper)
    );
    for cap in [0.0, 4.0, f64::NAN] {
        assert_eq!(
            IkOptions::new(cap, KneeRange::Human),
            Err(IkOptionsError::StanceKneeCap)
        );
    }
}

#[test]
fn sampling_is_checked() {
    let n = MAX_SAMPLES - 1;
    assert!(Sampling::new(0.01, n, 2).is_ok());
    assert_eq!(
        Sampling::new(0.01, n + 1, 2001),
        Err(SamplingError::Intervals)
    );
    assert_eq!(Sampling::new(0.01, 1, 2001), Err(SamplingError::Intervals));
    assert_eq!(Sampling::new(-0.01, 224, 2001), Err(SamplingError::Period));
    assert_eq!(Sampling::new(0.01, 224, 1), Err(SamplingError::Grid));
    let paper = Sampling::<f64>::paper(2.24);
    assert_eq!(
        Sampling::new(paper.dt_s, paper.intervals, paper.grid),
        Ok(paper)
    );
}

#[test]
fn joint_range_limit_is_checked() {
    let limits = JointLimits::<f64>::paper_table_i();
    assert!(JointRangeLimit::new(limits, 0.1, 1e5).is_ok());
    assert_eq!(
        JointRangeLimit::new(limits, -0.1, 1e5),
        Err(LimitError::Margin)
    );
    assert_eq!(
        JointRangeLimit::new(limits, 0.1, f64::INFINITY),
        Err(LimitError::Weight)
    );
}

#[test]
fn differences_round_trip_by_name() {
    for d in [Differences::Backward, Differences::Central] {
        assert_eq!(Differences::from_name(d.name()), Some(d));
    }
    assert_eq!(Differences::from_name("forward"), None);
}

#[test]
fn a_stored_copy_of_the_bounds_is_compared_entry_by_entry() {
    let p = PaperProblem::<f64>::paper(PaperCase::Walk);
    let (lo, mut hi) = p.bounds();
    assert!(p.check_bounds_copy(&lo, &hi).is_ok());
    hi[11][1] = 0.9;
    let m = p.check_bounds_copy(&lo, &hi).unwrap_err();
    assert!(m.upper && m.row == 11 && m.col == 1 && m.stored == 0.9);
}
