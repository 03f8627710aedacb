//! The closed-loop refinement of a clinical table: from the point the
//! clinical search found on the *predicted* crutch load, a deterministic
//! pattern search whose objective is the crutch load the table gives when
//! the real controller (gait-control) plays it on the simulated device and
//! pilot (`sim`), with the clinical requirements as hard constraints.
//!
//! Why: the prediction ([`super::evaluate_phi`]) does not see the pilot's
//! tracking. On stair ascent the closed loop adds about 90 N·s to the
//! predicted 110 N·s balance part (the pilot's PD on the stance shank
//! overshoots where heel-off moves the pivot to the toe, and lags through
//! the weight shift before the lift-off), and seeds that predict less are
//! not better in the closed loop. Searching on the closed loop itself is
//! the only measure that ranks tables by what the pilot feels.
//!
//! Why a pattern search (Hooke–Jeeves: compass moves along each coordinate,
//! a pattern move along the last successful displacement, step halving):
//! - every evaluation is a closed-loop simulation (≈ 0.3 s for the two
//!   steps the search plays), so the budget is a few hundred to a couple of
//!   thousand evaluations — too few for CMA-ES to learn a 17-dimensional
//!   covariance, while a pattern search makes progress from its first
//!   sweep; its pattern move follows the valleys that a pure compass search
//!   crawls along;
//! - the objective is deterministic but not smooth (contact events and the
//!   sequencer's thresholds shift by a tick), and a constraint violation
//!   is a rejection, not a number: a pattern search only compares values,
//!   so rejections and small jumps are harmless;
//! - it is sequential and seedless: the same start gives the same table on
//!   any machine, with one thread.
//!
//! An evaluation plays [`RefineConfig::search_steps`] steps and stops at
//! the end of the last one's weight transfer; the best points are then
//! verified on 4 and 20 steps ([`verify`]) and the first that passes every
//! requirement is the result (the start point, verified the same way, is
//! the fallback).

mod pattern_search;

use exogait_device::DeviceConfig;
use exogait_device::admission::check_table;
use gait_core::kinematics::Phi;
use gait_core::tables::GaitTable;
use sim::compare::{GaitRun, RunLength, play_for};
use sim::pilot::PilotConfig;
use sim::scenario::{strong_pilot, table_geometry};

use super::search::{DIM, decode};
use super::{ClinicalCase, Evaluation, evaluate_phi, step_phi};
use crate::human::playable_human_gait;
use pattern_search::pattern_search;

/// What the refined table may not exceed: the human-data gait's figures at
/// the same geometry and timing, on the same device and pilot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HumanReference {
    /// Highest crutch peak of the human gait over 4 steps, N.
    pub crutch_peak_n: f64,
    /// Its closed-loop balance part, mean over 4 steps, N·s.
    pub balance_ns: f64,
    /// Its predicted stance-ankle peak, N·m.
    pub ankle_peak_nm: f64,
    /// Its predicted balance part, N·s.
    pub predicted_balance_ns: f64,
}

/// Why the refinement could not run.
#[derive(Debug)]
pub enum RefineError {
    /// The human-data gait could not be built or played.
    Human(String),
    /// The start point is not a table, or breaks a requirement.
    Start(String),
    /// The result breaks a requirement.
    Result(String),
}

impl std::fmt::Display for RefineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Human(e) => write!(f, "human-data gait: {e}"),
            Self::Start(e) => write!(f, "start point: {e}"),
            Self::Result(e) => write!(f, "result: {e}"),
        }
    }
}

impl std::error::Error for RefineError {}

/// Settings of the refinement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineConfig {
    /// Steps each search evaluation plays.
    pub search_steps: usize,
    /// Search evaluations in all.
    pub max_evals: usize,
    /// First step of the pattern search (in the unit box).
    pub initial_step: f64,
    /// The search stops once its step is below this.
    pub min_step: f64,
}

/// The number of the 4-step and the 20-step verification.
pub const VERIFY_STEPS: [usize; 2] = [4, 20];

/// Figures of a table played in the closed loop.
#[derive(Clone, Debug, PartialEq)]
pub struct Played {
    /// Balance part of each step, N·s.
    pub balance_ns: Vec<f64>,
    /// Mean balance part, N·s.
    pub mean_balance_ns: f64,
    /// Mean crutch impulse F, N·s.
    pub mean_impulse_ns: f64,
    /// Highest crutch peak, N.
    pub crutch_peak_n: f64,
    /// Time any hip or knee command was within 3 % of the drive's peak,
    /// per step, s.
    pub near_peak_s_per_step: f64,
}

/// A candidate's table and what the prediction says of it.
struct Candidate {
    phi: Vec<Phi<f64>>,
    image: Vec<u8>,
    evaluation: Evaluation,
}

/// The closed-loop objective of one gait: the case, the device, the pilot
/// and the human gait's caps.
pub struct ClosedLoop<'a> {
    case: &'a ClinicalCase,
    device: &'a DeviceConfig,
    pilot: PilotConfig,
    human: HumanReference,
}

/// Largest time per step a command may spend within 3 % of the drive's
/// peak, s, over the search's steps and the 20-step verification:
/// host-tests' `clinical_tables` asserts it over 20 steps (stair ascent's
/// stance knee as it takes the body at the lift-off; it grows over the
/// first steps, so the 4-step verification does not hold to it).
const NEAR_PEAK_S_PER_STEP: f64 = 0.12;
/// How far outside the clinical search's clearance band a table may be,
/// m.
const CLEARANCE_SLACK_M: f64 = 0.001;
/// Largest error of a step's length against the table's, m (host-tests
/// allow 1.5 cm).
const STEP_LENGTH_TOLERANCE_M: f64 = 0.012;

impl<'a> ClosedLoop<'a> {
    /// The objective of `case` on `device` with the strong pilot of the
    /// comparison, the human gait's caps taken at the geometry and timing
    /// of the table at `start` (as `exogait compare` does).
    pub fn new(
        case: &'a ClinicalCase,
        device: &'a DeviceConfig,
        start: &[f64; DIM],
    ) -> Result<Self, RefineError> {
        let pilot = strong_pilot();
        let c = candidate(case, start).map_err(RefineError::Start)?;
        let table = GaitTable::parse(&c.image).map_err(|e| RefineError::Start(e.to_string()))?;
        let geometry = table_geometry(&table, &device.body);
        let mut hcase = *case;
        hcase.spacing_m = geometry.landing_m;
        hcase.step_time_s = f64::from(table.duration_s());
        let human = playable_human_gait(&hcase, &crate::default_data_dir())
            .map_err(|e| RefineError::Human(e.to_string()))?;
        let h = evaluate_phi(&hcase, &human.phi).map_err(|e| RefineError::Human(e.to_string()))?;
        let image = crate::tables::table_image(case.gait, &case.ik, &human.phi)
            .map_err(|e| RefineError::Human(e.to_string()))?;
        let htable = GaitTable::parse(&image).map_err(|e| RefineError::Human(e.to_string()))?;
        let steps = VERIFY_STEPS[0];
        let (run, _) = play_for(
            device,
            htable,
            pilot,
            RunLength {
                steps,
                max_s: max_s(steps),
                tail_s: 1.5,
            },
            |_| {},
        )
        .map_err(|e| RefineError::Human(e.to_string()))?;
        let (Some(crutch_peak_n), Some(balance_ns)) = (run.peak_n(), run.mean(|s| s.balance_ns))
        else {
            return Err(RefineError::Human("no step landed".into()));
        };
        Ok(Self {
            case,
            device,
            pilot,
            human: HumanReference {
                crutch_peak_n,
                balance_ns,
                ankle_peak_nm: h.ankle_peak_nm,
                predicted_balance_ns: h.balance_ns,
            },
        })
    }

    /// The human gait's figures.
    pub fn human(&self) -> &HumanReference {
        &self.human
    }

    /// Plays the table of `x` for `steps` steps; `Err` names the first
    /// requirement it breaks (the table's own, then the closed loop's).
    /// `tail_s`: how long the run goes on after the last landing (the
    /// search stops at the end of its weight transfer; the verification
    /// plays 1.5 s, as `exogait compare` does, to catch a late fault).
    pub fn play(&self, x: &[f64; DIM], steps: usize, tail_s: f64) -> Result<Played, String> {
        self.play_within(x, steps, tail_s, Some(NEAR_PEAK_S_PER_STEP))
    }

    /// [`Self::play`], the time near the drive's peak held to
    /// `near_peak_s_per_step` (`None`: not checked).
    fn play_within(
        &self,
        x: &[f64; DIM],
        steps: usize,
        tail_s: f64,
        near_peak_s_per_step: Option<f64>,
    ) -> Result<Played, String> {
        let c = candidate(self.case, x)?;
        self.table_requirements(&c.evaluation)?;
        let table = GaitTable::parse(&c.image).map_err(|e| e.to_string())?;
        let demand = check_table(self.device, &table).map_err(|e| e.to_string())?;
        if demand.drive_use > 0.8 {
            return Err(format!("admission: drive use {}", demand.drive_use));
        }
        let (run, rig) = play_for(
            self.device,
            table,
            self.pilot,
            RunLength {
                steps,
                max_s: max_s(steps),
                tail_s,
            },
            |_| {},
        )
        .map_err(|e| e.to_string())?;
        self.loop_requirements(&run, steps, &table)?;
        let landings = rig.plant.landings();
        for (n, l) in landings.iter().take(steps).enumerate() {
            let expected = if n % 2 == 0 {
                sim::Side::Right
            } else {
                sim::Side::Left
            };
            if l.side != expected {
                return Err(format!("landing {n} on the wrong foot"));
            }
        }
        let dt = f64::from(self.device.dt_s);
        let peak = f64::from(self.device.drives[0].peak_torque_nm());
        let near = rig
            .trace
            .iter()
            .filter(|s| {
                s.report
                    .command_nm
                    .iter()
                    .any(|c| f64::from(c.abs()) >= 0.97 * peak)
            })
            .count() as f64
            * dt
            / steps as f64;
        if near_peak_s_per_step.is_some_and(|limit| near > limit) {
            return Err(format!("{near:.3} s per step near the drive's peak"));
        }
        let warning = f64::from(self.device.motors[0].i2t_warning_a2s);
        if let Some(j) = rig
            .wiring
            .motors
            .iter()
            .position(|m| m.i2t_a2s() >= warning)
        {
            return Err(format!("joint {j}'s I²t reached its warning level"));
        }
        let balance_ns: Vec<f64> = run.steps.iter().map(|s| s.balance_ns).collect();
        Ok(Played {
            mean_balance_ns: balance_ns.iter().sum::<f64>() / balance_ns.len() as f64,
            balance_ns,
            mean_impulse_ns: run.mean(|s| s.impulse_ns).unwrap_or(f64::NAN),
            crutch_peak_n: run.peak_n().unwrap_or(f64::NAN),
            near_peak_s_per_step: near,
        })
    }

    /// The requirements on the table itself, each a little inside the
    /// bound gait-opt's `clinical_tables` test asserts (the clearance in
    /// the band the clinical search aims at).
    fn table_requirements(&self, e: &Evaluation) -> Result<(), String> {
        let checks = [
            (e.drive_use <= 0.78, "drive use"),
            (
                e.joint_speed_peak_rad_s.iter().all(|&s| s <= 1.85),
                "joint speed",
            ),
            (e.joint_accel_peak_rad_s2 <= 24.0, "joint acceleration"),
            (e.i2t_ratio.iter().all(|&r| r <= 0.97), "I²t"),
            // The clinical search's band (4–7 cm: inside the clinical
            // 3–8 cm by what tracking lag may take), with the 1 mm its soft
            // penalty lets the search's point stray outside.
            (
                (self.case.limits.clearance_m.0 - CLEARANCE_SLACK_M
                    ..=self.case.limits.clearance_m.1 + CLEARANCE_SLACK_M)
                    .contains(&e.clearance_m),
                "clearance",
            ),
            (e.sole_margin_m >= -0.003, "sole margin"),
            (
                e.ankle_peak_nm <= self.human.ankle_peak_nm,
                "stance-ankle peak",
            ),
            (
                e.balance_ns < 0.5 * self.human.predicted_balance_ns,
                "predicted balance part",
            ),
        ];
        match checks.iter().find(|(ok, _)| !ok) {
            Some((_, what)) => Err(format!("table: {what}")),
            None => Ok(()),
        }
    }

    /// Every step landed on its point without a fault, the crutch peak no
    /// higher than the human gait's.
    fn loop_requirements(
        &self,
        run: &GaitRun,
        steps: usize,
        table: &GaitTable<'_>,
    ) -> Result<(), String> {
        if let Some(e) = &run.ended_by {
            return Err(format!("ended: {e}"));
        }
        if let Some((code, name)) = run.faults.first() {
            return Err(format!("fault {code} {name}"));
        }
        if run.steps.len() < steps || run.landed() < steps {
            return Err(format!("{} of {steps} steps landed", run.landed()));
        }
        let step = table_geometry(table, &self.device.body).landing_m[0];
        if run
            .landings_m
            .windows(2)
            .take(steps)
            .any(|w| ((w[1][0] - w[0][0]) - step).abs() > STEP_LENGTH_TOLERANCE_M)
        {
            return Err("a step's length is off the table's".into());
        }
        match run.peak_n() {
            Some(p) if p <= self.human.crutch_peak_n => Ok(()),
            p => Err(format!("crutch peak {p:?} N")),
        }
    }
}

/// Simulated time a run of `steps` steps may take, s (as `exogait
/// compare`).
fn max_s(steps: usize) -> f64 {
    8.0 + 4.0 * steps as f64
}

/// The table of `x`.
fn candidate(case: &ClinicalCase, x: &[f64; DIM]) -> Result<Candidate, String> {
    let step = decode(case, x).map_err(|e| format!("{e:?}"))?;
    let phi = step_phi(case, &step).map_err(|e| e.to_string())?;
    let evaluation = evaluate_phi(case, &phi).map_err(|e| e.to_string())?;
    let image = crate::tables::table_image(case.gait, &case.ik, &phi).map_err(|e| e.to_string())?;
    Ok(Candidate {
        phi,
        image,
        evaluation,
    })
}

/// The refined table.
#[derive(Clone, Debug, PartialEq)]
pub struct Refinement {
    /// Where the search started.
    pub start: [f64; DIM],
    /// The verified result (`start` when no better point passed).
    pub x: [f64; DIM],
    /// Its Φ samples.
    pub phi: Vec<Phi<f64>>,
    /// Its predicted figures.
    pub evaluation: Evaluation,
    /// Search evaluations spent (verifications not counted).
    pub evaluations: usize,
    /// The search objective at the start and at the result, N·s.
    pub search_ns: [f64; 2],
    /// The result played for 4 and 20 steps.
    pub verified: [Played; 2],
    /// The start played for 4 steps.
    pub start_played: Played,
    /// The human gait's figures it was held to.
    pub human: HumanReference,
    /// Each improvement of the search: (evaluations so far, objective).
    pub trajectory: Vec<(usize, f64)>,
}

/// How many of the best points are verified before falling back to the
/// start.
const MAX_VERIFIED: usize = 20;

/// Plays `x` for the 4- and 20-step verifications.
pub fn verify(objective: &ClosedLoop<'_>, x: &[f64; DIM]) -> Result<[Played; 2], String> {
    let four = objective.play_within(x, VERIFY_STEPS[0], 1.5, None)?;
    let twenty = objective.play(x, VERIFY_STEPS[1], 1.5)?;
    Ok([four, twenty])
}

/// The refinement from `start` (see the module documentation); `progress`
/// sees (evaluations, best objective) at every improvement and every
/// halving of the step.
pub fn refine(
    case: &ClinicalCase,
    device: &DeviceConfig,
    start: &[f64; DIM],
    config: &RefineConfig,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Refinement, RefineError> {
    let objective = ClosedLoop::new(case, device, start)?;
    let f0 = objective.search_value(start, config, device);
    if !f0.is_finite() {
        return Err(RefineError::Start(
            "the start point breaks a requirement".into(),
        ));
    }
    let f = |x: &[f64; DIM]| objective.search_value(x, config, device);
    let (improvements, evaluations) = pattern_search(*start, f0, config, f, progress);
    // The best points first; the first that passes both verifications.
    let mut ranked = improvements.clone();
    ranked.sort_by(|a, b| a.1.total_cmp(&b.1));
    let x = ranked
        .iter()
        .take(MAX_VERIFIED)
        .find(|(x, _, _)| verify(&objective, x).is_ok())
        .map_or(*start, |(x, _, _)| *x);
    let mut r = assemble(&objective, config, device, start, &x, evaluations)?;
    r.trajectory = std::iter::once((0, f0))
        .chain(improvements.iter().map(|&(_, v, n)| (n, v)))
        .collect();
    Ok(r)
}

/// A refinement recorded as (start, result, evaluations), recomputed
/// without the search: the same figures [`refine`] gives for it (its
/// trajectory empty). Fails when the result does not pass the
/// verifications.
pub fn replay(
    case: &ClinicalCase,
    device: &DeviceConfig,
    start: &[f64; DIM],
    x: &[f64; DIM],
    evaluations: usize,
    config: &RefineConfig,
) -> Result<Refinement, RefineError> {
    let objective = ClosedLoop::new(case, device, start)?;
    assemble(&objective, config, device, start, x, evaluations)
}

/// The figures of a refinement from `start` to `x`.
fn assemble(
    objective: &ClosedLoop<'_>,
    config: &RefineConfig,
    device: &DeviceConfig,
    start: &[f64; DIM],
    x: &[f64; DIM],
    evaluations: usize,
) -> Result<Refinement, RefineError> {
    let start_played = objective
        .play_within(start, VERIFY_STEPS[0], 1.5, None)
        .map_err(RefineError::Start)?;
    let verified = verify(objective, x).map_err(RefineError::Result)?;
    let c = candidate(objective.case, x).map_err(RefineError::Result)?;
    Ok(Refinement {
        start: *start,
        x: *x,
        phi: c.phi,
        evaluation: c.evaluation,
        evaluations,
        search_ns: [
            objective.search_value(start, config, device),
            objective.search_value(x, config, device),
        ],
        verified,
        start_played,
        human: objective.human,
        trajectory: Vec::new(),
    })
}

impl ClosedLoop<'_> {
    /// The search's objective: the mean balance part over the search's
    /// steps, the run ending with the last step's weight transfer;
    /// infinite when a requirement is broken.
    fn search_value(&self, x: &[f64; DIM], config: &RefineConfig, device: &DeviceConfig) -> f64 {
        let tail_s = f64::from(device.controller.sequencer.transfer_s) + 0.01;
        self.play(x, config.search_steps, tail_s)
            .map_or(f64::INFINITY, |p| p.mean_balance_ns)
    }
}
