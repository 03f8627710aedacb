//! Healthy runs: each gait with sensor noise and no fault, in which
//! anything latched is a false trip.

use exogait_device::DeviceConfig;
use gait_control::operator::Gait;

use crate::outcome::Outcome;
use crate::scenario::{run_tables_with, strong_pilot};

use super::CampaignGaits;
use super::parallel::on_every_core;
use super::play::{judged, no_table};

/// Steps a healthy run asks for: the third is the first taken from a
/// steady stance (the first two start and follow the start from standing).
pub const HEALTHY_STEPS: usize = 3;

/// One healthy run: a gait with sensor noise and no fault.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HealthyRun {
    /// The gait's movement.
    pub gait: Gait,
    /// The gait itself: its slot in the campaign's gaits
    /// ([`super::CampaignGaits`]).
    pub slot: usize,
    /// Seed of the sensor noise (±3 encoder, ±10 ADC counts).
    pub noise_seed: u64,
}

/// What a healthy run gave.
#[derive(Clone, Debug, PartialEq)]
pub struct HealthyResult {
    /// The plan.
    pub run: HealthyRun,
    /// Its outcome (any fault in it is a false trip).
    pub outcome: Outcome,
    /// Why the simulation stopped early, if it did (other than a fall).
    pub error: Option<String>,
}

impl HealthyResult {
    /// Something latched although nothing was wrong.
    pub fn false_trip(&self) -> bool {
        !self.outcome.faults.is_empty()
    }

    /// Fewer landings than steps asked.
    pub fn short(&self) -> bool {
        self.outcome.landings < HEALTHY_STEPS
    }

    /// Fell, crossed a stop, tripped, stopped short or could not finish.
    pub fn bad(&self) -> bool {
        self.outcome.fell.is_some()
            || self.outcome.worst_limit_margin_rad < 0.0
            || self.false_trip()
            || self.short()
            || self.error.is_some()
    }
}

/// Plays one healthy run of the device's own gaits: [`HEALTHY_STEPS`]
/// steps and 1.5 s standing.
pub fn play_healthy(run: &HealthyRun, device: &DeviceConfig) -> HealthyResult {
    play_healthy_on(run, device, &CampaignGaits::built_in())
}

/// [`play_healthy`] of a run over `gaits`.
pub fn play_healthy_on(
    run: &HealthyRun,
    device: &DeviceConfig,
    gaits: &CampaignGaits<'_>,
) -> HealthyResult {
    let seed = run.noise_seed;
    let Some(g) = gaits.get(run.slot) else {
        return no_table(run.slot, |outcome, error| HealthyResult {
            run: *run,
            outcome,
            error,
        });
    };
    let played = run_tables_with(
        device,
        g.tables,
        g.gait,
        strong_pilot(),
        25.0,
        HEALTHY_STEPS,
        |rig| rig.set_sensor_noise(3, 10, seed),
    );
    let (outcome, _, error) = judged(played.as_ref());
    HealthyResult {
        run: *run,
        outcome,
        error,
    }
}

/// [`play_healthy`] over `runs` on the machine's cores.
pub fn play_all_healthy(
    runs: &[HealthyRun],
    device: &DeviceConfig,
    done: &(dyn Fn() + Sync),
) -> Vec<HealthyResult> {
    play_all_healthy_on(runs, device, &CampaignGaits::built_in(), done)
}

/// [`play_healthy_on`] over `runs` on the machine's cores.
pub fn play_all_healthy_on(
    runs: &[HealthyRun],
    device: &DeviceConfig,
    gaits: &CampaignGaits<'_>,
    done: &(dyn Fn() + Sync),
) -> Vec<HealthyResult> {
    on_every_core(runs, |r| play_healthy_on(r, device, gaits), done)
}
