//! Runs of the fault campaign replayed one by one, shared by the scenarios
//! that pin a campaign's case.

use exogait_device::DeviceConfig;
use gait_control::operator::Gait;
use sim::campaign::{CampaignRun, RunResult, play_with_pilot};
use sim::pilot::PilotConfig;
use sim::scenario::{instant_pilot, strong_pilot};

/// One run of the campaign (`fault` in `sim::inject`'s syntax), as
/// `exogait faults --json` lists it.
pub fn campaign_run(gait: Gait, fault: &str, noise_seed: u64) -> RunResult {
    run_with_pilot(gait, fault, noise_seed, strong_pilot())
}

/// [`campaign_run`] with the pilot who meets a hold at once
/// (`scenario::instant_pilot`), with whom some runs reach their cases:
/// what the campaign tells of a run does not depend on the pilot.
pub fn instant_pilot_run(gait: Gait, fault: &str, noise_seed: u64) -> RunResult {
    run_with_pilot(gait, fault, noise_seed, instant_pilot())
}

fn run_with_pilot(gait: Gait, fault: &str, noise_seed: u64, pilot: PilotConfig) -> RunResult {
    campaign_run_on(
        &DeviceConfig::exogait().unwrap(),
        gait,
        fault,
        noise_seed,
        pilot,
    )
}

/// [`campaign_run`] on `device` with `pilot`: a setting of the device tried
/// on a run of the campaign.
pub fn campaign_run_on(
    device: &DeviceConfig,
    gait: Gait,
    fault: &str,
    noise_seed: u64,
    pilot: PilotConfig,
) -> RunResult {
    let run = CampaignRun {
        gait,
        slot: sim::campaign::built_in_slot(gait),
        fault: fault.parse().unwrap(),
        noise_seed,
    };
    play_with_pilot(&run, device, pilot)
}
