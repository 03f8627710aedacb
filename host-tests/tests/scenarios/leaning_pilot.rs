//! A pilot off the plan, on the encoders the device has. With their noise,
//! the tables carry a pilot leaning 2° forward on the flat and 4° forward
//! on stairs through every step, with no fault; a stance foot placed off
//! is carried to every foothold. (Without noise,
//! a joint the closed chain of a weight transfer holds still reads the
//! same counts tick after tick, which the frozen-encoder rule, 0x0204,
//! cannot tell from a frozen encoder; a real encoder never repeats a count
//! so: `docs/replanning.md`.)

use exogait_device::DeviceConfig;
use gait_core::flash_tables;
use gait_core::tables::GaitTable;
use sim::compare::play;
use sim::pilot::PilotConfig;
use sim::scenario::strong_pilot;

/// ±3 counts on every encoder, ±10 on the force ADC: the campaigns' noise.
const ENCODER_NOISE: u16 = 3;
const ADC_NOISE: u16 = 10;

fn walks_on_leaning(name: &str, table: GaitTable<'static>, lean_deg: f64) {
    let device = DeviceConfig::exogait().unwrap();
    let pilot = PilotConfig {
        habit_lean_rad: lean_deg.to_radians(),
        ..strong_pilot()
    };
    let (run, _) = play(&device, table, pilot, 4, 40.0, |rig| {
        rig.set_sensor_noise(ENCODER_NOISE, ADC_NOISE, 2026);
    })
    .unwrap();
    assert!(
        run.faults.is_empty(),
        "{name}, {lean_deg}°: {:?}",
        run.faults
    );
    assert_eq!(run.landed(), 4, "{name}, {lean_deg}°: {:?}", run.ended_by);
}

#[test]
fn a_pilot_leaning_forward_walks_every_step_on_the_tables() {
    walks_on_leaning("walk", flash_tables::walk().unwrap(), 2.0);
    walks_on_leaning("stair ascent", flash_tables::stair_up().unwrap(), 4.0);
    walks_on_leaning("stair descent", flash_tables::stair_down().unwrap(), 4.0);
}

#[test]
fn a_stance_foot_placed_off_is_carried_to_every_foothold() {
    // The pilot starts with the stance foot 2 cm forward under the body.
    // Each step lands about as planned from the one before, the first
    // from that foot, so every foothold keeps the offset: the board sees
    // the joints, not the floor.
    let device = DeviceConfig::exogait().unwrap();
    let table = flash_tables::walk().unwrap();
    let (run, _) = play(&device, table, strong_pilot(), 4, 40.0, |rig| {
        rig.place_stance_foot(0.02).unwrap();
        rig.set_sensor_noise(ENCODER_NOISE, ADC_NOISE, 2026);
    })
    .unwrap();
    assert_eq!(run.landed(), 4, "{:?}", run.ended_by);
    for (i, s) in run.steps.iter().enumerate() {
        let step = s.step_error_m.unwrap().abs();
        let foothold = s.landing_error_m.unwrap();
        assert!(step < 0.01, "step {i}: {step} m from the foot before");
        assert!(
            (0.015..0.04).contains(&foothold),
            "step {i}: foothold off by {foothold} m"
        );
    }
}
