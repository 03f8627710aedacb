//! Replays ticks recorded in the simulator (`sim::replay`,
//! `exogait_device::tick_record`) through the board's controller over the
//! QEMU rig, timing each tick by the phase the controller reports and
//! comparing its motor commands with the host's for the same inputs.
//!
//! The recording is built in at compile time: `build.rs` copies the file
//! named by `EXOGAIT_TICK_RECORDS` (written by `cargo xtask qemu`) and an
//! empty one otherwise, which replays nothing.

use exogait_device::DeviceConfig;
use exogait_device::tick_record::{self, FileError};
use gait_control::acquisition::Frames;
use gait_control::controller::{Controller, TickReport};
use gait_control::feedforward::{ModelSlot, ModelTask};
use gait_control::operator::Gait;
use gait_control::sequencer::Phase;

use crate::{board_config, qemu_rig};

/// The recording this image carries.
pub static TICK_RECORDS: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/tick_records.bin"));

/// The run this image replays with its idle-time re-planner on
/// (`sim::replay::record_replanning`; empty: none).
pub static REPLANNING_RECORDS: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/replanning_records.bin"));

/// The phases ticks are grouped by, as printed.
pub const PHASES: [&str; 5] = [
    "standing",
    "waiting-ready",
    "swing",
    "transfer",
    "safe-hold",
];

/// `phase`'s index in [`PHASES`].
#[must_use]
pub const fn phase_index(phase: &Phase) -> usize {
    match phase {
        Phase::Standing => 0,
        Phase::WaitingReady { .. } => 1,
        Phase::Swing { .. } => 2,
        Phase::Transfer { .. } => 3,
        Phase::SafeHold { .. } => 4,
    }
}

/// Instructions of the ticks of one phase.
#[derive(Clone, Copy, Debug, Default)]
pub struct PhaseCost {
    /// Ticks in the phase.
    pub ticks: u32,
    /// Their instructions in all.
    pub total: u64,
    /// The costliest one.
    pub worst: u32,
    /// Where it is: run and tick within it (0-based).
    pub worst_at: (u32, u32),
}

impl PhaseCost {
    /// Counts one more: `instr` at tick `k` of the `segments`-th run.
    pub fn add(&mut self, segments: u32, k: u32, instr: u32) {
        self.ticks += 1;
        self.total += u64::from(instr);
        if instr > self.worst {
            self.worst = instr;
            self.worst_at = (segments.saturating_sub(1), k);
        }
    }

    /// Average instructions per tick.
    #[must_use]
    pub fn average(&self) -> u64 {
        self.total / u64::from(self.ticks.max(1))
    }
}

/// What a replay found.
#[derive(Clone, Copy, Debug, Default)]
pub struct Replay {
    /// Runs replayed.
    pub segments: u32,
    /// Ticks replayed.
    pub ticks: u32,
    /// Per phase, in [`PHASES`] order.
    pub phases: [PhaseCost; 5],
    /// The model task's answers between the ticks
    /// ([`gait_control::feedforward`]), all phases together.
    pub model: PhaseCost,
    /// The acquisitions before the ticks, through the rig's parts
    /// ([`qemu_rig::acquire`]): the work the board's DMA does instead.
    pub acquisition: PhaseCost,
    /// The largest |target − host| motor command, N·m.
    pub max_command_diff_nm: f32,
    /// Ticks whose commands differ from the host's at all.
    pub differing_ticks: u32,
    /// The first of them: run and tick within it (0-based), the target's
    /// and the host's commands there (N·m).
    pub first_differing: Option<(u32, u32, [f32; 4], [f32; 4])>,
}

/// Why a replay could not run.
#[derive(Clone, Copy, Debug)]
pub enum ReplayError {
    /// The recording is malformed.
    File(FileError),
    /// The controller or its drivers were refused for a run's gait.
    Config,
}

/// Marks, in QEMU's execution log, where the replay begins: `cargo xtask
/// profile` counts the instructions executed from here on.
#[inline(never)]
fn replay_starts() {
    core::hint::black_box(());
}

/// Mark, in QEMU's execution log, each replayed tick and the phase it
/// ended in: `cargo xtask profile` attributes what runs between a start
/// and an end to that phase, and keeps each phase's costliest tick. Each
/// hands `black_box` its own constant: identical bodies would be merged
/// into one function, one symbol for all.
mod marks {
    macro_rules! marks {
        ($($name:ident = $n:literal),*) => {$(
            #[inline(never)]
            pub fn $name() {
                core::hint::black_box($n);
            }
        )*};
    }
    marks!(
        tick_starts = 1u8,
        tick_ended_standing = 2u8,
        tick_ended_waiting_ready = 3u8,
        tick_ended_swing = 4u8,
        tick_ended_transfer = 5u8,
        tick_ended_safe_hold = 6u8
    );
}

/// Replays [`TICK_RECORDS`] on `device`; `time` runs one tick and says how
/// many instructions it took, `time_model` the same of the model task's
/// answer after it and of the acquisition before it.
pub fn replay(
    device: &DeviceConfig,
    mut time: impl FnMut(&mut dyn FnMut() -> TickReport) -> (u32, TickReport),
    time_model: impl FnMut(&mut dyn FnMut()) -> u32,
) -> Result<Replay, ReplayError> {
    replay_starts();
    replay_with(
        TICK_RECORDS,
        device,
        |gait| {
            exogait_device::build_controller(device, board_config::flash_tables(), gait)
                .map_err(|_| ReplayError::Config)
        },
        |tick| {
            marks::tick_starts();
            let (instr, report) = time(tick);
            match report.phase {
                Phase::Standing => marks::tick_ended_standing(),
                Phase::WaitingReady { .. } => marks::tick_ended_waiting_ready(),
                Phase::Swing { .. } => marks::tick_ended_swing(),
                Phase::Transfer { .. } => marks::tick_ended_transfer(),
                Phase::SafeHold { .. } => marks::tick_ended_safe_hold(),
            }
            (instr, report)
        },
        time_model,
    )
}

/// Replays the recording `file` on `device`, each run through the
/// controller `controller` builds for its gait, with the model task the
/// board runs answering between two ticks, as its lower-priority
/// interrupt does, and each tick's sensors acquired before it, as the
/// board's DMA does.
pub fn replay_with<'t>(
    file: &[u8],
    device: &DeviceConfig,
    mut controller: impl FnMut(Gait) -> Result<Controller<'t>, ReplayError>,
    mut time: impl FnMut(&mut dyn FnMut() -> TickReport) -> (u32, TickReport),
    mut time_model: impl FnMut(&mut dyn FnMut()) -> u32,
) -> Result<Replay, ReplayError> {
    let mut out = Replay::default();
    for segment in tick_record::segments(file).map_err(ReplayError::File)? {
        let slot = ModelSlot::new();
        let mut controller: Controller<'_> = controller(segment.gait)?;
        let checks = controller.set_model_task(&slot);
        let mut task = ModelTask::new(controller.config().model, &slot)
            .with_checks(checks)
            .with_steps(controller.steps());
        let mut hw = board_config::hardware(device, qemu_rig::peripherals())
            .map_err(|_| ReplayError::Config)?;
        out.segments += 1;
        for (k, record) in (0u32..).zip(segment.ticks()) {
            qemu_rig::replay(device, &record);
            let mut frames = Frames::MISSING;
            let acquisition = time_model(&mut || {
                frames = qemu_rig::acquire(&mut hw, &controller);
            });
            out.acquisition.add(out.segments, k, acquisition);
            let (instr, report) =
                time(&mut || controller.tick_acquired(&mut hw, &frames, record.deadline_missed));
            out.account(k, instr, &report, &record.host_command_nm);
            let model = time_model(&mut || {
                task.serve();
            });
            out.model.add(out.segments, k, model);
        }
    }
    Ok(out)
}

impl Replay {
    /// Counts tick `k` of the current run: its cost `instr` under its
    /// phase, and its commands against the host's.
    pub fn account(&mut self, k: u32, instr: u32, report: &TickReport, host_nm: &[f32; 4]) {
        let run = self.segments.saturating_sub(1);
        self.ticks += 1;
        if let Some(p) = self.phases.get_mut(phase_index(&report.phase)) {
            p.add(self.segments, k, instr);
        }
        let diff = report
            .command_nm
            .iter()
            .zip(host_nm)
            .map(|(t, h)| {
                if t.to_bits() == h.to_bits() {
                    0.0
                } else {
                    (t - h).abs()
                }
            })
            .fold(0.0f32, |m, d| if d.is_nan() || d > m { d } else { m });
        if diff != 0.0 {
            self.differing_ticks += 1;
            if self.first_differing.is_none() {
                self.first_differing = Some((run, k, report.command_nm, *host_nm));
            }
        }
        if diff.is_nan() || diff > self.max_command_diff_nm {
            self.max_command_diff_nm = diff;
        }
    }
}
