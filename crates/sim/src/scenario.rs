//! Ready-made closed-loop set-ups: the device with the tables it carries in
//! flash, standing in the walk table's start posture, with a pilot who knows
//! the gait; and the main job, one walking step from GO to landing.

use exogait_device::DeviceConfig;
use gait_control::operator::Gait;
use gait_control::sequencer::{GaitTables, Phase};
use gait_core::BodyModel;
use gait_core::bundle::{BundleError, GaitInfo, GaitName, GaitSource, Patient, bundle_len, encode};
use gait_core::clinical::riser_behind_stance_x;
use gait_core::flash_tables::{STAIR_DOWN, WALK};
use gait_core::foot::StanceFoot;
use gait_core::tables::{GaitKind, GaitTable};

use crate::closed_loop::{PilotBehaviour, Rig, RigError, RigSetup};
use crate::pilot::PilotConfig;
use crate::plant::{PlantConfig, Side, SimError};
use crate::summary::{RunSummary, summarise};
use crate::terrain::Terrain;

/// The tables the firmware carries (`gait_core::flash_tables`), verified.
pub fn flash_tables() -> GaitTables<'static> {
    GaitTables::by_kind(
        gait_core::flash_tables::walk().ok(),
        gait_core::flash_tables::stair_up().ok(),
        gait_core::flash_tables::stair_down().ok(),
    )
}

/// A bundle for `patient` on `device` of the flash tables' stair descent
/// (`down`), then walk (`walk`): a clinician's list in an order of its own,
/// not the built-in one, to boot and play from. The gaits' descriptions
/// carry the same placeholder figures (nothing plays them) and the flash
/// tables' stance-hip residual limits.
pub fn descent_then_walk_bundle(
    device: &DeviceConfig,
    patient: &Patient,
) -> Result<Vec<u8>, BundleError> {
    let source = |entry: u8, name: &str, kind: GaitKind, table: &'static [u8]| {
        let name = GaitName::new(name).ok_or(BundleError::BadEntry(entry))?;
        let info = GaitInfo {
            name,
            kind,
            step_length_m: 0.3,
            rise_m: 0.0,
            tread_m: 0.0,
            step_time_s: 2.24,
            pace_m_s: 0.1,
            clearance_m: 0.05,
            // The device's own table's limit (NaN, none, reads 0).
            stance_hip_residual_nm: gait_core::flash_tables::of(kind)
                .map_or(0, |t| t.stance_hip_residual_nm() as u8),
        };
        Ok::<_, BundleError>(GaitSource { info, table })
    };
    let gaits = [
        source(0, "down", GaitKind::StairDown, &STAIR_DOWN)?,
        source(1, "walk", GaitKind::Walk, &WALK)?,
    ];
    let mut img = vec![0u8; bundle_len(&gaits)];
    encode(device.fingerprint(), 1, patient, &gaits, &mut img)?;
    Ok(img)
}

/// A pilot strong enough for the paper's walk (300 N·m through the
/// crutches, ≈ 670 N on them together at the 0.45 m lever), who meets an
/// unannounced safe hold as a person does: 0.15 s to react (an arm's
/// automatic response starts ≈ 0.1 s after a perturbation, a voluntary one
/// 0.18–0.23 s), then 1.5 s to move the body to the hold's aim (a
/// deliberate move of the body by the arms takes 1–2 s). Sources and
/// what an instant pilot changes: `docs/campaign.md`.
pub fn strong_pilot() -> PilotConfig {
    PilotConfig {
        torque_limit_nm: 300.0,
        gravity_compensation: 1.0,
        hold_reaction_s: 0.15,
        hold_recovery_s: 1.5,
        ..PilotConfig::default()
    }
}

/// [`strong_pilot`] meeting a safe hold on the tick it begins with all
/// its strength: no person can (kept to compare the campaign against).
pub fn instant_pilot() -> PilotConfig {
    PilotConfig {
        hold_reaction_s: 0.0,
        hold_recovery_s: 0.0,
        ..strong_pilot()
    }
}

/// The device standing (double support) in the walk table's start posture,
/// left leg in front as stance, the pilot following the plan, the plant held
/// still for the first 60 ms while the drives soft-start (40 ms).
pub fn walk_rig(pilot: PilotConfig, tables: GaitTables<'static>) -> Result<Rig<'static>, RigError> {
    gait_rig(Gait::Walk, pilot, tables)
}

/// Where a table puts the feet: the landing point of its swing ankle
/// relative to the stance foot (flat-foot frame, m) and the world layout
/// that goes with it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableGeometry {
    /// The swing ankle's landing point relative to the stance ankle's
    /// flat-foot position, m: (tread or step length, rise).
    pub landing_m: [f64; 2],
    /// The ground for it: level, or a staircase up or down.
    pub terrain: Terrain,
    /// World position of the first stance ankle, m (on its tread).
    pub stance_foot_m: [f64; 2],
}

/// The geometry of `table` on `model`: the landing point from its last
/// posture (the stance ankle may have rolled onto its toe); on stairs the
/// riser just ahead of the trailing foot's toe
/// ([`gait_core::clinical::riser_behind_stance_x`], the rule the table
/// generator designs for), the stance foot on the first step up or down;
/// [`STAIR_STEPS`] steps.
pub fn table_geometry(table: &GaitTable<'_>, model: &BodyModel<f64>) -> TableGeometry {
    let foot = StanceFoot::for_model(model);
    let last = table.last().map(f64::from);
    let landing_m = foot.points(model, &last)[4];
    let [tread, rise] = landing_m;
    let (terrain, stance_y) = match riser_behind_stance_x(landing_m, &foot) {
        None => (Terrain::Level, 0.0),
        Some(riser) => (
            Terrain::Stairs {
                start_x_m: riser,
                rise_m: rise,
                tread_m: tread,
                steps: STAIR_STEPS,
            },
            rise,
        ),
    };
    TableGeometry {
        landing_m,
        terrain,
        stance_foot_m: [0.0, stance_y],
    }
}

/// The device standing in `gait`'s start posture, left leg in front as
/// stance (on the first step for stair ascent, on the first tread down for
/// descent, [`table_geometry`]), the pilot following the table, the plant
/// held still for the first 60 ms while the drives soft-start.
pub fn gait_rig(
    gait: Gait,
    pilot: PilotConfig,
    tables: GaitTables<'static>,
) -> Result<Rig<'static>, RigError> {
    let device = DeviceConfig::exogait().map_err(RigError::Device)?;
    table_rig(&device, gait, pilot, tables)
}

/// [`gait_rig`] for any device configuration and tables.
pub fn table_rig<'t>(
    device: &DeviceConfig,
    gait: Gait,
    pilot: PilotConfig,
    tables: GaitTables<'t>,
) -> Result<Rig<'t>, RigError> {
    let table = tables
        .get(gait)
        .copied()
        .ok_or(RigError::Config("no verified table for the gait"))?;
    let geometry = table_geometry(&table, &device.body);
    table_rig_on(device, gait, pilot, tables, geometry.terrain)
}

/// [`table_rig`] on `terrain` instead of the ground the table was planned
/// for (a tread lower or higher than planned, a curb), the stance foot on
/// it.
pub fn table_rig_on<'t>(
    device: &DeviceConfig,
    gait: Gait,
    pilot: PilotConfig,
    tables: GaitTables<'t>,
    terrain: Terrain,
) -> Result<Rig<'t>, RigError> {
    rig_with(device, gait, pilot, tables, terrain, None)
}

/// A patient's rig: `tables` and the clinician's list `operator` of their
/// bundle (`exogait_device::boot::patient_gaits`), the pilot standing in
/// the start posture of the first table of `stand_for`, on its ground.
pub fn patient_rig<'t>(
    device: &DeviceConfig,
    stand_for: Gait,
    pilot: PilotConfig,
    tables: GaitTables<'t>,
    operator: gait_control::operator::OperatorConfig,
) -> Result<Rig<'t>, RigError> {
    let table = tables
        .get(stand_for)
        .copied()
        .ok_or(RigError::Config("no verified table for the gait"))?;
    let terrain = table_geometry(&table, &device.body).terrain;
    rig_with(device, stand_for, pilot, tables, terrain, Some(operator))
}

fn rig_with<'t>(
    device: &DeviceConfig,
    gait: Gait,
    pilot: PilotConfig,
    tables: GaitTables<'t>,
    terrain: Terrain,
    operator: Option<gait_control::operator::OperatorConfig>,
) -> Result<Rig<'t>, RigError> {
    let table = tables
        .get(gait)
        .copied()
        .ok_or(RigError::Config("no verified table for the gait"))?;
    let setup = RigSetup {
        device: *device,
        plant: PlantConfig {
            pilot,
            terrain,
            // After an impact the trailing foot lifts off by a centimetre or
            // two and hovers through the weight transfer; with the default
            // 1 cm its settling back onto a stair tread counted as a landing
            // and swapped the legs back at the start of the next swing.
            lift_clearance_m: LIFT_CLEARANCE_M,
            ..PlantConfig::default()
        },
        phi: table.first().map(f64::from),
        stance: Side::Left,
        stance_foot_m: [0.0, terrain.height_m(0.0)],
        pilot: PilotBehaviour::FollowsTable,
        gait,
        support_ticks: 60,
        operator,
    };
    Rig::new(&setup, tables)
}

/// Steps of the simulated staircases (twenty steps and more can be
/// climbed or descended).
pub const STAIR_STEPS: u32 = 24;

/// Height the swing ankle must rise before a landing counts in the rigs, m
/// (gaits lift the foot 3–8 cm; the trailing foot hovers 1–2 cm after an
/// impact).
pub const LIFT_CLEARANCE_M: f64 = 0.025;

/// When GO is pressed in [`walk_step`] (tick), and for how long.
pub const GO_AT_TICK: u64 = 400;
/// GO is held past the 1 s long press.
pub const GO_TICKS: u64 = 1200;

/// One closed-loop run and what it did.
pub struct StepRun<'t> {
    /// The rig, with its trace.
    pub rig: Rig<'t>,
    /// The summary.
    pub summary: RunSummary,
    /// Why the simulation stopped early (the plant fell or blew up), if it
    /// did; the summary covers what happened before.
    pub ended_by: Option<SimError>,
}

/// The main job: GO and walking with the flash table until `steps`
/// landings have happened and 1.5 s more (or a safe hold has lasted 1 s, or
/// `max_s` in all).
pub fn walk_step(max_s: f64) -> Result<StepRun<'static>, RigError> {
    walk(max_s, 1)
}

/// See [`walk_step`]; `steps` landings.
pub fn walk(max_s: f64, steps: usize) -> Result<StepRun<'static>, RigError> {
    run_gait(Gait::Walk, max_s, steps)
}

/// `gait` from standing (see [`gait_rig`]): GO, then steps until `steps`
/// landings have happened and 1.5 s more (or a safe hold has lasted 1 s, or
/// `max_s` in all).
pub fn run_gait(gait: Gait, max_s: f64, steps: usize) -> Result<StepRun<'static>, RigError> {
    run_gait_with(gait, max_s, steps, |_| {})
}

/// [`run_gait`], with `prepare` applied to the rig before the first tick
/// (sensor noise, fault injection, other button scripts).
pub fn run_gait_with(
    gait: Gait,
    max_s: f64,
    steps: usize,
    prepare: impl FnOnce(&mut Rig<'static>),
) -> Result<StepRun<'static>, RigError> {
    let device = DeviceConfig::exogait().map_err(RigError::Device)?;
    run_gait_on(&device, gait, max_s, steps, prepare)
}

/// [`run_gait_with`] on `device`: `gait` from its [`flash_tables`] with the
/// [`strong_pilot`] (see [`run_tables_with`]).
pub fn run_gait_on(
    device: &DeviceConfig,
    gait: Gait,
    max_s: f64,
    steps: usize,
    prepare: impl FnOnce(&mut Rig<'static>),
) -> Result<StepRun<'static>, RigError> {
    run_tables_with(
        device,
        flash_tables(),
        gait,
        strong_pilot(),
        max_s,
        steps,
        prepare,
    )
}

/// Ticks `rig` until `steps` landings have happened and 1.5 s more, a safe
/// hold has lasted 1 s, the plant fails (its error), or `max_s` in all.
pub fn run_steps(rig: &mut Rig<'_>, steps: usize, max_s: f64) -> Result<(), SimError> {
    run_steps_then(rig, steps, max_s, 1.5)
}

/// [`run_steps`], going on for `tail_s` after the last landing asked for
/// instead of 1.5 s.
pub fn run_steps_then(
    rig: &mut Rig<'_>,
    steps: usize,
    max_s: f64,
    tail_s: f64,
) -> Result<(), SimError> {
    let dt = rig.plant.config().dt_s;
    let max_ticks = (max_s / dt) as u64;
    let tail = (tail_s / dt).round() as usize;
    let mut landed_at: Option<usize> = None;
    let mut held_since: Option<usize> = None;
    for _ in 0..max_ticks {
        rig.tick()?;
        if landed_at.is_none() && rig.plant.landings().len() >= steps.max(1) {
            landed_at = Some(rig.trace.len());
        }
        if landed_at.is_some_and(|k| rig.trace.len() > k + tail) {
            break;
        }
        // From when the hold begins (a swing may land first) or the motors
        // are off.
        let holding = matches!(rig.phase(), Phase::SafeHold { .. })
            || rig.worst_reaction() >= gait_control::faults::Reaction::DisableMotors;
        if held_since.is_none() && holding {
            held_since = Some(rig.trace.len());
        }
        if held_since.is_some_and(|k| rig.trace.len() > k + 1000) {
            break;
        }
    }
    Ok(())
}

/// The rig of `gait` from `tables` on `device` with `pilot` (see
/// [`table_rig`]), standing, GO pressed at [`GO_AT_TICK`] for
/// [`GO_TICKS`], `prepare` applied: what every played gait starts from.
pub fn started_rig<'t>(
    device: &DeviceConfig,
    tables: GaitTables<'t>,
    gait: Gait,
    pilot: PilotConfig,
    prepare: impl FnOnce(&mut Rig<'t>),
) -> Result<Rig<'t>, RigError> {
    let mut rig = table_rig(device, gait, pilot, tables)?;
    Rig::press(&rig.go, GO_AT_TICK, GO_TICKS);
    prepare(&mut rig);
    Ok(rig)
}

/// `gait` from `tables` on `device` with `pilot`, from standing (see
/// [`table_rig`]): GO, then steps until `steps` landings have happened and
/// 1.5 s more (or a safe hold has lasted 1 s, or `max_s` in all).
pub fn run_tables_with<'t>(
    device: &DeviceConfig,
    tables: GaitTables<'t>,
    gait: Gait,
    pilot: PilotConfig,
    max_s: f64,
    steps: usize,
    prepare: impl FnOnce(&mut Rig<'t>),
) -> Result<StepRun<'t>, RigError> {
    let table = tables
        .get(gait)
        .copied()
        .ok_or(RigError::Config("no verified table for the gait"))?;
    let planned_landing_x_m = table_geometry(&table, &device.body).landing_m[0];
    let mut rig = started_rig(device, tables, gait, pilot, prepare)?;
    let result = run_steps(&mut rig, steps, max_s);
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
