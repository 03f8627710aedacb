//! The device's step re-planning, as the board runs it in the idle time of
//! its tick (and the simulator in between two ticks): gait-core's
//! re-planner ([`gait_core::replan`]) fed this device's drive, envelope and
//! body, its answer checked by the device's admission check
//! ([`crate::admission::check_samples`]) before it is offered to the
//! sequencer through the slot ([`gait_control::replan`]).
//!
//! How long a re-plan may take: the sequencer takes the answer
//! [`REPLAN.latency_ticks`](REPLAN) after asking. The tick leaves the core
//! [`IDLE_INSTRUCTIONS_PER_TICK`] a tick; a re-plan costs
//! [`INSTRUCTIONS_PER_SAMPLE`] per sample and evaluation (measured by the
//! QEMU image, which fails if it costs more), so its evaluations are capped
//! to what fits in the latency.

use gait_control::posture::phi_from_joints;
use gait_control::replan::{ReplanConfig, ReplanOutcome, ReplanRequest};
use gait_control::sequencer::GaitTables;
use gait_core::LINKS;
use gait_core::foot::StanceFoot;
use gait_core::playback::swing_ankle;
use gait_core::replan::{
    DriveLimit, MAX_EVALS, Measured, Outcome, Progress, ReplanError, ReplanLimits, ReplanSetup,
    Replanner,
};
use gait_core::tables::GaitTable;

use crate::DeviceConfig;
use crate::admission::{Refusal, check_samples};

/// How the sequencer uses the re-planner on this device
/// ([`ReplanConfig::DEFAULT`]).
pub const REPLAN: ReplanConfig = ReplanConfig::DEFAULT;

/// The motor board's core clock, Hz, and its tick, Hz.
const CORE_HZ: u64 = 168_000_000;
const TICK_HZ: u64 = 1_000;
/// The tick's budget, instructions (`cargo xtask qemu`'s `tick:` lines
/// stay below it).
pub const TICK_BUDGET_INSTRUCTIONS: u64 = 10_000;
/// What a tick leaves the idle-time re-planner: the core's cycles in one
/// tick period less the tick's budget (one instruction a cycle, as the
/// M4F runs this code near enough; the QEMU image measures instructions).
pub const IDLE_INSTRUCTIONS_PER_TICK: u64 = CORE_HZ / TICK_HZ - TICK_BUDGET_INSTRUCTIONS;
/// One evaluation's cost per table sample (IK, inverse dynamics, load
/// sharing, cost), instructions on the M4F: the QEMU image measures it and
/// fails above this.
pub const INSTRUCTIONS_PER_SAMPLE: u64 = 6_400;
/// The pilot's crutch lever the re-planner's cost is scaled by, m (the
/// clinical mode's; it scales the cost, not which step is best).
const CRUTCH_LEVER_M: f32 = 0.45;

/// What a re-plan came to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Answer {
    /// What the sequencer is told.
    pub outcome: ReplanOutcome,
    /// The re-planner's own answer (`None`: it could not be set up).
    pub detail: Option<Outcome<f32>>,
    /// Why it could not be set up, if so.
    pub setup_error: Option<ReplanError>,
    /// The admission check's refusal, if it refused the step.
    pub refusal: Option<Refusal>,
    /// Evaluations used.
    pub evals: u16,
    /// Samples a step has (the table's).
    pub samples: usize,
}

impl Answer {
    /// Its estimated cost on the M4F, instructions.
    #[must_use]
    pub fn instructions(&self) -> u64 {
        u64::from(self.evals) * self.samples as u64 * INSTRUCTIONS_PER_SAMPLE
    }

    /// Ticks of idle time it takes on the board (at least one: it is
    /// published after the tick that asked).
    #[must_use]
    pub fn ticks(&self) -> u64 {
        self.instructions()
            .div_ceil(IDLE_INSTRUCTIONS_PER_TICK)
            .max(1)
    }
}

/// Evaluations that fit in the latency for a table of `samples`: what the
/// idle time of `latency_ticks` ticks buys, at most [`MAX_EVALS`].
#[must_use]
pub fn evals_within(latency_ticks: u16, samples: usize) -> u16 {
    let per_eval = (samples as u64).max(1) * INSTRUCTIONS_PER_SAMPLE;
    // One tick of margin: the answer must be in before the tick that takes it.
    let idle = u64::from(latency_ticks.saturating_sub(1)) * IDLE_INSTRUCTIONS_PER_TICK;
    u16::try_from(idle / per_eval)
        .unwrap_or(u16::MAX)
        .min(MAX_EVALS)
}

/// The re-planner's limits on `cfg`: its hip and knee drive, the
/// supervisor's envelope, the clinical mode's soft limits.
#[must_use]
pub fn limits(cfg: &DeviceConfig) -> ReplanLimits<f32> {
    let drive = &cfg.drives[1];
    let sv = &cfg.supervisor;
    let [hip, knee, ..] = sv.joint_range;
    let [ankle, _] = sv.ankle_range;
    ReplanLimits::clinical(
        DriveLimit {
            peak_nm: drive.peak_torque_nm(),
            full_torque_speed_rad_s: drive.full_torque_speed_rad_s(),
            no_load_speed_rad_s: drive.no_load_speed_rad_s(),
        },
        [hip.min_rad, hip.max_rad],
        [knee.min_rad, knee.max_rad],
        ankle.min_rad,
    )
}

/// Re-plans `request`'s step of `tables` on `cfg` into `out` (at least the
/// table's length), in at most `max_evals` evaluations, and checks the
/// answer for admission. Bounded: `max_evals` playbacks of the table and
/// one admission pass.
pub fn replan(
    cfg: &DeviceConfig,
    tables: &GaitTables<'_>,
    request: &ReplanRequest,
    out: &mut [[f32; LINKS]],
    max_evals: u16,
) -> Answer {
    let mut answer = Answer {
        outcome: ReplanOutcome::Declined,
        detail: None,
        setup_error: None,
        refusal: None,
        evals: 0,
        samples: 0,
    };
    let Some(table) = tables.slot(usize::from(request.slot)).copied() else {
        return answer;
    };
    answer.samples = table.len();
    let Some(buffer) = out.get_mut(..table.len()) else {
        answer.setup_error = Some(ReplanError::BufferLength);
        return answer;
    };
    let model = cfg.controller.model;
    let foot = StanceFoot::for_model(&model);
    let setup = ReplanSetup {
        model: &model,
        foot,
        spring_nm_per_rad: cfg.ankle_spring_nm_per_rad as f32,
        spacing_m: spacing(&table, &model, &foot),
        crutch_lever_m: CRUTCH_LEVER_M,
        aim_m: REPLAN.landing_aim_for(table.kind()),
    };
    let measured = Measured {
        phi1_rad: request.phi1_rad,
        // The ankle at rest at the request (the sequencer holds the start
        // posture while the pilot settles).
        rate_rad_s: 0.0,
        persist: request.persist,
        posture: Some(phi_from_joints(
            &request.joints_rad,
            request.phi1_rad,
            request.stance,
        )),
    };
    // Not one evaluation fits in the time: the table.
    if max_evals == 0 {
        return answer;
    }
    let budget = max_evals.min(MAX_EVALS);
    let mut planner = match Replanner::new(setup, limits(cfg), table, measured, buffer, budget) {
        Ok(p) => p,
        Err(e) => {
            answer.setup_error = Some(e);
            return answer;
        }
    };
    let outcome = match planner.step(budget) {
        Progress::Done(o) => o,
        // Not reached: `step` finishes within its own budget.
        Progress::Running { .. } => return answer,
    };
    answer.evals = planner.evals();
    answer.detail = Some(outcome);
    if let Outcome::Replanned { .. } = outcome {
        let samples = planner.samples();
        answer.outcome = match check_samples(cfg, samples.len(), table.period_s(), |k| {
            samples.get(k).copied()
        }) {
            Ok(_) => ReplanOutcome::Replanned,
            Err(r) => {
                answer.refusal = Some(r);
                ReplanOutcome::Refused
            }
        };
    }
    answer
}

/// Where the step's swing foot lands from its stance ankle (flat-foot
/// frame): the spacing of the table's staircase or walk, m.
fn spacing(
    table: &GaitTable<'_>,
    model: &gait_core::BodyModel<f32>,
    foot: &StanceFoot<f32>,
) -> [f32; 2] {
    swing_ankle(model, foot, &table.last())
}
