//! The gait-table generator: optimised steps → verified binary tables →
//! the generated Rust module `crates/gait-core/src/flash_tables.rs` that
//! the firmware links into flash.
//!
//! Which gaits and why (until a clinically constrained table family exists):
//! every table is a **periodic** step (`gait_core::problem::PeriodicStep`):
//! its landing posture, seen from the new stance foot, is its start posture,
//! so steps chain with the legs alternating and the weight transfer between
//! them moves no joint. The paper's own optima are not periodic: the walk
//! lands with the new stance shank 0.3 rad ahead of the next start and the
//! torso pitched 0.2 rad forward, and playing it step after step made every
//! transfer pull the body backwards through the crutches.
//! - **walk**: `PeriodicStep::walk` (the paper's step, r2(0) = 1) with the
//!   velocity weight raised from 1,000 to 8,000 N²·m² per (m/s): the
//!   paper-mode optimum lands at 2.2 m/s and exceeds the supervisor's
//!   joint-velocity limits.
//! - **stair ascent**: `PeriodicStep::stair_up` (the paper's stair), paper
//!   v_p.
//! - **stair descent**: `PeriodicStep::stair_down` (the paper's stair walked
//!   down), paper v_p. It needs two things the paper does not have: the toe
//!   rocker (`gait_core::foot`: the trailing heel is up in double support)
//!   and the IK's continuous `KneeRange::Human` (the paper's range jumps as
//!   the stance knee passes over the swing foot). docs/model.md, "Stair
//!   descent".
//!
//! Deterministic: the optimiser is seeded and budgeted by evaluation count,
//! so regenerating gives the same bytes; a test checks that the committed
//! module is what the generator produces.

use std::fmt::Write as _;

use gait_core::BodyModel;
use gait_core::gait::{ControlPoints, GaitError};
use gait_core::kinematics::Phi;
use gait_core::problem::{
    JointMotionLimit, JointRangeLimit, PaperCase, PaperProblem, PeriodicError, PeriodicStep,
    StepCase,
};
use gait_core::tables::{GaitKind, TableError, encode, image_len};

use crate::solver::{OptimizeConfig, OptimizeError, optimize_problem};

/// Velocity weight of the flash walk table, N²·m² per (m/s).
pub const WALK_VELOCITY_WEIGHT: f64 = 8000.0;
/// Hip and knee speed above which a table's cost grows, rad/s: half the
/// supervisor's hip limit (6 rad/s), so that tracking lag and landing
/// transients keep clear of it.
pub const TABLE_JOINT_SPEED_RAD_S: f64 = 3.0;
/// Weight of the speed excess, N²·m² per (rad/s)² per sample: one sample
/// 1 rad/s over the limit costs about as much as the whole torque part of a
/// good step.
pub const TABLE_JOINT_SPEED_WEIGHT: f64 = 1.0e4;
/// Hip and knee acceleration above which a table's cost grows, rad/s²
/// (the drives' 12 N·m per ms slew and the feed-forward's 10 ms
/// differences both want smooth references).
pub const TABLE_JOINT_ACCEL_RAD_S2: f64 = 30.0;
/// Weight of the acceleration excess, N²·m² per (rad/s²)² per sample.
pub const TABLE_JOINT_ACCEL_WEIGHT: f64 = 10.0;
/// How far inside Table I's hip and knee stops a table's cost starts to
/// grow, rad: 10°, twice the supervisor's envelope margin (a descent's swing
/// knee folded to 108° otherwise).
pub const TABLE_JOINT_RANGE_MARGIN_RAD: f64 = 10.0 * std::f64::consts::PI / 180.0;
/// Weight of the squared range excess, N²·m² per rad² per sample: 10° over
/// for 0.1 s costs about as much as a good step's torque part.
pub const TABLE_JOINT_RANGE_WEIGHT: f64 = 1.0e5;
/// Sample period of the tables, µs (the paper's Δt).
pub const TABLE_PERIOD_US: u32 = 10_000;

/// Why a table could not be generated.
#[derive(Debug)]
pub enum TableGenError {
    /// The search failed.
    Optimize(OptimizeError),
    /// Sampling the optimised step failed (IK or sampling).
    Gait(GaitError),
    /// The samples do not fit the table format.
    Table(TableError),
    /// The periodic case does not exist.
    Periodic(PeriodicError),
}

impl std::fmt::Display for TableGenError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Optimize(e) => write!(f, "optimiser: {e}"),
            Self::Gait(e) => write!(f, "sampling: {e}"),
            Self::Table(e) => write!(f, "table: {e}"),
            Self::Periodic(e) => write!(f, "periodic case: {e}"),
        }
    }
}

impl std::error::Error for TableGenError {}

/// Φ at every sample of the step P describes (the IK at each t_k).
pub fn step_phi(
    problem: &PaperProblem<f64>,
    p: &ControlPoints<f64>,
) -> Result<Vec<Phi<f64>>, GaitError> {
    let step = problem.step(p);
    let ik = step.ik(&problem.model);
    let mut out = Vec::new();
    step.for_each_sample::<GaitError>(|s| {
        out.push(s.solve(&ik)?.phi);
        Ok(())
    })?;
    Ok(out)
}

/// A verified table image from Φ samples at [`TABLE_PERIOD_US`].
pub fn table_image(kind: GaitKind, phi: &[Phi<f64>]) -> Result<Vec<u8>, TableError> {
    let f: Vec<[f32; 5]> = phi.iter().map(|p| p.map(|v| v as f32)).collect();
    let mut buf = vec![0u8; image_len(f.len())];
    let n = encode(kind, TABLE_PERIOD_US, &f, &mut buf)?;
    buf.truncate(n);
    Ok(buf)
}

/// One generated table with its provenance.
#[derive(Clone, Debug, PartialEq)]
pub struct GeneratedTable {
    /// The gait.
    pub kind: GaitKind,
    /// Rust identifier of the static.
    pub ident: &'static str,
    /// How it was made (goes into the generated file).
    pub provenance: String,
    /// The image.
    pub image: Vec<u8>,
}

/// The problem a table is optimised on: the periodic case of `step` with
/// Table III and the paper's sampling.
pub fn table_problem(
    step: &PeriodicStep<f64>,
    velocity_weight: Option<f64>,
) -> Result<PaperProblem<f64>, TableGenError> {
    let model = BodyModel::paper_table_iii();
    let case = StepCase::periodic(step, &model).map_err(TableGenError::Periodic)?;
    let mut problem = PaperProblem::new(case, model);
    if let Some(vp) = velocity_weight {
        problem.velocity_weight = vp;
    }
    problem.joint_motion_limit = Some(JointMotionLimit {
        speed_rad_s: TABLE_JOINT_SPEED_RAD_S,
        speed_weight: TABLE_JOINT_SPEED_WEIGHT,
        accel_rad_s2: TABLE_JOINT_ACCEL_RAD_S2,
        accel_weight: TABLE_JOINT_ACCEL_WEIGHT,
    });
    problem.joint_range_limit = Some(JointRangeLimit {
        limits: *problem.model.limits(),
        margin_rad: TABLE_JOINT_RANGE_MARGIN_RAD,
        weight: TABLE_JOINT_RANGE_WEIGHT,
    });
    problem.count_every_sample = true;
    Ok(problem)
}

fn optimised(
    case: PaperCase,
    step: &PeriodicStep<f64>,
    velocity_weight: Option<f64>,
) -> Result<(Vec<Phi<f64>>, String), TableGenError> {
    let problem = table_problem(step, velocity_weight)?;
    let mut config = OptimizeConfig::new(case);
    if let Some(vp) = velocity_weight {
        config.explore_velocity_weight = 2.0 * vp;
    }
    let r = optimize_problem(&problem, &config, &mut |_| {}).map_err(TableGenError::Optimize)?;
    let phi = step_phi(&problem, &r.control_points).map_err(TableGenError::Gait)?;
    let c = r.cost;
    let figures = format!(
        "J = {:.1} (torque {:.1}, velocity {:.1}, joint motion {:.1}; τ RMS {:.1} N·m, \
         peak swing-ankle speed {:.2} m/s)",
        c.j, c.torque, c.velocity, c.joint_motion, c.tau_rms_nm, c.peak_ankle_speed_m_s
    );
    Ok((phi, figures))
}

/// The walk table (see the module documentation).
pub fn walk_table() -> Result<GeneratedTable, TableGenError> {
    let (phi, j) = optimised(
        PaperCase::Walk,
        &PeriodicStep::walk(),
        Some(WALK_VELOCITY_WEIGHT),
    )?;
    Ok(GeneratedTable {
        kind: GaitKind::Walk,
        ident: "WALK",
        provenance: format!(
            "periodic walk (PeriodicStep::walk) with v_p = {WALK_VELOCITY_WEIGHT} \
             (paper: 1000), seed 1, 20,000 evaluations; {j}"
        ),
        image: table_image(GaitKind::Walk, &phi).map_err(TableGenError::Table)?,
    })
}

/// The stair-ascent table (periodic, paper v_p).
pub fn stair_up_table() -> Result<GeneratedTable, TableGenError> {
    let (phi, j) = optimised(PaperCase::StairUp, &PeriodicStep::stair_up(), None)?;
    Ok(GeneratedTable {
        kind: GaitKind::StairUp,
        ident: "STAIR_UP",
        provenance: format!(
            "periodic stair ascent (PeriodicStep::stair_up), paper v_p, seed 1, \
             20,000 evaluations; {j}"
        ),
        image: table_image(GaitKind::StairUp, &phi).map_err(TableGenError::Table)?,
    })
}

/// The stair-descent table (periodic, toe rocker, human knee range, paper
/// v_p).
pub fn stair_down_table() -> Result<GeneratedTable, TableGenError> {
    let (phi, j) = optimised(PaperCase::StairUp, &PeriodicStep::stair_down(), None)?;
    Ok(GeneratedTable {
        kind: GaitKind::StairDown,
        ident: "STAIR_DOWN",
        provenance: format!(
            "periodic stair descent (PeriodicStep::stair_down: toe rocker, \
             KneeRange::Human), paper v_p, seed 1, 20,000 evaluations; {j}"
        ),
        image: table_image(GaitKind::StairDown, &phi).map_err(TableGenError::Table)?,
    })
}

/// The source of `crates/gait-core/src/flash_tables.rs`.
pub fn flash_module_source() -> Result<String, TableGenError> {
    let tables = [walk_table()?, stair_up_table()?, stair_down_table()?];
    let mut s = String::new();
    let _ = writeln!(
        s,
        "//! GENERATED by `cargo xtask tables` (crates/gait-opt/src/tables.rs,\n\
         //! crates/gait-opt/examples/flash_tables.rs). Do not edit by hand: a test\n\
         //! (gait-opt, `flash_tables_match_the_generator`) regenerates it and\n\
         //! compares.\n\
         //!\n\
         //! The gait tables the firmware carries in flash, in the format of\n\
         //! [`crate::tables`] (verified by [`crate::tables::GaitTable::parse`]\n\
         //! before any use).\n\
         #![allow(clippy::unreadable_literal)]\n\
         \n\
         use crate::tables::{{GaitTable, TableError}};\n"
    );
    for t in &tables {
        let _ = writeln!(s, "/// {:?}: {}.", t.kind, t.provenance);
        let _ = writeln!(s, "pub static {}: [u8; {}] = [", t.ident, t.image.len());
        for chunk in t.image.chunks(16) {
            let line: Vec<String> = chunk.iter().map(|b| format!("0x{b:02x}")).collect();
            let _ = writeln!(s, "    {},", line.join(", "));
        }
        let _ = writeln!(s, "];\n");
    }
    let _ = writeln!(
        s,
        "/// The walking table, verified.\n\
         pub fn walk() -> Result<GaitTable<'static>, TableError> {{\n    GaitTable::parse(&WALK)\n}}\n\n\
         /// The stair-ascent table, verified.\n\
         pub fn stair_up() -> Result<GaitTable<'static>, TableError> {{\n    GaitTable::parse(&STAIR_UP)\n}}\n\n\
         /// The stair-descent table, verified.\n\
         pub fn stair_down() -> Result<GaitTable<'static>, TableError> {{\n    GaitTable::parse(&STAIR_DOWN)\n}}"
    );
    Ok(s)
}
