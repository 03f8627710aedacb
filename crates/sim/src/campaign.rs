//! A seeded randomised fault campaign: each run walks, climbs or descends
//! with sensor noise and one fault of a random kind, target, value and time
//! (standing, in a swing or in a weight transfer), and is judged by
//! [`crate::outcome`]. Beside it, healthy runs of each gait with sensor
//! noise and no fault, in which anything latched is a false trip. The same
//! seed gives the same runs. `exogait faults` and the campaign tests run
//! them; docs/safety.md has the figures.

mod named;

pub use named::{NamedCase, explains_stop, named_case};

use exogait_device::DeviceConfig;
use gait_control::faults::FaultCode;
use gait_control::operator::Gait;
use gait_control::sequencer::Phase;

use crate::inject::{Injection, Kind, Target};
use crate::outcome::{Outcome, outcome};
use crate::pilot::PilotConfig;
use crate::scenario::{flash_tables, run_tables_with, strong_pilot};

/// One planned run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CampaignRun {
    /// The gait.
    pub gait: Gait,
    /// The fault.
    pub fault: Injection,
    /// Seed of the sensor noise (±3 encoder, ±10 ADC counts).
    pub noise_seed: u64,
}

/// What one run gave.
#[derive(Clone, Debug, PartialEq)]
pub struct RunResult {
    /// The plan.
    pub run: CampaignRun,
    /// Its outcome.
    pub outcome: Outcome,
    /// A fault latched before the injection: a false trip.
    pub false_trip: bool,
    /// Some fault latched at or after the injection.
    pub detected: bool,
    /// Why the simulation stopped early, if it did (other than a fall).
    pub error: Option<String>,
    /// Where the gait was when the fault struck.
    pub struck_in: Option<Phase>,
    /// Per leg (left, right): it was the stance leg of a swing at or after
    /// the strike and before the fall, if any (a drive lost before that
    /// swing is lost in it too): what tells the run's fall.
    pub stance_after_strike: [bool; 2],
    /// The same, but only swings before the run's first stop crossed:
    /// what tells its stops crossed (a later swing cannot have taken a
    /// joint there).
    pub stance_before_stop: [bool; 2],
    /// Per leg (left, right): its foot carried the larger share of the body
    /// when the fault struck (the simulator's truth).
    pub carrying_at_strike: [bool; 2],
}

impl RunResult {
    /// A kind the supervisor must detect was not detected.
    pub fn missed(&self) -> bool {
        must_be_detected(self.run.fault.kind) && !self.detected
    }

    /// The named case this run's fall belongs to, if it fell in one.
    pub fn named_fall(&self) -> Option<NamedCase> {
        self.outcome.fell.as_ref().and_then(|_| {
            named_case(
                &self.run,
                self.struck_in,
                self.stance_after_strike,
                self.carrying_at_strike,
            )
            .filter(|_| self.drives_off_by(self.outcome.fell_s))
        })
    }

    /// Whether an e-stop run's drives were off (its safe state reached)
    /// by `at_s`, when what is told happened: the e-stop's cases rest on
    /// every drive disabled and braked, and in a swing the drives first set
    /// the foot down (`docs/safety.md`, "The e-stop in a swing"), which is
    /// the device's doing. True for every other kind.
    fn drives_off_by(&self, at_s: Option<f64>) -> bool {
        if !matches!(self.run.fault.kind, Kind::EStop | Kind::EStopRead) {
            return true;
        }
        let off_s = self
            .outcome
            .faults
            .iter()
            .filter(|f| matches!(f.code, FaultCode::EStopPressed | FaultCode::EStopInputFault))
            .filter_map(|f| f.safe_state_s)
            .reduce(f64::min);
        match (off_s, at_s) {
            (Some(off), Some(at)) => at >= off - 1e-9,
            _ => false,
        }
    }

    /// The pilot fell, and not in a named case: the device's to fix.
    pub fn unnamed_fall(&self) -> bool {
        self.outcome.fell.is_some() && self.named_fall().is_none()
    }

    /// A hip or knee crossed its stop.
    pub fn past_a_stop(&self) -> bool {
        self.outcome.worst_limit_margin_rad < 0.0
    }

    /// The named case whose physical reason took every joint that crossed
    /// a stop past it ([`explains_stop`]), if the run crossed one.
    pub fn named_stop(&self) -> Option<NamedCase> {
        let crossed = || {
            (0..4)
                .zip(self.outcome.limit_margins)
                .filter(|(_, (m, _))| *m < 0.0)
        };
        let named = named_case(
            &self.run,
            self.struck_in,
            self.stance_before_stop,
            self.carrying_at_strike,
        );
        named
            .filter(|_| self.past_a_stop())
            .filter(|_| self.drives_off_by(self.outcome.first_stop_crossed_s))
            .filter(|&c| {
                crossed().all(|(j, (_, flexion))| {
                    let o = &self.outcome;
                    let gave_all = o.resisted_at_limit.get(j) == Some(&true);
                    explains_stop(c, &self.run, j, flexion, gave_all)
                })
            })
    }

    /// A joint crossed its stop, and not for a named case's reason: the
    /// device's to fix.
    pub fn unnamed_stop(&self) -> bool {
        self.past_a_stop() && self.named_stop().is_none()
    }
}

/// Kinds every run must detect: those whose fault the table promises to
/// see whatever the gait is doing. (A glitch or a spike is tolerated by
/// design; a weak motor or a stuck bridge is found once its current departs
/// from its command, a frozen encoder while its joint is driven, the
/// pilot's lean through its consequences.)
pub fn must_be_detected(kind: Kind) -> bool {
    matches!(
        kind,
        Kind::EncoderBus
            | Kind::EncoderParity
            | Kind::EncoderErrorFlag
            | Kind::EncoderJump(_)
            | Kind::FsrOpen
            | Kind::FsrShort
            | Kind::AdcBus
            | Kind::PwmFail
            | Kind::CurrentOpen
            | Kind::CurrentShort
            | Kind::EStop
            | Kind::EStopRead
            | Kind::ButtonRead
            | Kind::Overrun(_)
    )
}

/// A seeded xorshift generator (as [`crate::noise`]: a fixed sequence per
/// seed across library versions).
struct Draw(u64);

impl Draw {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    fn below(&mut self, n: usize) -> usize {
        (self.unit() * n as f64) as usize % n.max(1)
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// The `runs` runs of campaign `seed`.
pub fn plan(seed: u64, runs: usize) -> Vec<CampaignRun> {
    let mut d = Draw(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    for _ in 0..8 {
        d.next();
    }
    (0..runs)
        .map(|_| {
            let gait = [Gait::Walk, Gait::StairUp, Gait::StairDown][d.below(3)];
            let joint = Target::Joint(d.below(4));
            let encoder = if d.below(3) == 0 {
                Target::Ankle(d.below(2))
            } else {
                joint
            };
            let force = Target::Force(d.below(4));
            let sign = if d.below(2) == 0 { -1 } else { 1 };
            let (kind, target) = match d.below(24) {
                0 => (Kind::EncoderBus, Some(encoder)),
                1 => (Kind::EncoderParity, Some(encoder)),
                2 => (Kind::EncoderErrorFlag, Some(encoder)),
                3 => (Kind::EncoderStuck, Some(encoder)),
                4 => (
                    Kind::EncoderJump(sign * (110 + d.below(400)) as i32),
                    Some(joint),
                ),
                5 => (
                    Kind::EncoderGlitch(sign * (200 + d.below(3000)) as i32),
                    Some(encoder),
                ),
                6 => (Kind::FsrOpen, Some(force)),
                7 => (Kind::FsrShort, Some(force)),
                8 => (Kind::FsrOverRange, Some(force)),
                9 => (Kind::FsrSpike(d.range(100.0, 500.0)), Some(force)),
                10 => (Kind::AdcBus, None),
                11 => (Kind::MotorWeak(d.range(0.2, 0.8)), Some(joint)),
                12 => (Kind::MotorStuck, Some(joint)),
                13 => (Kind::PwmFail, Some(joint)),
                14 => (Kind::DirFail, Some(joint)),
                15 => (Kind::EStop, None),
                16 => (Kind::EStopRead, None),
                17 => (Kind::ButtonRead, None),
                18 => (Kind::Overrun(3 + d.below(8) as u32), None),
                19 => (Kind::PilotLean(d.range(0.05, 0.2)), None),
                20 => (Kind::PilotStopsBalancing, None),
                21 => (Kind::CurrentOpen, Some(joint)),
                22 => (Kind::GearSlip(d.range(0.2, 0.8)), Some(joint)),
                _ => (Kind::CurrentShort, Some(joint)),
            };
            // Standing before GO, then anywhere in the first two steps.
            let at_s = (d.range(0.3, 5.0) * 1000.0).round() / 1000.0;
            CampaignRun {
                gait,
                fault: Injection { kind, target, at_s },
                noise_seed: d.next() % 1_000_000,
            }
        })
        .collect()
}

/// Plays one run: two steps asked, the run ends 4 s after the fault.
pub fn play(run: &CampaignRun, device: &DeviceConfig) -> RunResult {
    play_with_pilot(run, device, strong_pilot())
}

/// [`play`] with another simulated pilot (the campaign's is
/// [`strong_pilot`]): how the figures depend on what only the simulation
/// has, e.g. the pilot's reaction to a hold (`docs/safety.md`).
pub fn play_with_pilot(run: &CampaignRun, device: &DeviceConfig, pilot: PilotConfig) -> RunResult {
    let fault = run.fault;
    let seed = run.noise_seed;
    let played = run_tables_with(
        device,
        flash_tables(),
        run.gait,
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
fn judged(
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
    on_every_core(runs, |r| play_with_pilot(r, device, pilot), done)
}

/// `each` over `items` on the machine's cores (at most 8 threads), calling
/// `done` after each; the results in the items' order. A worker that
/// panicked loses its items; the result is then shorter than `items`,
/// which the callers check.
fn on_every_core<T: Sync, R: Send>(
    items: &[T],
    each: impl Fn(&T) -> R + Sync,
    done: &(dyn Fn() + Sync),
) -> Vec<R> {
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get().clamp(1, 8));
    let each = &each;
    let mut parts: Vec<Vec<(usize, R)>> = Vec::new();
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                s.spawn(move || {
                    items
                        .iter()
                        .enumerate()
                        .skip(w)
                        .step_by(workers)
                        .map(|(i, item)| {
                            let result = each(item);
                            done();
                            (i, result)
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for h in handles {
            if let Ok(part) = h.join() {
                parts.push(part);
            }
        }
    });
    let mut all: Vec<(usize, R)> = parts.into_iter().flatten().collect();
    all.sort_by_key(|(i, _)| *i);
    all.into_iter().map(|(_, r)| r).collect()
}

/// Steps a healthy run asks for: the third is the first taken from a
/// steady stance (the first two start and follow the start from standing).
pub const HEALTHY_STEPS: usize = 3;

/// One healthy run: a gait with sensor noise and no fault.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HealthyRun {
    /// The gait.
    pub gait: Gait,
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

/// `per_gait` healthy runs of each gait, the noise seeds drawn from
/// `seed` (the same seed gives the same runs; none is a fault run's).
pub fn healthy_plan(seed: u64, per_gait: usize) -> Vec<HealthyRun> {
    let mut d = Draw(seed.wrapping_mul(0xD1B5_4A32_D192_ED03) | 1);
    for _ in 0..8 {
        d.next();
    }
    [Gait::Walk, Gait::StairUp, Gait::StairDown]
        .into_iter()
        .flat_map(|gait| (0..per_gait).map(move |_| gait))
        .map(|gait| HealthyRun {
            gait,
            noise_seed: d.next() % 1_000_000,
        })
        .collect()
}

/// Plays one healthy run: [`HEALTHY_STEPS`] steps and 1.5 s standing.
pub fn play_healthy(run: &HealthyRun, device: &DeviceConfig) -> HealthyResult {
    let seed = run.noise_seed;
    let played = run_tables_with(
        device,
        flash_tables(),
        run.gait,
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
    on_every_core(runs, |r| play_healthy(r, device), done)
}

/// The outcome of a run that could not start.
fn no_outcome() -> Outcome {
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

/// Counts over a campaign, per kind and in all.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tally {
    /// Runs.
    pub runs: usize,
    /// Runs in which the pilot fell.
    pub falls: usize,
    /// Of them, falls outside the cases named with their physical reason
    /// ([`NamedCase`]): the device's to fix.
    pub unnamed_falls: usize,
    /// Runs in which a hip or knee went past its Table I stop.
    pub past_a_stop: usize,
    /// Of them, runs whose stop no named case explains: the device's.
    pub unnamed_past_a_stop: usize,
    /// Runs of a must-detect kind that nothing detected.
    pub missed: usize,
    /// Runs with a fault latched before the injection.
    pub false_trips: usize,
    /// Runs the simulation could not finish (not a fall).
    pub errors: usize,
}

impl Tally {
    /// Adds one run.
    pub fn add(&mut self, r: &RunResult) {
        self.runs += 1;
        self.falls += usize::from(r.outcome.fell.is_some());
        self.unnamed_falls += usize::from(r.unnamed_fall());
        self.past_a_stop += usize::from(r.past_a_stop());
        self.unnamed_past_a_stop += usize::from(r.unnamed_stop());
        self.missed += usize::from(r.missed());
        self.false_trips += usize::from(r.false_trip);
        self.errors += usize::from(r.error.is_some());
    }
}

/// The tally of `results` per kind name, in the order kinds first appear,
/// and over all.
pub fn tally(results: &[RunResult]) -> (Vec<(&'static str, Tally)>, Tally) {
    grouped(results, |r| r.run.fault.kind.name(), Tally::add)
}

/// `results` added up per `key`, in the order keys first appear, and over
/// all.
fn grouped<R, K: PartialEq, T: Default>(
    results: &[R],
    key: impl Fn(&R) -> K,
    add: impl Fn(&mut T, &R),
) -> (Vec<(K, T)>, T) {
    let mut by: Vec<(K, T)> = Vec::new();
    let mut all = T::default();
    for r in results {
        let k = key(r);
        match by.iter_mut().find(|(n, _)| *n == k) {
            Some((_, t)) => add(t, r),
            None => {
                let mut t = T::default();
                add(&mut t, r);
                by.push((k, t));
            }
        }
        add(&mut all, r);
    }
    (by, all)
}

/// Counts over healthy runs, per gait and in all.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HealthyTally {
    /// Runs.
    pub runs: usize,
    /// Runs in which the pilot fell.
    pub falls: usize,
    /// Runs in which a hip or knee went past its Table I stop.
    pub past_a_stop: usize,
    /// Runs in which anything latched.
    pub false_trips: usize,
    /// Runs with fewer landings than steps asked.
    pub short: usize,
    /// Runs the simulation could not finish (not a fall).
    pub errors: usize,
}

impl HealthyTally {
    /// Adds one run.
    pub fn add(&mut self, r: &HealthyResult) {
        self.runs += 1;
        self.falls += usize::from(r.outcome.fell.is_some());
        self.past_a_stop += usize::from(r.outcome.worst_limit_margin_rad < 0.0);
        self.false_trips += usize::from(r.false_trip());
        self.short += usize::from(r.short());
        self.errors += usize::from(r.error.is_some());
    }
}

/// The tally of healthy `results` per gait, in the order gaits first
/// appear, and over all.
pub fn healthy_tally(results: &[HealthyResult]) -> (Vec<(Gait, HealthyTally)>, HealthyTally) {
    grouped(results, |r| r.run.gait, HealthyTally::add)
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

    /// A descent's e-stop run that fell (or crossed a knee's flexion stop)
    /// at `at_s`, its drives off at `off_s`.
    fn estop_run(at_s: f64, off_s: Option<f64>) -> RunResult {
        let mut outcome = no_outcome();
        outcome.fell = Some("fell: hip 0.400 m high".into());
        outcome.fell_s = Some(at_s);
        outcome.worst_limit_margin_rad = -0.01;
        outcome.worst_limit_joint = 1;
        outcome.limit_margins[1] = (-0.01, true);
        outcome.first_stop_crossed_s = Some(at_s);
        outcome.faults.push(crate::outcome::FaultOutcome {
            code: FaultCode::EStopPressed,
            injected_s: Some(2.0),
            detected_s: 2.0,
            latency_ticks: Some(0),
            reaction: gait_control::faults::Reaction::DisableMotors,
            channel: None,
            safe_state_s: off_s,
        });
        RunResult {
            run: CampaignRun {
                gait: Gait::StairDown,
                fault: "estop@2".parse().unwrap_or_else(|e| panic!("{e}")),
                noise_seed: 1,
            },
            outcome,
            false_trip: false,
            detected: true,
            error: None,
            struck_in: Some(Phase::Swing {
                stance: Side::Left,
                t_s: 0.5,
            }),
            stance_after_strike: [true, false],
            stance_before_stop: [true, false],
            carrying_at_strike: [true, false],
        }
    }

    #[test]
    fn an_e_stop_s_case_names_only_what_happened_once_the_drives_were_off() {
        // Off at 2.5 s (the swing foot set down first): a fall or a stop
        // crossed from then on is the case's, before it the device's.
        let after = estop_run(3.0, Some(2.5));
        assert_eq!(after.named_fall(), Some(NamedCase::DescentKneeWithoutDrive));
        assert_eq!(after.named_stop(), Some(NamedCase::DescentKneeWithoutDrive));
        let during = estop_run(2.3, Some(2.5));
        assert_eq!(during.named_fall(), None);
        assert!(during.unnamed_fall() && during.unnamed_stop());
        // Drives never off: the device's.
        assert!(estop_run(3.0, None).unnamed_fall());
    }

    #[test]
    fn the_plan_is_seeded_valid_and_covers_every_kind() {
        let a = plan(7, 400);
        assert_eq!(a, plan(7, 400));
        assert_ne!(a, plan(8, 400));
        for r in &a {
            // Each planned fault reads back as itself.
            let text = r.fault.to_string();
            let back: Injection = text.parse().unwrap_or_else(|e| panic!("{text}: {e}"));
            assert_eq!(back.kind.name(), r.fault.kind.name());
            assert!((0.3..=5.0).contains(&r.fault.at_s));
        }
        for name in [
            "encoder-bus",
            "encoder-jump",
            "fsr-over-range",
            "motor-stuck",
            "overrun",
            "pilot-stops-balancing",
            "current-open",
            "current-short",
        ] {
            assert!(a.iter().any(|r| r.fault.kind.name() == name), "{name}");
        }
    }

    #[test]
    fn the_healthy_plan_is_seeded_and_gives_each_gait_its_runs() {
        let a = healthy_plan(3, 50);
        assert_eq!(a, healthy_plan(3, 50));
        assert_ne!(a, healthy_plan(4, 50));
        for gait in [Gait::Walk, Gait::StairUp, Gait::StairDown] {
            let seeds: std::collections::BTreeSet<u64> = a
                .iter()
                .filter(|r| r.gait == gait)
                .map(|r| r.noise_seed)
                .collect();
            assert_eq!(seeds.len(), 50, "{gait:?}: distinct noise seeds");
        }
    }
}
