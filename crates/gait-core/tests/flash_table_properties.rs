//! What the device relies on in the tables it carries: each step chains into
//! the next with the legs swapped (periodic), and no hip or knee is asked to
//! move faster than the supervisor allows, with margin for tracking.
#![allow(clippy::expect_used, clippy::indexing_slicing)]

use gait_core::flash_tables;
use gait_core::kinematics::{swap_legs, theta_from_phi, wrap_pi};
use gait_core::tables::GaitTable;

fn tables() -> [(&'static str, GaitTable<'static>); 2] {
    [
        ("walk", flash_tables::walk().expect("walk table verifies")),
        (
            "stair_up",
            flash_tables::stair_up().expect("stair table verifies"),
        ),
    ]
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
    // overshoot, never more than 4.
    for (name, t) in tables() {
        let dt = t.period_s();
        let mut prev: Option<[f32; 5]> = None;
        for k in 0..t.len() {
            let theta = theta_from_phi(&t.sample(k).expect("in range"));
            if let Some(p) = prev {
                for j in 1..5 {
                    let rate = (theta[j] - p[j]).abs() / dt;
                    assert!(rate < 4.0, "{name}: joint {j} at sample {k}: {rate} rad/s");
                }
            }
            prev = Some(theta);
        }
    }
}
