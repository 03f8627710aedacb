//! The gait-table generator: optimised steps → verified binary tables →
//! the generated Rust module `crates/gait-core/src/flash_tables.rs` that
//! the firmware links into flash.
//!
//! Every table is a **clinical-mode** step ([`crate::clinical`]) on the
//! device's configuration (`exogait_device`): double support first, the
//! predicted crutch load as the cost, within the drives and the
//! supervisor's envelope, periodic (its landing posture, seen from the new
//! stance foot, is its start posture, so steps chain with the legs
//! alternating and the transfer between them moves no joint). The paper's
//! own problem stays in paper mode ([`crate::solver`]), for the record.
//!
//! Deterministic: the optimiser is seeded and budgeted by evaluation count,
//! so regenerating gives the same bytes; a test checks that the committed
//! module is what the generator produces.

use std::fmt::Write as _;

use gait_core::BodyModel;
use gait_core::gait::{ControlPoints, GaitError};
use gait_core::ik::IkOptions;
use gait_core::kinematics::Phi;
use gait_core::problem::{
    JointMotionLimit, JointRangeLimit, PaperProblem, PeriodicError, PeriodicStep, StepCase,
};
use gait_core::tables::{GaitKind, GaitTable, TableError, encode, image_len};

use exogait_device::DeviceConfig;

use crate::clinical::closed_loop::{RefineConfig, refine, replay};
use crate::clinical::{
    ClinicalCase, ClinicalConfig, ClinicalResult, ClinicalSearchError, DIM, decode,
    optimize_clinical,
};
use crate::clinical_report::{ClinicalReport, gait_name};
use crate::solver::OptimizeError;

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
    /// The clinical search failed.
    Clinical(ClinicalSearchError),
    /// The device configuration was refused.
    Device(exogait_device::DeviceError),
    /// The closed-loop refinement failed, or its record does not hold.
    Refine(String),
    /// A healthy closed-loop run of the table faulted or landed short
    /// (the stance hip's residual measured, `crate::residual_limit`).
    ClosedLoop(String),
}

impl std::fmt::Display for TableGenError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Optimize(e) => write!(f, "optimiser: {e}"),
            Self::Gait(e) => write!(f, "sampling: {e}"),
            Self::Table(e) => write!(f, "table: {e}"),
            Self::Periodic(e) => write!(f, "periodic case: {e}"),
            Self::Clinical(e) => write!(f, "clinical search: {e}"),
            Self::Device(e) => write!(f, "device configuration: {e:?}"),
            Self::Refine(e) => write!(f, "closed-loop refinement: {e}"),
            Self::ClosedLoop(e) => write!(f, "closed loop: {e}"),
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

/// A verified table image from Φ samples at [`TABLE_PERIOD_US`]; `ik`: the
/// IK options the samples were generated with (they go into the header,
/// and the controller plans its weight transfers with them).
pub fn table_image(
    kind: GaitKind,
    ik: &IkOptions<f64>,
    phi: &[Phi<f64>],
) -> Result<Vec<u8>, TableError> {
    let f: Vec<[f32; 5]> = phi.iter().map(|p| p.map(|v| v as f32)).collect();
    let mut buf = vec![0u8; image_len(f.len())];
    let n = encode(kind, TABLE_PERIOD_US, ik.cast(), &f, &mut buf)?;
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

/// The search settings of each clinical flash table, (seed, evaluations):
/// the seeds were chosen among the first ten by playing each result in the
/// closed loop for four steps (docs/optimiser.md, "Clinical mode"): the
/// prediction ranks the candidates, the closed loop decides.
pub fn clinical_table_search(kind: GaitKind) -> ClinicalConfig {
    let (seed, max_evals) = match kind {
        GaitKind::Walk => (1, 12_000),
        GaitKind::StairUp => (4, 16_000),
        GaitKind::StairDown => (1, 12_000),
    };
    ClinicalConfig { seed, max_evals }
}

/// The closed-loop refinement each table gets after its clinical search
/// (`None`: the search's point is the table). Only stair ascent: there the
/// closed loop adds most to the predicted crutch load (docs/optimiser.md,
/// "Where the targets stand"); walk and descent meet their targets as
/// searched.
pub fn closed_loop_refinement(kind: GaitKind) -> Option<RefineConfig> {
    match kind {
        GaitKind::StairUp => Some(RefineConfig {
            search_steps: 4,
            max_evals: 1000,
            initial_step: 0.02,
            min_step: 1e-4,
        }),
        GaitKind::Walk | GaitKind::StairDown => None,
    }
}

/// The clinical search of `kind` on `device` (the refinement's start).
pub fn clinical_start(
    kind: GaitKind,
    device: &DeviceConfig,
) -> Result<ClinicalResult, TableGenError> {
    let case = ClinicalCase::for_gait(kind, device);
    optimize_clinical(&case, &clinical_table_search(kind), &mut |_, _| {})
        .map_err(TableGenError::Clinical)
}

/// Where the closed-loop refinement's result comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum RefineSource {
    /// Run the search (`cargo xtask tables`; minutes).
    Search,
    /// Recompute the figures of a recorded refinement without the search,
    /// after checking that the clinical search still gives its start (the
    /// CI test; seconds).
    Recorded(Box<RefineRecord>),
}

/// What the generated file records of a refinement: enough to check and
/// recompute it without the search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineRecord {
    /// The clinical search's point, where the refinement started.
    pub start: [f64; DIM],
    /// The refined point.
    pub x: [f64; DIM],
    /// Search evaluations spent.
    pub evaluations: usize,
}

const START_X: &str = "start x = ";
const TABLE_X: &str = "table x = ";
const SEARCH_EVALS: &str = "search evaluations = ";

impl RefineRecord {
    /// The record in a generated module's doc comment of the table `ident`
    /// (`None` when it has none).
    pub fn from_flash_module(source: &str, ident: &str) -> Option<Self> {
        let decl = format!("pub static {ident}:");
        let at = source.find(&decl)?;
        let doc = source.get(..at)?.lines().rev().nth(0)?;
        let vector = |label: &str| -> Option<[f64; DIM]> {
            let from = doc.find(label)? + label.len();
            let rest = doc.get(from..)?.strip_prefix('[')?;
            let inner = rest.get(..rest.find(']')?)?;
            let v: Vec<f64> = inner
                .split(',')
                .map(|t| t.trim().parse().ok())
                .collect::<Option<_>>()?;
            v.try_into().ok()
        };
        let evals = {
            let from = doc.find(SEARCH_EVALS)? + SEARCH_EVALS.len();
            let digits: String = doc
                .get(from..)?
                .chars()
                .take_while(char::is_ascii_digit)
                .collect();
            digits.parse().ok()?
        };
        Some(Self {
            start: vector(START_X)?,
            x: vector(TABLE_X)?,
            evaluations: evals,
        })
    }
}

/// The clinical-mode table of `kind` on `device` (see the module
/// documentation), with its report: the clinical search, then, for the
/// gaits [`closed_loop_refinement`] names, the closed-loop refinement
/// (`refine` says how; `progress` sees the refinement's evaluations and
/// best value).
pub fn clinical_table(
    kind: GaitKind,
    device: &DeviceConfig,
    refine_source: &RefineSource,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<(GeneratedTable, ClinicalReport), TableGenError> {
    let case = ClinicalCase::for_gait(kind, device);
    let config = clinical_table_search(kind);
    let mut r = clinical_start(kind, device)?;
    let ident = match kind {
        GaitKind::Walk => "WALK",
        GaitKind::StairUp => "STAIR_UP",
        GaitKind::StairDown => "STAIR_DOWN",
    };
    let mut refined = String::new();
    if let Some(rc) = closed_loop_refinement(kind) {
        let f = match refine_source {
            RefineSource::Search => refine(&case, device, &r.x, &rc, progress),
            RefineSource::Recorded(rec) => {
                if rec.start != r.x {
                    return Err(TableGenError::Refine(format!(
                        "the clinical search no longer gives the recorded start: {:?}",
                        r.x
                    )));
                }
                replay(&case, device, &rec.start, &rec.x, rec.evaluations, &rc)
            }
        }
        .map_err(|e| TableGenError::Refine(e.to_string()))?;
        let [four, twenty] = &f.verified;
        let h = &f.human;
        refined = format!(
            "; closed-loop refinement (Hooke–Jeeves pattern search from the clinical search's \
             point on the balance part of {} closed-loop steps, first step {}, {START_X}{:?}, \
             {SEARCH_EVALS}{}): search objective {:.1} → {:.1} N·s; {TABLE_X}{:?}; closed loop \
             (strong pilot, device as shipped) balance part {:.1} N·s over 4 steps (clinical \
             search's point {:.1}; human-data gait at that point's geometry {:.1}, {:.1} % below \
             it), {:.1} N·s over 20, highest crutch peak {:.0} N over 4 and 20 steps (human {:.0} N \
             over 4), near the drive's peak {:.3} s a step",
            rc.search_steps,
            rc.initial_step,
            f.start,
            f.evaluations,
            f.search_ns[0],
            f.search_ns[1],
            f.x,
            four.mean_balance_ns,
            f.start_played.mean_balance_ns,
            h.balance_ns,
            100.0 * (1.0 - four.mean_balance_ns / h.balance_ns),
            twenty.mean_balance_ns,
            four.crutch_peak_n.max(twenty.crutch_peak_n),
            h.crutch_peak_n,
            four.near_peak_s_per_step.max(twenty.near_peak_s_per_step),
        );
        r = ClinicalResult {
            x: f.x,
            step: decode(&case, &f.x).map_err(|e| TableGenError::Refine(format!("{e:?}")))?,
            phi: f.phi,
            evaluation: f.evaluation,
            evaluations: r.evaluations,
        };
    }
    let report = ClinicalReport::new(&case, &r, config.seed);
    let e = &r.evaluation;
    let provenance = format!(
        "clinical mode ({}: spacing ({}, {}) m, ts {} s), seed {}, {} evaluations{refined}; \
         predicted balance impulse {:.1} N·s, pilot peak {:.1} N·m, joint peaks \
         {:.0}/{:.0}/{:.0}/{:.0} N·m, clearance {:.3} m",
        gait_name(kind),
        case.spacing_m[0],
        case.spacing_m[1],
        case.step_time_s,
        config.seed,
        config.max_evals,
        e.balance_ns,
        e.pilot_peak_nm,
        e.joint_peak_nm[0],
        e.joint_peak_nm[1],
        e.joint_peak_nm[2],
        e.joint_peak_nm[3],
        e.clearance_m
    );
    Ok((
        GeneratedTable {
            kind,
            ident,
            provenance,
            image: table_image(kind, &case.ik, &r.phi).map_err(TableGenError::Table)?,
        },
        report,
    ))
}

/// The walk table (clinical mode, the device's configuration).
pub fn walk_table() -> Result<GeneratedTable, TableGenError> {
    Ok(clinical_table(
        GaitKind::Walk,
        &device()?,
        &RefineSource::Search,
        &mut |_, _| {},
    )?
    .0)
}

/// The stair-ascent table (clinical mode, refined in the closed loop: a
/// few minutes).
pub fn stair_up_table() -> Result<GeneratedTable, TableGenError> {
    Ok(clinical_table(
        GaitKind::StairUp,
        &device()?,
        &RefineSource::Search,
        &mut |_, _| {},
    )?
    .0)
}

/// The stair-descent table (clinical mode).
pub fn stair_down_table() -> Result<GeneratedTable, TableGenError> {
    Ok(clinical_table(
        GaitKind::StairDown,
        &device()?,
        &RefineSource::Search,
        &mut |_, _| {},
    )?
    .0)
}

fn device() -> Result<DeviceConfig, TableGenError> {
    DeviceConfig::exogait().map_err(TableGenError::Device)
}

/// The source of `crates/gait-core/src/flash_tables.rs`, with the full
/// closed-loop refinement (minutes: see [`flash_module_source_with`]).
pub fn flash_module_source() -> Result<String, TableGenError> {
    flash_module_source_with(&RefineSource::Search, &mut |_, _| {})
}

/// The source of `crates/gait-core/src/flash_tables.rs`, the stair-ascent
/// refinement searched or recomputed from a record (`refine_source`), its
/// progress to `progress`.
pub fn flash_module_source_with(
    refine_source: &RefineSource,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<String, TableGenError> {
    let device = device()?;
    let mut table = |kind| clinical_table(kind, &device, refine_source, progress).map(|(t, _)| t);
    let tables = [
        table(GaitKind::Walk)?,
        table(GaitKind::StairUp)?,
        table(GaitKind::StairDown)?,
    ];
    let mut limits = [(0.0, 0u8); 3];
    for (limit, t) in limits.iter_mut().zip(&tables) {
        let table = GaitTable::parse(&t.image).map_err(TableGenError::Table)?;
        let max_s = 4.0 + 4.0 * (f64::from(table.duration_s()) + 3.0);
        *limit = crate::residual_limit::measure(&device, table, 4, max_s)
            .map_err(TableGenError::ClosedLoop)?;
    }
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
         use crate::tables::{{GaitKind, GaitTable, TableError}};\n"
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
    let names = [
        ("walking", "walk", "WALK"),
        ("stair-ascent", "stair_up", "STAIR_UP"),
        ("stair-descent", "stair_down", "STAIR_DOWN"),
    ];
    for ((what, f, ident), (peak, limit)) in names.iter().zip(limits) {
        let _ = writeln!(
            s,
            "/// The {what} table, verified, with the stance hip's torque-residual\n\
             /// limit of its swings: {limit} N·m (its healthy closed loop peaks at\n\
             /// {peak:.1} N·m there; `gait_opt::residual_limit`).\n\
             pub fn {f}() -> Result<GaitTable<'static>, TableError> {{\n    \
             GaitTable::parse(&{ident}).map(|t| t.with_stance_hip_residual_nm({limit}))\n}}\n"
        );
    }
    let _ = writeln!(
        s,
        "/// The table of a movement, verified.\n\
         pub fn of(kind: GaitKind) -> Result<GaitTable<'static>, TableError> {{\n    match kind {{\n        GaitKind::Walk => walk(),\n        GaitKind::StairUp => stair_up(),\n        GaitKind::StairDown => stair_down(),\n    }}\n}}"
    );
    Ok(s)
}
