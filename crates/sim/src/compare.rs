//! The paper's Table II in the closed loop: a gait table played step by
//! step by the real controller on the simulated device and pilot, and the
//! crutch load of each step, so that two tables (the one the firmware ships
//! and the human-data gait) can be compared on the same device.
//!
//! Per step, over its window — from the start of its swing to its landing
//! plus the weight transfer (the sequencer's `transfer_s`), the paper's
//! window of a step:
//! - F = T_s Σ (f_l + f_r), the crutch impulse from the plant's true crutch
//!   forces, N·s;
//! - its balance part: F less the pilot's constant lean on the crutches
//!   (Σ |τ_pilot| / lever · T_s: what the gait changes);
//! - each crutch's peak force, N;
//! - the time the pilot's torque was at its limit, s;
//! - where the foot landed against the table's plan, m.

use exogait_device::DeviceConfig;
use gait_control::operator::Gait;
use gait_control::sequencer::{GaitTables, Phase};
use gait_core::tables::{GaitKind, GaitTable};

use crate::closed_loop::{Rig, RigError};
use crate::pilot::PilotConfig;
use crate::scenario::{run_steps_then, started_rig, table_geometry};

/// One step's crutch load.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepLoad {
    /// Start of the swing, s.
    pub start_s: f64,
    /// End of the window (landing + transfer, or the end of the run), s.
    pub end_s: f64,
    /// F = T_s Σ (f_l + f_r), N·s.
    pub impulse_ns: f64,
    /// F less the pilot's constant lean, N·s.
    pub balance_ns: f64,
    /// Peak force of the left and right crutch, N.
    pub peak_n: [f64; 2],
    /// Time the pilot's torque was at its limit, s.
    pub saturated_s: f64,
    /// Landing x less the plan's, m (`None`: the step did not land): the
    /// drift of the steps so far.
    pub landing_error_m: Option<f64>,
    /// This step's own error: its landing less the previous one (or the
    /// stance foot the run started on) less the planned step, m.
    pub step_error_m: Option<f64>,
    /// Time the device waited for the pilot before this step's swing
    /// (readiness, and a re-plan's latency), s.
    pub waited_s: f64,
    /// When it landed, s (`None`: it did not).
    pub landing_s: Option<f64>,
}

/// A gait played for a number of steps.
#[derive(Clone, Debug, PartialEq)]
pub struct GaitRun {
    /// Every step whose swing started.
    pub steps: Vec<StepLoad>,
    /// Landings (leg is implied: they alternate), world x, m.
    pub landings_m: Vec<[f64; 2]>,
    /// Faults latched, as ("0x0401", name).
    pub faults: Vec<(String, &'static str)>,
    /// Why the simulation stopped early, if it did.
    pub ended_by: Option<String>,
    /// Time, crutch forces (left, right) and pilot torque of every tick,
    /// for plots.
    pub series: Vec<(f64, [f64; 2], f64)>,
}

impl GaitRun {
    /// Steps that landed.
    pub fn landed(&self) -> usize {
        self.steps
            .iter()
            .filter(|s| s.landing_error_m.is_some())
            .count()
    }

    /// Mean over the landed steps of a quantity (`None` without one).
    pub fn mean(&self, f: impl Fn(&StepLoad) -> f64) -> Option<f64> {
        let landed: Vec<f64> = self
            .steps
            .iter()
            .filter(|s| s.landing_error_m.is_some())
            .map(f)
            .collect();
        (!landed.is_empty()).then(|| landed.iter().sum::<f64>() / landed.len() as f64)
    }

    /// Progression, m/s: how far forward the last landed step's foot came
    /// down (world x; the first stance ankle stands at 0) over the time
    /// from the first swing's start to that landing; 0 without a landing.
    pub fn progression_m_s(&self) -> f64 {
        let t0 = self.steps.first().map(|s| s.start_s);
        let last = self
            .steps
            .iter()
            .zip(&self.landings_m)
            .filter_map(|(s, p)| s.landing_s.map(|t| (t, p[0])))
            .next_back();
        match (t0, last) {
            (Some(t0), Some((t, x))) if t > t0 => x / (t - t0),
            _ => 0.0,
        }
    }

    /// Highest crutch peak over the landed steps, N.
    pub fn peak_n(&self) -> Option<f64> {
        self.steps
            .iter()
            .filter(|s| s.landing_error_m.is_some())
            .map(|s| s.peak_n[0].max(s.peak_n[1]))
            .reduce(f64::max)
    }
}

/// The gait of a table kind.
pub fn gait_of(kind: GaitKind) -> Gait {
    match kind {
        GaitKind::Walk => Gait::Walk,
        GaitKind::StairUp => Gait::StairUp,
        GaitKind::StairDown => Gait::StairDown,
    }
}

/// Tables holding only `table`, under its kind.
pub fn tables_of<'t>(table: GaitTable<'t>) -> GaitTables<'t> {
    match table.kind() {
        GaitKind::Walk => GaitTables::by_kind(Some(table), None, None),
        GaitKind::StairUp => GaitTables::by_kind(None, Some(table), None),
        GaitKind::StairDown => GaitTables::by_kind(None, None, Some(table)),
    }
}

/// How long a run plays: `steps` landings, then `tail_s` more (a search
/// that needs only the steps' windows stops at the end of the last weight
/// transfer, the sequencer's `transfer_s`); 1 s into a safe hold, or
/// `max_s` in all, at most.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunLength {
    /// Landings asked for.
    pub steps: usize,
    /// The longest the run may last, s.
    pub max_s: f64,
    /// Time after the last landing asked for, s.
    pub tail_s: f64,
}

/// Plays `table` on `device` with `pilot` from standing: GO, then `steps`
/// steps (the run ends 1.5 s after the last landing asked for, 1 s into a
/// safe hold, or at `max_s`); `prepare` is applied to the rig before the
/// first tick. Returns the rig too (its trace, for plots and tests).
pub fn play<'t>(
    device: &DeviceConfig,
    table: GaitTable<'t>,
    pilot: PilotConfig,
    steps: usize,
    max_s: f64,
    prepare: impl FnOnce(&mut Rig<'t>),
) -> Result<(GaitRun, Rig<'t>), RigError> {
    let length = RunLength {
        steps,
        max_s,
        tail_s: 1.5,
    };
    play_for(device, table, pilot, length, prepare)
}

/// [`play`] for `length`.
pub fn play_for<'t>(
    device: &DeviceConfig,
    table: GaitTable<'t>,
    pilot: PilotConfig,
    length: RunLength,
    prepare: impl FnOnce(&mut Rig<'t>),
) -> Result<(GaitRun, Rig<'t>), RigError> {
    let RunLength {
        steps,
        max_s,
        tail_s,
    } = length;
    let gait = gait_of(table.kind());
    let geometry = table_geometry(&table, &device.body);
    let mut rig = started_rig(device, tables_of(table), gait, pilot, prepare)?;
    let ended_by = run_steps_then(&mut rig, steps, max_s, tail_s)
        .err()
        .map(|e| e.to_string());
    let mut run = measure(&rig, device, &pilot, geometry.landing_m, ended_by);
    // A swing started after the last step asked for is not one of them.
    run.steps.truncate(steps);
    Ok((run, rig))
}

/// The per-step figures of a rig's trace (see the module documentation).
fn measure(
    rig: &Rig<'_>,
    device: &DeviceConfig,
    pilot: &PilotConfig,
    step_m: [f64; 2],
    ended_by: Option<String>,
) -> GaitRun {
    let dt = f64::from(device.dt_s);
    let transfer = f64::from(device.controller.sequencer.transfer_s);
    let trace = &rig.trace;
    let starts: Vec<f64> = trace
        .windows(2)
        .filter(|w| {
            matches!(w[1].report.phase, Phase::Swing { .. })
                && !matches!(w[0].report.phase, Phase::Swing { .. })
        })
        .map(|w| w[1].state.time_s - dt)
        .collect();
    let waits = crate::summary::waited_before_swings(trace, dt);
    let landings = rig.plant.landings();
    // Where the first step starts from: the stance ankle the run began on
    // (0 unless the pilot placed the foot off: `Rig::place_stance_foot`).
    let start_foot_x = trace.first().map_or(0.0, |s| s.state.points_m[0][0]);
    let end_of_run = trace.last().map_or(0.0, |s| s.state.time_s);
    let limit = pilot.torque_limit_nm - 1e-9;
    let steps = starts
        .iter()
        .enumerate()
        .map(|(i, &start)| {
            // The landing that ends this step: the first after its start.
            let landing = landings.iter().find(|l| l.time_s > start);
            let next_start = starts.get(i + 1).copied().unwrap_or(f64::INFINITY);
            let end = landing.map_or(end_of_run, |l| (l.time_s + transfer).min(next_start));
            let waited_s = waits.get(i).copied().unwrap_or(0.0);
            let mut s = StepLoad {
                start_s: start,
                end_s: end,
                impulse_ns: 0.0,
                balance_ns: 0.0,
                peak_n: [0.0; 2],
                saturated_s: 0.0,
                landing_error_m: None,
                step_error_m: None,
                waited_s,
                landing_s: None,
            };
            for t in trace
                .iter()
                .filter(|t| t.state.time_s > start && t.state.time_s <= end)
            {
                let f = t.state.crutch_forces_n;
                s.impulse_ns += (f[0] + f[1]) * dt;
                s.balance_ns += t.state.pilot_torque_nm.abs() / pilot.crutch_lever_m * dt;
                s.peak_n = [s.peak_n[0].max(f[0]), s.peak_n[1].max(f[1])];
                if t.state.pilot_torque_nm.abs() >= limit {
                    s.saturated_s += dt;
                }
            }
            if let Some(l) = landing.filter(|l| l.time_s < next_start) {
                let k = (i + 1) as f64;
                s.landing_error_m = Some(l.position_m[0] - step_m[0] * k);
                let from = landings
                    .iter()
                    .rev()
                    .find(|p| p.time_s < start)
                    .map_or(start_foot_x, |p| p.position_m[0]);
                s.step_error_m = Some(l.position_m[0] - from - step_m[0]);
                s.landing_s = Some(l.time_s);
            }
            s
        })
        .collect();
    GaitRun {
        steps,
        landings_m: landings.iter().map(|l| l.position_m).collect(),
        faults: rig
            .faults()
            .iter()
            .map(|c| (format!("0x{:04x}", c.code()), c.name()))
            .collect(),
        ended_by,
        series: trace
            .iter()
            .map(|t| {
                (
                    t.state.time_s,
                    t.state.crutch_forces_n,
                    t.state.pilot_torque_nm,
                )
            })
            .collect(),
    }
}

/// Reduction of `ours` against `theirs`, %: 100 (1 − ours/theirs).
pub fn reduction_pct(ours: Option<f64>, theirs: Option<f64>) -> Option<f64> {
    match (ours, theirs) {
        (Some(a), Some(b)) if b.abs() > 1e-12 => Some(100.0 * (1.0 - a / b)),
        _ => None,
    }
}

/// The swing foot's lowest clearance over a stair nosing it crossed in a
/// run, m (`None` on level ground, or when no swing crossed one): at each
/// swing tick whose foot spans a riser (heel behind it, toe ahead), the
/// swing ankle's height above that nosing, in the plant's ankle-level
/// convention (heights are where an ankle standing there is, the foot
/// level under it); going down, not the edge the foot steps off. Ticks before the ankle has travelled
/// [`ROLL_TRAVEL_M`] from where its swing began are skipped: the foot is
/// still rolling on its planted toe, which stands behind the riser.
pub fn nosing_clearance_m(rig: &Rig<'_>) -> Option<f64> {
    use crate::terrain::Terrain;
    use gait_core::clinical::HEEL_M;
    use gait_core::foot::TOE_M;
    let Terrain::Stairs {
        start_x_m,
        rise_m,
        tread_m,
        steps,
    } = rig.plant.config().terrain
    else {
        return None;
    };
    let risers: Vec<(f64, f64)> = (0..steps)
        .map(|k| {
            let k = f64::from(k);
            (
                start_x_m + k * tread_m,
                (rise_m * k).max(rise_m * (k + 1.0)),
            )
        })
        .collect();
    let terrain = rig.plant.config().terrain;
    let mut swing_start_x: Option<f64> = None;
    let mut lowest: Option<f64> = None;
    for s in &rig.trace {
        let [x, y] = s.state.points_m[5];
        if !matches!(s.report.phase, Phase::Swing { .. }) {
            swing_start_x = None;
            continue;
        }
        let start = *swing_start_x.get_or_insert(x);
        if (x - start).abs() < ROLL_TRAVEL_M {
            continue;
        }
        // Going down, the edge of the tread the foot leaves is no obstacle:
        // the foot moves off it above its own tread.
        let own_edge = terrain.height_m(start);
        for (rx, nosing) in &risers {
            let leaving = rise_m < 0.0 && (nosing - own_edge).abs() < 1e-3;
            if !leaving && x - HEEL_M <= *rx && *rx <= x + TOE_M {
                let c = y - nosing;
                lowest = Some(lowest.map_or(c, |l: f64| l.min(c)));
            }
        }
    }
    lowest
}

/// How far a swing ankle travels while its foot rolls on its planted toe
/// (at most 2 cm up to a 30° pitch), with margin, m.
pub const ROLL_TRAVEL_M: f64 = 0.03;
