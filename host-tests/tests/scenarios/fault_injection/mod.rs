//! Fault injection in the closed loop, by name (`sim::inject`), on the
//! device as shipped: healthy runs with sensor noise never trip, and an
//! encoder step the joint could not have made is a jump fault however the
//! frames around it went (docs/safety.md, "Fault injection from the command
//! line").

mod braking;
mod detection;
mod estop_and_restart;
mod landing;
mod named_cases;
mod pilot;

use exogait_device::DeviceConfig;
use gait_control::operator::Gait;
use sim::inject::Injection;
use sim::outcome::outcome;
use sim::scenario::{StepRun, run_gait_on};

use crate::common::campaign_run;

/// The outcome of [`run_faulted`] on the device as shipped.
fn run(
    gait: Gait,
    steps: usize,
    max_s: f64,
    noise_seed: Option<u64>,
    faults: &[&str],
) -> sim::outcome::Outcome {
    let device = DeviceConfig::exogait().unwrap();
    let run = run_faulted(&device, gait, max_s, steps, noise_seed, faults);
    outcome(&run.rig, run.ended_by.as_ref())
}

/// `gait` on `device` with its flash tables and the campaign's pilot, the
/// `faults` (in `sim::inject`'s syntax) scheduled and, given a seed, the
/// sensors' noise on: GO, then steps until `steps` landings and 1.5 s more
/// (`sim::scenario::run_gait_on`).
fn run_faulted(
    device: &DeviceConfig,
    gait: Gait,
    max_s: f64,
    steps: usize,
    noise_seed: Option<u64>,
    faults: &[&str],
) -> StepRun<'static> {
    let injections: Vec<Injection> = faults.iter().map(|f| f.parse().unwrap()).collect();
    run_gait_on(device, gait, max_s, steps, |rig| {
        if let Some(seed) = noise_seed {
            rig.set_sensor_noise(3, 10, seed);
        }
        for f in injections {
            rig.schedule(f);
        }
    })
    .unwrap()
}

/// Each of seed 1's campaign runs (`fault`, noise seed) of `gait` lands a
/// step, and the pilot stands with no hip or knee past its stop.
fn stands_clear_of_the_stops(gait: Gait, runs: &[(&str, u64)]) {
    for &(fault, seed) in runs {
        let o = campaign_run(gait, fault, seed).outcome;
        assert!(o.fell.is_none(), "{fault}: {o:?}");
        assert!(o.worst_limit_margin_rad > 0.0, "{fault}: {o:?}");
        assert!(o.landings >= 1, "{fault}: {o:?}");
    }
}
