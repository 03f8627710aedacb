//! Playing a fault run on the simulated device and judging it: where the
//! gait was when the fault struck, which legs carried the body after it,
//! what latched before and after.

use exogait_device::DeviceConfig;
use gait_control::sequencer::Phase;

use crate::outcome::{Outcome, outcome};
use crate::pilot::PilotConfig;
use crate::scenario::{run_tables_with, strong_pilot};

use super::parallel::on_every_core;
use super::{CampaignGaits, CampaignRun, RunResult};

/// Plays one run: two steps asked, the run ends 4 s after the fault.
pub fn play(run: &CampaignRun, device: &DeviceConfig) -> RunResult {
    play_with_pilot(run, device, strong_pilot())
}

/// [`play`] with another simulated pilot (the campaign's is
/// [`strong_pilot`]): how the figures depend on what only the simulation
/// has, e.g. the pilot's reaction to a hold (`docs/campaign.md`).
pub fn play_with_pilot(run: &CampaignRun, device: &DeviceConfig, pilot: PilotConfig) -> RunResult {
    play_on(run, device, pilot, &CampaignGaits::built_in())
}

/// [`play_with_pilot`] of a run over `gaits`.
pub fn play_on(
    run: &CampaignRun,
    device: &DeviceConfig,
    pilot: PilotConfig,
    gaits: &CampaignGaits<'_>,
) -> RunResult {
    let fault = run.fault;
    let seed = run.noise_seed;
    let Some(g) = gaits.get(run.slot) else {
        return no_table(run.slot, |outcome, error| RunResult {
            run: *run,
            outcome,
            false_trip: false,
            detected: false,
            error,
            struck_in: None,
            stance_after_strike: [false; 2],
            stance_before_stop: [false; 2],
            carrying_at_strike: [false; 2],
        });
    };
    let played = run_tables_with(
        device,
        g.tables,
        g.gait,
        pilot,
        fault.at_s + 4.0,
        2,
        |rig| {
            rig.set_sensor_noise(3, 10, seed);
            rig.schedule(fault);
        },
    );
    let struck_at = played
        .as_ref()
        .ok()
        .and_then(|r| r.rig.injected().first().map(|&(_, at)| at));
    let after_strike = || {
        played
            .as_ref()
            .ok()
            .zip(struck_at)
            .into_iter()
            .flat_map(|(r, at)| {
                r.rig
                    .trace
                    .iter()
                    .filter(move |s| s.state.time_s >= at - 1e-9)
            })
    };
    let struck_in = after_strike().next().map(|s| s.report.phase);
    let carrying_at_strike = after_strike().next().map_or([false; 2], |s| {
        let [left, right] = s.state.foot_forces_n;
        [left > 0.0 && left >= right, right > 0.0 && right > left]
    });
    let (outcome, injected, error) = judged(played.as_ref());
    // Only a swing before the fall, or before the first stop crossed, can
    // have taken the pilot or a joint there.
    let phases = || after_strike().map(|s| (s.state.time_s, s.report.phase));
    let stance_after_strike = stance_legs_before(phases(), outcome.fell_s);
    let stance_before_stop = stance_legs_before(phases(), outcome.first_stop_crossed_s);
    let before = |t: f64| injected.is_none_or(|i| t < i - 1e-9);
    RunResult {
        run: *run,
        false_trip: outcome.faults.iter().any(|f| before(f.detected_s)),
        detected: outcome.faults.iter().any(|f| !before(f.detected_s)),
        outcome,
        error,
        struck_in,
        stance_after_strike,
        stance_before_stop,
        carrying_at_strike,
    }
}

/// Per leg (left, right): whether it was the stance leg of a swing among
/// `phases` (time, s, and phase) before `until_s` (none: the whole run).
fn stance_legs_before(
    phases: impl Iterator<Item = (f64, Phase)>,
    until_s: Option<f64>,
) -> [bool; 2] {
    let until = until_s.unwrap_or(f64::INFINITY);
    let mut legs = [false; 2];
    for (_, phase) in phases.take_while(|&(t, _)| t < until) {
        if let Phase::Swing { stance, .. } = phase {
            if let Some(l) = legs.get_mut(stance.index()) {
                *l = true;
            }
        }
    }
    legs
}

/// A played run's outcome, when its first injection struck (s), and why
/// the simulation stopped early other than by a fall; a run that could not
/// start has no outcome to speak of and its error.
pub(super) fn judged(
    played: Result<&crate::scenario::StepRun<'_>, &crate::closed_loop::RigError>,
) -> (Outcome, Option<f64>, Option<String>) {
    match played {
        Ok(r) => {
            let o = outcome(&r.rig, r.ended_by.as_ref());
            let injected = r.rig.injected().first().map(|&(_, t)| t);
            let error = match (&r.ended_by, &o.fell) {
                (Some(e), None) => Some(e.to_string()),
                _ => None,
            };
            (o, injected, error)
        }
        Err(e) => (no_outcome(), None, Some(e.to_string())),
    }
}

/// The result `make` builds for a run whose slot holds no gait: no
/// outcome, and that as its error.
pub(super) fn no_table<R>(slot: usize, make: impl FnOnce(Outcome, Option<String>) -> R) -> R {
    make(
        no_outcome(),
        Some(format!("the campaign has no gait in slot {slot}")),
    )
}

/// The outcome of a run that could not start.
pub(super) fn no_outcome() -> Outcome {
    Outcome {
        landings: 0,
        tracking_rms_rad: [0.0; 4],
        tracking_peak_rad: [0.0; 4],
        worst_limit_margin_rad: 0.0,
        worst_limit_joint: 0,
        limit_margins: [(0.0, false); 4],
        first_stop_crossed_s: None,
        fell_s: None,
        braked_joints: [false; 4],
        resisted_at_limit: [false; 4],
        fell: None,
        faults: Vec::new(),
    }
}

/// Plays `runs` on the machine's cores (at most 8 threads; each builds its
/// own rigs), calling `done` after each; the results in the runs' order.
pub fn play_all(
    runs: &[CampaignRun],
    device: &DeviceConfig,
    done: &(dyn Fn() + Sync),
) -> Vec<RunResult> {
    play_all_with_pilot(runs, device, strong_pilot(), done)
}

/// [`play_all`] with another simulated pilot ([`play_with_pilot`]).
pub fn play_all_with_pilot(
    runs: &[CampaignRun],
    device: &DeviceConfig,
    pilot: PilotConfig,
    done: &(dyn Fn() + Sync),
) -> Vec<RunResult> {
    play_all_on(runs, device, pilot, &CampaignGaits::built_in(), done)
}

/// [`play_on`] over `runs` on the machine's cores.
pub fn play_all_on(
    runs: &[CampaignRun],
    device: &DeviceConfig,
    pilot: PilotConfig,
    gaits: &CampaignGaits<'_>,
    done: &(dyn Fn() + Sync),
) -> Vec<RunResult> {
    on_every_core(runs, |r| play_on(r, device, pilot, gaits), done)
}

#[cfg(test)]
mod tests {
    use super::*;
    use gait_control::layout::Side;

    #[test]
    fn a_leg_counts_as_stance_only_in_a_swing_before_the_time_given() {
        let swing = |stance| Phase::Swing { stance, t_s: 0.1 };
        let phases = [
            (1.0, Phase::Standing),
            (1.5, swing(Side::Left)),
            (2.5, swing(Side::Right)),
        ];
        let legs = |crossed| stance_legs_before(phases.into_iter(), crossed);
        assert_eq!(legs(None), [true, true]);
        assert_eq!(legs(Some(2.0)), [true, false]);
        // A swing that starts as the stop is crossed (or the pilot falls)
        // came too late for it.
        assert_eq!(legs(Some(1.5)), [false, false]);
        assert_eq!(legs(Some(3.0)), [true, true]);
    }
}
