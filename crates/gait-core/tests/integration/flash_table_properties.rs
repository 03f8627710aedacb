//! What the device relies on in the tables it carries: each step chains into
//! the next with the legs swapped (periodic), and no hip or knee is asked to
//! move faster than the supervisor allows, with margin for tracking.

use gait_core::flash_tables;
use gait_core::kinematics::{swap_legs, theta_from_phi, wrap_pi};
use gait_core::tables::GaitTable;

fn tables() -> [(&'static str, GaitTable<'static>); 3] {
    [
        ("walk", flash_tables::walk().expect("walk table verifies")),
        (
            "stair_up",
            flash_tables::stair_up().expect("stair table verifies"),
        ),
        (
            "stair_down",
            flash_tables::stair_down().expect("descent table verifies"),
        ),
    ]
}

/// The descent table's feet: the front foot flat at the start (on the
/// tread below), and the stance knee within the supervisor's 95° all along.
#[test]
fn descent_table_starts_flat_and_keeps_the_knee_in_range() {
    use gait_core::foot::StanceFoot;
    let t = flash_tables::stair_down().expect("descent table verifies");
    let foot = StanceFoot::<f32>::table_i();
    assert!(!foot.on_toe(t.first()[0]));
    for k in 0..t.len() {
        let phi = t.sample(k).expect("in range");
        let knee = (phi[0] - phi[1]).to_degrees();
        assert!(
            (-1.0..95.0).contains(&knee),
            "sample {k}: stance knee {knee}°"
        );
    }
}

#[test]
fn every_flash_table_lands_in_its_own_start_posture() {
    for (name, t) in tables() {
        let next = swap_legs(&t.last());
        for (a, b) in next.iter().zip(&t.first()) {
            // f32 tables: a few 1e-6 rad of rounding.
            assert!(
                wrap_pi(a - b).abs() < 1e-4,
                "{name}: {next:?} vs {:?}",
                t.first()
            );
        }
    }
}

#[test]
fn hip_and_knee_speeds_stay_well_inside_the_supervisor_limits() {
    // Supervisor limits: 6 rad/s hips, 8 rad/s knees. The tables are
    // optimised with a soft limit at 3 rad/s; allow the optimiser's small
    // overshoot (3.2 rad/s today), never more than 3.5.
    for (name, t) in tables() {
        let dt = t.period_s();
        let mut prev: Option<[f32; 5]> = None;
        for k in 0..t.len() {
            let theta = theta_from_phi(&t.sample(k).expect("in range"));
            if let Some(p) = prev {
                for j in 1..5 {
                    let rate = (theta[j] - p[j]).abs() / dt;
                    assert!(rate < 3.5, "{name}: joint {j} at sample {k}: {rate} rad/s");
                }
            }
            prev = Some(theta);
        }
    }
}

/// The tables leave and reach the standing posture slowly. Not at rest:
/// the pilot's stance shank still moves at the ends (0.10 rad/s at the
/// walk's start, 0.14 rad/s at its landing, the paper's logistic), and at
/// the walk's start the trailing leg is straight, at the IK's stretch
/// boundary, so that small shank motion turns into 1.5 rad/s of swing knee
/// (docs/model.md, "Periodic steps"). These bounds pin today's values so a
/// regenerated table that starts with a jump fails here.
#[test]
fn tables_leave_and_reach_the_standing_posture_slowly() {
    for (name, t) in tables() {
        let dt = t.period_s();
        let n = t.len();
        for (a, b, bound) in [(0, 1, 1.6), (n - 2, n - 1, 1.1)] {
            let ta = theta_from_phi(&t.sample(a).expect("in range"));
            let tb = theta_from_phi(&t.sample(b).expect("in range"));
            for j in 1..5 {
                let rate = (tb[j] - ta[j]).abs() / dt;
                assert!(
                    rate < bound,
                    "{name}: joint {j} between samples {a} and {b}: {rate} rad/s"
                );
            }
        }
    }
}
