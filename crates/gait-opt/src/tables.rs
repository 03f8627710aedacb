//! The gait-table generator: optimised steps → verified binary tables →
//! the generated Rust module `crates/gait-core/src/flash_tables.rs` that
//! the firmware links into flash.
//!
//! Which gaits and why (until a clinically constrained table family exists):
//! - **walk**: the paper's problem with the velocity weight raised from
//!   1,000 to 8,000 N²·m² per (m/s). The paper-mode optimum lands at 2.2 m/s
//!   and its last 0.2 s exceed the supervisor's joint-velocity limits; with
//!   v_p = 8,000 the swing-ankle peak is 0.83 m/s and the closed-loop
//!   simulation lands the foot within 3 cm of the planned point
//!   (`host-tests`, `a_swing_lands_on_the_planned_point`).
//! - **stair ascent**: the paper-mode optimum (peak swing-ankle speed
//!   1.1 m/s).
//! - **stair descent**: none yet (the paper defines no descent problem), so
//!   the gait cannot be selected.
//!
//! Deterministic: the optimiser is seeded and budgeted by evaluation count,
//! so regenerating gives the same bytes; a test checks that the committed
//! module is what the generator produces.

use std::fmt::Write as _;

use gait_core::gait::{ControlPoints, GaitError};
use gait_core::ik::IkSolver;
use gait_core::kinematics::Phi;
use gait_core::problem::{PaperCase, PaperProblem};
use gait_core::tables::{GaitKind, TableError, encode, image_len};

use crate::solver::{OptimizeConfig, OptimizeError, optimize_problem};

/// Velocity weight of the flash walk table, N²·m² per (m/s).
pub const WALK_VELOCITY_WEIGHT: f64 = 8000.0;
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
}

impl std::fmt::Display for TableGenError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Optimize(e) => write!(f, "optimiser: {e}"),
            Self::Gait(e) => write!(f, "sampling: {e}"),
            Self::Table(e) => write!(f, "table: {e}"),
        }
    }
}

impl std::error::Error for TableGenError {}

/// Φ at every sample of the step P describes (the IK at each t_k).
pub fn step_phi(
    problem: &PaperProblem<f64>,
    p: &ControlPoints<f64>,
) -> Result<Vec<Phi<f64>>, GaitError> {
    let ik = IkSolver::new(&problem.model);
    let mut out = Vec::new();
    problem.step(p).for_each_sample::<GaitError>(|s| {
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

fn optimised(
    case: PaperCase,
    velocity_weight: Option<f64>,
) -> Result<(Vec<Phi<f64>>, f64), TableGenError> {
    let mut problem = PaperProblem::<f64>::paper(case);
    let mut config = OptimizeConfig::new(case);
    if let Some(vp) = velocity_weight {
        problem.velocity_weight = vp;
        config.explore_velocity_weight = 2.0 * vp;
    }
    let r = optimize_problem(&problem, &config, &mut |_| {}).map_err(TableGenError::Optimize)?;
    let phi = step_phi(&problem, &r.control_points).map_err(TableGenError::Gait)?;
    Ok((phi, r.cost.j))
}

/// The walk table (see the module documentation).
pub fn walk_table() -> Result<GeneratedTable, TableGenError> {
    let (phi, j) = optimised(PaperCase::Walk, Some(WALK_VELOCITY_WEIGHT))?;
    Ok(GeneratedTable {
        kind: GaitKind::Walk,
        ident: "WALK",
        provenance: format!(
            "paper walk problem with v_p = {WALK_VELOCITY_WEIGHT} (paper: 1000), seed 1, \
             20,000 evaluations; J = {j:.1} at that v_p"
        ),
        image: table_image(GaitKind::Walk, &phi).map_err(TableGenError::Table)?,
    })
}

/// The stair-ascent table (paper mode).
pub fn stair_up_table() -> Result<GeneratedTable, TableGenError> {
    let (phi, j) = optimised(PaperCase::StairUp, None)?;
    Ok(GeneratedTable {
        kind: GaitKind::StairUp,
        ident: "STAIR_UP",
        provenance: format!("paper-mode stair-up optimum, seed 1, 20,000 evaluations; J = {j:.1}"),
        image: table_image(GaitKind::StairUp, &phi).map_err(TableGenError::Table)?,
    })
}

/// The source of `crates/gait-core/src/flash_tables.rs`.
pub fn flash_module_source() -> Result<String, TableGenError> {
    let tables = [walk_table()?, stair_up_table()?];
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
         //! before any use). Stair descent has no table yet.\n\
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
         pub fn stair_up() -> Result<GaitTable<'static>, TableError> {{\n    GaitTable::parse(&STAIR_UP)\n}}"
    );
    Ok(s)
}
