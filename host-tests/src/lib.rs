//! Shared fixtures of the closed-loop scenarios: the gait tables the device
//! would carry (built from the optimiser's paper-mode walk, as the table
//! generator does), and a rig standing in a table's start posture with a
//! pilot who knows the gait.

use std::sync::OnceLock;

use gait_control::operator::Gait;
use gait_control::sequencer::GaitTables;
use gait_core::gait::GaitError;
use gait_core::ik::{IkSolver, IkTarget};
use gait_core::kinematics::Phi;
use gait_core::problem::{PaperCase, PaperProblem};
use gait_core::tables::{GaitKind, GaitTable, encode, image_len};
use gait_opt::solver::{OptimizeConfig, optimize, optimize_problem};
use sim::closed_loop::{PilotBehaviour, Rig, RigError, RigSetup, heel_rocker_model};
use sim::pilot::PilotConfig;
use sim::{PlantConfig, Side};

/// Φ samples of a step described by control points (IK at every sample).
pub fn step_phi(
    problem: &PaperProblem<f64>,
    p: &gait_core::gait::ControlPoints<f64>,
) -> Result<Vec<Phi<f64>>, GaitError> {
    let ik = IkSolver::new(&problem.model);
    let mut out = Vec::new();
    problem.step(p).for_each_sample::<GaitError>(|s| {
        let sol = ik
            .solve(&IkTarget {
                x5: s.p5[0],
                y5: s.p5[1],
                phi1: s.phi1,
                phi3: s.phi3,
                r2: s.r2,
            })
            .map_err(|error| GaitError::Ik { k: s.k, error })?;
        out.push(sol.phi);
        Ok(())
    })?;
    Ok(out)
}

/// A table image from Φ samples at the paper's 10 ms period.
pub fn table_image(kind: GaitKind, phi: &[Phi<f64>]) -> Option<Vec<u8>> {
    let f: Vec<[f32; 5]> = phi.iter().map(|p| p.map(|v| v as f32)).collect();
    let mut buf = vec![0u8; image_len(f.len())];
    encode(kind, 10_000, &f, &mut buf).ok()?;
    Some(buf)
}

/// The paper-mode optimised walk (seed 1) as a table image, computed once.
pub fn walk_image() -> &'static [u8] {
    static IMAGE: OnceLock<Vec<u8>> = OnceLock::new();
    IMAGE.get_or_init(|| {
        let problem = PaperProblem::<f64>::paper(PaperCase::Walk);
        optimize(&OptimizeConfig::new(PaperCase::Walk), &mut |_| {})
            .ok()
            .and_then(|r| step_phi(&problem, &r.control_points).ok())
            .and_then(|phi| table_image(GaitKind::Walk, &phi))
            .unwrap_or_default()
    })
}

/// The walk with a slower landing: the paper's problem with v_p = 8,000
/// instead of 1,000 (peak swing-ankle speed 0.83 m/s instead of 2.2 m/s),
/// seed 1, computed once. The paper-mode optimum's last 0.2 s are too fast
/// for the supervisor's joint-velocity limits; this one is not.
pub fn gentle_walk_image() -> &'static [u8] {
    static IMAGE: OnceLock<Vec<u8>> = OnceLock::new();
    IMAGE.get_or_init(|| {
        let mut problem = PaperProblem::<f64>::paper(PaperCase::Walk);
        problem.velocity_weight = GENTLE_VELOCITY_WEIGHT;
        let mut config = OptimizeConfig::new(PaperCase::Walk);
        config.explore_velocity_weight = 2.0 * GENTLE_VELOCITY_WEIGHT;
        optimize_problem(&problem, &config, &mut |_| {})
            .ok()
            .and_then(|r| step_phi(&problem, &r.control_points).ok())
            .and_then(|phi| table_image(GaitKind::Walk, &phi))
            .unwrap_or_default()
    })
}

/// v_p of [`gentle_walk_image`], N²·m² per (m/s).
pub const GENTLE_VELOCITY_WEIGHT: f64 = 8000.0;

/// The verified walk table (an empty image fails verification, and the
/// scenario then fails on its own `expect`).
pub fn walk_tables() -> GaitTables<'static> {
    GaitTables {
        walk: GaitTable::parse(walk_image()).ok(),
        ..GaitTables::default()
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
