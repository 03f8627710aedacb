//! Ready-made closed-loop set-ups: the device with the tables it carries in
//! flash, standing in the walk table's start posture, with a pilot who knows
//! the gait; and the main job, one walking step from GO to landing.

use gait_control::operator::Gait;
use gait_control::sequencer::GaitTables;
use gait_core::BodyModel;
use gait_core::foot::StanceFoot;
use gait_core::problem::{PeriodicStep, StepCase};

use crate::closed_loop::{PilotBehaviour, Rig, RigError, RigSetup, heel_rocker_model};
use crate::pilot::PilotConfig;
use crate::plant::{PlantConfig, Side, SimError};
use crate::summary::{RunSummary, summarise};
use crate::terrain::Terrain;

/// The tables the firmware carries (`gait_core::flash_tables`), verified.
pub fn flash_tables() -> GaitTables<'static> {
    GaitTables {
        walk: gait_core::flash_tables::walk().ok(),
        stair_up: gait_core::flash_tables::stair_up().ok(),
        stair_down: gait_core::flash_tables::stair_down().ok(),
    }
}

/// A pilot strong enough for the paper's walk (300 N·m through the
/// crutches, ≈ 670 N on them together at the 0.45 m lever).
pub fn strong_pilot() -> PilotConfig {
    PilotConfig {
        torque_limit_nm: 300.0,
        gravity_compensation: 1.0,
        ..PilotConfig::default()
    }
}

/// The device standing (double support) in the walk table's start posture,
/// left leg in front as stance, the pilot following the plan, the plant held
/// still for the first 60 ms while the drives soft-start (40 ms).
pub fn walk_rig(pilot: PilotConfig, tables: GaitTables<'static>) -> Result<Rig<'static>, RigError> {
    gait_rig(Gait::Walk, pilot, tables)
}

/// The paper's staircase (rise 0.0935 m, tread 0.275 m, 12 steps), its first
/// riser halfway between the feet of the stair-ascent start posture: the
/// stance foot at x = 0 stands on the first step, the trailing foot on the
/// floor 0.275 m behind.
pub const PAPER_STAIRS: Terrain = Terrain::Stairs {
    start_x_m: -0.1375,
    rise_m: 0.0935,
    tread_m: 0.275,
    steps: 12,
};

/// The paper's staircase walked down: the top floor at height 0 up to the
/// first (downward) riser, then 12 steps of 0.0935 m down. The stance foot
/// at x = 0 stands on the first tread (y = −0.0935), the trailing foot on
/// the top floor 0.275 m behind, on the ball of its foot (0.14 m ahead of
/// its ankle, [`gait_core::foot::TOE_M`]). The riser at x = −0.12 puts that
/// ball 1.5 cm inside the top floor's edge and the stance heel (5 cm
/// behind its ankle) 7 cm onto its tread; the simulated steps are 8 mm short
/// (docs/model.md), so 8 steps keep every heel on its tread.
pub const PAPER_STAIRS_DOWN: Terrain = Terrain::Stairs {
    start_x_m: -0.12,
    rise_m: -0.0935,
    tread_m: 0.275,
    steps: 12,
};

/// The device standing in `gait`'s start posture, left leg in front as
/// stance (on the first step for stair ascent, see [`PAPER_STAIRS`]; on the
/// first tread down for descent, [`PAPER_STAIRS_DOWN`]), the
/// pilot following the plan the table was optimised with, the plant held
/// still for the first 60 ms while the drives soft-start (40 ms).
pub fn gait_rig(
    gait: Gait,
    pilot: PilotConfig,
    tables: GaitTables<'static>,
) -> Result<Rig<'static>, RigError> {
    let first = tables
        .get(gait)
        .map(|t| t.first().map(f64::from))
        .ok_or(RigError::Config("no verified table for the gait"))?;
    // The flash tables are optimised on these cases (gait-opt's tables):
    // the pilot has learnt their stance-shank profiles.
    let (step, terrain, foot_y) = match gait {
        Gait::Walk => (PeriodicStep::walk(), Terrain::Level, 0.0),
        Gait::StairUp => (PeriodicStep::stair_up(), PAPER_STAIRS, 0.0935),
        Gait::StairDown => (PeriodicStep::stair_down(), PAPER_STAIRS_DOWN, -0.0935),
    };
    let case = StepCase::periodic(&step, &BodyModel::paper_table_iii())
        .map_err(|_| RigError::Config("no periodic case for the gait"))?;
    let setup = RigSetup {
        plant: PlantConfig {
            model: heel_rocker_model(),
            pilot,
            terrain,
            // After an impact the trailing foot lifts off by a centimetre or
            // two and hovers through the weight transfer; with the default
            // 1 cm its settling back onto a stair tread counted as a landing
            // and swapped the legs back at the start of the next swing.
            // Swings clear 16 cm.
            lift_clearance_m: 0.03,
            ..PlantConfig::default()
        },
        phi: first,
        stance: Side::Left,
        stance_foot_m: [0.0, foot_y],
        pilot: PilotBehaviour::FollowsPlan(case.stance),
        gait,
        support_ticks: 60,
    };
    Rig::new(&setup, tables)
}

/// When GO is pressed in [`walk_step`] (tick), and for how long.
pub const GO_AT_TICK: u64 = 400;
/// GO is held past the 1 s long press.
pub const GO_TICKS: u64 = 1200;

/// One closed-loop run and what it did.
pub struct StepRun {
    /// The rig, with its trace.
    pub rig: Rig<'static>,
    /// The summary.
    pub summary: RunSummary,
    /// Why the simulation stopped early (the plant fell or blew up), if it
    /// did; the summary covers what happened before.
    pub ended_by: Option<SimError>,
}

/// The main job: GO and walking with the flash table until `steps`
/// landings have happened and 1.5 s more (or a safe hold has lasted 1 s, or
/// `max_s` in all).
pub fn walk_step(max_s: f64) -> Result<StepRun, RigError> {
    walk(max_s, 1)
}

/// See [`walk_step`]; `steps` landings.
pub fn walk(max_s: f64, steps: usize) -> Result<StepRun, RigError> {
    run_gait(Gait::Walk, max_s, steps)
}

/// `gait` from standing (see [`gait_rig`]): GO, then steps until `steps`
/// landings have happened and 1.5 s more (or a safe hold has lasted 1 s, or
/// `max_s` in all).
pub fn run_gait(gait: Gait, max_s: f64, steps: usize) -> Result<StepRun, RigError> {
    run_gait_with(gait, max_s, steps, |_| {})
}

/// [`run_gait`], with `prepare` applied to the rig before the first tick
/// (sensor noise, fault injection, other button scripts).
pub fn run_gait_with(
    gait: Gait,
    max_s: f64,
    steps: usize,
    prepare: impl FnOnce(&mut Rig<'static>),
) -> Result<StepRun, RigError> {
    let tables = flash_tables();
    let planned_landing_x_m = tables.get(gait).map_or(0.0, |t| {
        let m = heel_rocker_model();
        let last = t.last().map(f64::from);
        // The stance ankle may have rolled onto its toe (descent).
        StanceFoot::for_model(&m).points(&m, &last)[4][0]
    });
    let mut rig = gait_rig(gait, strong_pilot(), tables)?;
    Rig::press(&rig.go, GO_AT_TICK, GO_TICKS);
    prepare(&mut rig);
    let max_ticks = (max_s * 1000.0) as u64;
    let mut landed_at: Option<usize> = None;
    let mut held_since: Option<usize> = None;
    let mut result = Ok(());
    for _ in 0..max_ticks {
        if let Err(e) = rig.tick() {
            result = Err(e);
            break;
        }
        if landed_at.is_none() && rig.plant.landings().len() >= steps.max(1) {
            landed_at = Some(rig.trace.len());
        }
        if landed_at.is_some_and(|k| rig.trace.len() > k + 1500) {
            break;
        }
        if held_since.is_none() && rig.worst_reaction() >= gait_control::faults::Reaction::SafeHold
        {
            held_since = Some(rig.trace.len());
        }
        if held_since.is_some_and(|k| rig.trace.len() > k + 1000) {
            break;
        }
    }
    let faults = rig.faults().iter().map(|c| c.name()).collect();
    let on_board = rig
        .controller
        .crutch_load()
        .log()
        .next()
        .map(|s| f64::from(s.impulse_ns))
        .or_else(|| {
            rig.controller
                .crutch_load()
                .current()
                .map(|s| f64::from(s.impulse_ns))
        });
    let summary = summarise(
        &rig.trace,
        rig.plant.landings(),
        planned_landing_x_m,
        faults,
        on_board,
        rig.plant.config().dt_s,
    );
    Ok(StepRun {
        rig,
        summary,
        ended_by: result.err(),
    })
}
