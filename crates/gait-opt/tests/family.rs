//! A patient's family is cleared only where the closed loop keeps every hip
//! and knee inside Table I's stops (`family::STOP_MARGIN_RAD`).

use exogait_device::DeviceConfig;
use exogait_device::fitting::{Measures, fit};
use gait_core::tables::GaitKind;
use gait_core::tables::GaitTable;
use gait_opt::family::{DEFAULT_EVALS, Outcome, STOP_MARGIN_RAD, design, stair_plan};
use sim::compare::{RunLength, play_for};
use sim::scenario::strong_pilot;

/// The 1.60 m, 55 kg patient's 0.18 m descent at the pace asked takes the
/// trailing knee a little past its extension stop (0°) in the closed loop:
/// not cleared so. Its slower attempt is, with every joint inside.
#[test]
fn a_descent_that_takes_a_knee_past_its_stop_is_cleared_only_slower() {
    let device = DeviceConfig::exogait().unwrap();
    let patient = fit(
        &device,
        &Measures {
            height_m: 1.60,
            mass_kg: 55.0,
            thigh_m: None,
            shank_m: None,
            foot_m: None,
        },
    )
    .unwrap();
    let fitted = device.fitted(&patient.model).unwrap();
    let plan = stair_plan(GaitKind::StairDown, 0.18, 0.28);
    let Outcome::Cleared(gait) = design(&plan, &fitted, DEFAULT_EVALS) else {
        panic!("the 0.18 m descent is not cleared at all");
    };
    assert!(
        gait.plan.step_time_s > plan.step_time_s + 0.1,
        "cleared at the pace asked: {} s",
        gait.plan.step_time_s
    );
    let table = GaitTable::parse(&gait.image).unwrap();
    let (_, rig) = play_for(
        &fitted,
        table,
        strong_pilot(),
        RunLength {
            steps: 4,
            max_s: 30.0,
            tail_s: 1.5,
        },
        |_| {},
    )
    .unwrap();
    let o = sim::outcome::outcome(&rig, None);
    assert!(
        o.worst_limit_margin_rad >= STOP_MARGIN_RAD,
        "{} rad",
        o.worst_limit_margin_rad
    );
}
