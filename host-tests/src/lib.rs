//! Shared fixtures of the closed-loop scenarios: the gait tables the device
//! carries in flash (`gait_core::flash_tables`, made by gait-opt's table
//! generator), and a rig standing in the walk table's start posture with a
//! pilot who knows the gait.

use gait_control::operator::Gait;
use gait_control::sequencer::GaitTables;
use gait_core::problem::{PaperCase, PaperProblem};
use sim::closed_loop::{PilotBehaviour, Rig, RigError, RigSetup, heel_rocker_model};
use sim::pilot::PilotConfig;
use sim::{PlantConfig, Side};

/// The tables the firmware carries (`gait_core::flash_tables`), verified.
pub fn walk_tables() -> GaitTables<'static> {
    GaitTables {
        walk: gait_core::flash_tables::walk().ok(),
        stair_up: gait_core::flash_tables::stair_up().ok(),
        stair_down: None,
    }
}

/// A rig standing (double support) in the walk table's start posture, left
/// leg in front as stance, the pilot following the plan, the plant held
/// still for the first 60 ms while the drives soft-start (40 ms).
pub fn standing_rig(pilot: PilotConfig) -> Result<Rig<'static>, RigError> {
    rig_with(pilot, walk_tables())
}

/// [`standing_rig`] with other tables (the walk table's start posture).
pub fn rig_with(pilot: PilotConfig, tables: GaitTables<'static>) -> Result<Rig<'static>, RigError> {
    let first = tables
        .walk
        .as_ref()
        .map(|t| t.first().map(f64::from))
        .ok_or(RigError::Config("no verified walk table"))?;
    let case = PaperProblem::<f64>::paper(PaperCase::Walk).case;
    let setup = RigSetup {
        plant: PlantConfig {
            model: heel_rocker_model(),
            pilot,
            ..PlantConfig::default()
        },
        phi: first,
        stance: Side::Left,
        stance_foot_m: [0.0, 0.0],
        pilot: PilotBehaviour::FollowsPlan(case.stance),
        gait: Gait::Walk,
        support_ticks: 60,
    };
    Rig::new(&setup, tables)
}

/// A pilot strong enough for the paper's walk (300 N·m through the
/// crutches).
pub fn strong_pilot() -> PilotConfig {
    PilotConfig {
        torque_limit_nm: 300.0,
        ..PilotConfig::default()
    }
}
