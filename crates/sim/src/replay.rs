//! Recordings of the controller's inputs for a replay on the target
//! (`exogait_device::tick_record`): the QEMU image plays them through the
//! same controller, times every tick per phase and compares its motor
//! commands with the host's (`cargo xtask qemu`).
//!
//! [`record_gaits`] records what the main job and the fault campaign
//! exercise: two steps of each gait with the flash tables and the simulated
//! pilot, and a walk whose stance knee's encoder jumps in mid-swing, so the
//! supervisor's safe hold is timed too; [`record_replanning`], a run with
//! the idle-time re-planner on. No sensor noise: a record holds one sample
//! of each reading.

use exogait_device::DeviceConfig;
use exogait_device::tick_record::{self, TickRecord};
use gait_control::operator::Gait;

use crate::closed_loop::RigError;
use crate::inject::Injection;
use crate::scenario::{run_gait_on, run_tables_with, strong_pilot};

/// One recorded run.
#[derive(Clone, Debug)]
pub struct Recording {
    /// The gait the controller was built for.
    pub gait: Gait,
    /// What was recorded, tick by tick.
    pub ticks: Vec<TickRecord>,
}

/// The runs [`record_gaits`] makes: gait, steps, longest run (s), fault.
const RUNS: [(Gait, usize, f64, Option<&str>); 5] = [
    (Gait::Walk, 2, 12.0, None),
    (Gait::StairUp, 2, 12.0, None),
    (Gait::StairDown, 2, 12.0, None),
    // Mid first swing (1.36–3.54 s): a jump on the right knee, its offset
    // taken out; the step lands, then a safe hold for the second left.
    (Gait::Walk, 2, 4.5, Some("encoder-jump=300:right-knee@2.4")),
    // Mid first swing of a stair ascent: the swing knee's encoder freezes,
    // found 100 ms later; the knee braked, the hold sets the swing foot
    // down onto the tread (an IK a tick). (A record carries counts, not a
    // frame's errors: a parity or bus fault would replay as good frames.)
    (Gait::StairUp, 1, 4.0, Some("encoder-stuck:right-knee@2.4")),
];

/// Records the runs above on `device` with the flash tables.
pub fn record_gaits(device: &DeviceConfig) -> Result<Vec<Recording>, RigError> {
    RUNS.iter()
        .map(|&(gait, steps, max_s, fault)| {
            let injection: Option<Injection> = fault.and_then(|f| f.parse().ok());
            let run = run_gait_on(device, gait, max_s, steps, |rig| {
                rig.record_ticks();
                if let Some(f) = injection {
                    rig.schedule(f);
                }
            })?;
            Ok(Recording {
                gait,
                ticks: run.rig.recorded.unwrap_or_default(),
            })
        })
        .collect()
}

/// Records `steps` steps of a patient bundle's first gait on the device
/// fitted to its patient (`fitted`), the bundle's tables in its order: the
/// run the QEMU image replays through the controller the board builds for
/// that bundle (`cargo xtask qemu --bundle`).
pub fn record_bundle_step(
    fitted: &DeviceConfig,
    bundle: &gait_core::bundle::Bundle<'_>,
    steps: usize,
) -> Result<Recording, RigError> {
    let first = bundle
        .gait(0)
        .ok_or(RigError::Config("the bundle holds no gait"))?;
    let tables: Vec<_> = (0..bundle.len())
        .map(|i| bundle.gait(i).map(|g| g.table))
        .collect();
    let gait = gait_control::sequencer::gait_of_kind(first.table.kind());
    let max_s = 6.0 + steps as f64 * (f64::from(first.table.duration_s()) + 2.0);
    let run = run_tables_with(
        fitted,
        gait_control::sequencer::GaitTables::in_order(&tables),
        gait,
        strong_pilot(),
        max_s,
        steps,
        |rig| rig.record_ticks(),
    )?;
    Ok(Recording {
        gait,
        ticks: run.rig.recorded.unwrap_or_default(),
    })
}

/// The lean of the pilot [`record_replanning`] records: 2° forward over
/// the table's start, rad (within the table's start tolerance, so that
/// the same pilot can step without re-planning).
pub const REPLANNING_LEAN_RAD: f64 = 0.034_906_585;

/// Records `steps` stair-descent steps of a pilot leaning
/// [`REPLANNING_LEAN_RAD`] forward with the board's idle-time re-planner
/// on (`sim::replanning`): the run the QEMU image replays with its own
/// re-planner in the tick's idle time, preempted by the tick. Its commands
/// equal the host's only if each of its answers reaches the sequencer
/// within the latency, as the host's did. Also returns the host's re-plans.
pub fn record_replanning(
    device: &DeviceConfig,
    steps: usize,
) -> Result<(Recording, Vec<crate::replanning::ReplanRecord>), RigError> {
    let table = gait_core::flash_tables::stair_down()
        .map_err(|_| RigError::Config("the flash stair-descent table is refused"))?;
    let pilot = crate::pilot::PilotConfig {
        habit_lean_rad: REPLANNING_LEAN_RAD,
        ..strong_pilot()
    };
    let slot = gait_control::replan::ReplanSlot::new();
    let max_s = 6.0 + steps as f64 * (f64::from(table.duration_s()) + 2.0);
    let (_, rig) = crate::compare::play(device, table, pilot, steps, max_s, |rig| {
        rig.replan_with(&slot);
        rig.record_ticks();
    })?;
    let replans = rig.replans().to_vec();
    Ok((
        Recording {
            gait: Gait::StairDown,
            ticks: rig.recorded.unwrap_or_default(),
        },
        replans,
    ))
}

/// The recordings as a tick-record file.
pub fn encode(recordings: &[Recording]) -> Vec<u8> {
    let count = u16::try_from(recordings.len()).unwrap_or(u16::MAX);
    let mut out = tick_record::file_header(count).to_vec();
    for r in recordings.iter().take(usize::from(count)) {
        let ticks = u32::try_from(r.ticks.len()).unwrap_or(u32::MAX);
        out.extend_from_slice(&tick_record::segment_header(r.gait, ticks));
        for t in r.ticks.iter().take(ticks as usize) {
            out.extend_from_slice(&t.encode());
        }
    }
    out
}

impl crate::closed_loop::Rig<'_> {
    /// Starts recording every tick's peripheral state and commands into
    /// [`Rig::recorded`] (turn sensor noise off: the record holds one sample
    /// of each reading, the driver may take others).
    pub fn record_ticks(&mut self) {
        self.recorded = Some(Vec::new());
    }

    /// What the peripherals present to the controller this tick.
    pub(crate) fn peripheral_state(&self, deadline_missed: bool) -> TickRecord {
        let now = self.now();
        TickRecord {
            encoder_counts: std::array::from_fn(|i| match i.checked_sub(4) {
                None => self.joint_encoders[i].angle_register(),
                Some(a) => self.ankle_encoders[a].angle_register(),
            }),
            adc_counts: std::array::from_fn(|ch| self.adc.counts(ch)),
            mode_pressed: self.mode.pressed_at(now),
            go_pressed: self.go.pressed_at(now),
            e_stop_pressed: self.e_stop.is_pressed(),
            deadline_missed,
            host_command_nm: [0.0; 4],
        }
    }
}
