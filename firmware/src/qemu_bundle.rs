//! What the QEMU image proves of a patient's bundle at boot
//! (`exogait_device::boot`): a refused bundle leaves the board holding with
//! fault 0x0604 latched, GO ignored; a verified one plays its first gait's
//! step through the controller the board builds for it, with the motor
//! commands of the host's run of the same step
//! (`cargo xtask qemu --bundle`).

use exogait_device::DeviceConfig;
use exogait_device::boot::{self, Gaits, TableSlots};
use exogait_device::calibration::{Record, Refusal};
use gait_control::controller::{Controller, TickReport};
use gait_control::faults::{FaultCode, Reaction};
use gait_control::sequencer::Phase;
use gait_core::bundle::MAX_GAITS;

use crate::tick_replay::{self, Replay, ReplayError};
use crate::{board_config, flash_sectors, qemu_rig};

/// Ticks the refused board is run for (2 s), GO pressed from tick
/// [`GO_FROM`] for [`GO_TICKS`].
const HOLD_TICKS: u32 = 2_000;
const GO_FROM: u32 = 500;
const GO_TICKS: u32 = 300;

/// How a board with a refused bundle behaved on the standing rig.
#[derive(Clone, Copy, Debug)]
pub struct HoldCheck {
    /// Ticks run.
    pub ticks: u32,
    /// A step started (waiting for the pilot, or a swing): it must not.
    pub stepped: bool,
    /// 0x0604 was latched at every tick.
    pub refusal_latched: bool,
    /// The reaction at the last tick.
    pub reaction: Reaction,
    /// The last tick's phase.
    pub phase: Phase,
    /// The motors held the posture (enabled) at the last tick.
    pub motors_enabled: bool,
}

/// Why a check could not run.
#[derive(Clone, Copy, Debug)]
pub enum CheckError {
    /// The controller or its drivers were refused.
    Config,
    /// The step recording could not be replayed.
    Replay(ReplayError),
}

/// Boots the board's controller for `gaits` (a refused bundle) on the
/// standing rig, presses GO and runs it.
pub fn refused_board(device: &DeviceConfig, gaits: &Gaits<'_>) -> Result<HoldCheck, CheckError> {
    let mut slots = [None; MAX_GAITS];
    let (cfg, mut controller) = build(device, gaits, &flashed_calibration(device), &mut slots)?;
    let mut check = HoldCheck {
        ticks: 0,
        stepped: false,
        refusal_latched: true,
        reaction: Reaction::None,
        phase: Phase::Standing,
        motors_enabled: false,
    };
    press_go_standing(&cfg, &mut controller, |r, _| {
        check.ticks += 1;
        check.stepped |= matches!(r.phase, Phase::WaitingReady { .. } | Phase::Swing { .. });
        check.refusal_latched &= r.faults.contains(FaultCode::BundleRefused);
        check.reaction = r.reaction;
        check.phase = r.phase;
        check.motors_enabled = r.motors_enabled;
    })?;
    Ok(check)
}

/// Replays the recording loaded beside the image (the host's run of the
/// bundle's first gait, fitted device) through the controller the board
/// builds for the verified bundle `gaits`; `Ok(None)` when no recording
/// was loaded.
pub fn play_step(
    device: &DeviceConfig,
    gaits: &Gaits<'_>,
    time: impl FnMut(&mut dyn FnMut() -> TickReport) -> (u32, TickReport),
) -> Result<Option<Replay>, CheckError> {
    let recording = flash_sectors::step_recording();
    if exogait_device::tick_record::segments(recording).is_err() {
        return Ok(None);
    }
    let mut slots = [None; MAX_GAITS];
    let (cfg, controller) = build(device, gaits, &flashed_calibration(device), &mut slots)?;
    // The recording holds one run: the controller the board built.
    let mut once = Some(controller);
    tick_replay::replay_with(
        recording,
        &cfg,
        |_| once.take().ok_or(ReplayError::Config),
        time,
        |model| {
            model();
            0
        },
    )
    .map(Some)
    .map_err(CheckError::Replay)
}

/// How a board without a usable calibration behaved on the standing rig.
#[derive(Clone, Copy, Debug)]
pub struct OffCheck {
    /// Ticks run.
    pub ticks: u32,
    /// A motor was enabled at some tick: it must not be.
    pub any_enabled: bool,
    /// 0x0605 was latched at every tick.
    pub refusal_latched: bool,
}

/// Boots the board's controller without a calibration (`refusal`) on the
/// standing rig, presses GO, and runs it for 2 s.
pub fn uncalibrated_board(device: &DeviceConfig, refusal: Refusal) -> Result<OffCheck, CheckError> {
    let mut slots = [None; MAX_GAITS];
    let (cfg, mut controller) = build(device, &Gaits::BuiltIn, &Err(refusal), &mut slots)?;
    let mut check = OffCheck {
        ticks: 0,
        any_enabled: false,
        refusal_latched: true,
    };
    press_go_standing(&cfg, &mut controller, |r, enabled| {
        check.ticks += 1;
        check.any_enabled |= r.motors_enabled || enabled;
        check.refusal_latched &= r.faults.contains(FaultCode::CalibrationRefused);
    })?;
    Ok(check)
}

/// The calibration procedure on the rig set to the jig's posture: what
/// it records, and the record read back from its bytes.
pub fn record_on_jig(
    device: &DeviceConfig,
) -> Result<exogait_device::calibration::Record, exogait_device::calibration::Refusal> {
    use exogait_device::calibration::{Record, Refusal, measure};
    qemu_rig::on_jig(device);
    let mut hw = board_config::hardware(device, qemu_rig::peripherals())
        .map_err(|_| Refusal::ReadFailed(0))?;
    let (enc, force) = measure(&mut hw)?;
    let rec = Record::from_readings(device, &enc, &force)?;
    Record::parse(&rec.encode(), device)
}

/// The device and controller the board builds (`boot::build`) for `gaits`
/// with `calibration`, over its flash tables.
fn build<'a>(
    device: &DeviceConfig,
    gaits: &Gaits<'a>,
    calibration: &Result<Record, Refusal>,
    slots: &'a mut TableSlots<'a>,
) -> Result<(DeviceConfig, Controller<'a>), CheckError> {
    boot::build(
        device,
        gaits,
        calibration,
        board_config::flash_tables(),
        slots,
    )
    .map_err(|_| CheckError::Config)
}

/// The calibration record in the board's calibration sector, for `device`.
fn flashed_calibration(device: &DeviceConfig) -> Result<Record, Refusal> {
    boot::calibration_in(device, flash_sectors::calibration())
}

/// Runs `controller` on the standing rig for [`HOLD_TICKS`], GO pressed
/// from [`GO_FROM`] for [`GO_TICKS`]; `each` sees every tick's report and
/// whether any motor driver was enabled after it.
fn press_go_standing(
    cfg: &DeviceConfig,
    controller: &mut Controller<'_>,
    mut each: impl FnMut(&TickReport, bool),
) -> Result<(), CheckError> {
    let mut hw =
        board_config::hardware(cfg, qemu_rig::standing(cfg)).map_err(|_| CheckError::Config)?;
    let pressed_high = matches!(
        cfg.buttons.active,
        gait_control::drivers::buttons::ActiveLevel::High
    );
    for i in 0..HOLD_TICKS {
        let go = (GO_FROM..GO_FROM + GO_TICKS).contains(&i);
        qemu_rig::PANEL.set_level(qemu_rig::Line::Go, go == pressed_high);
        let frames = qemu_rig::acquire(&mut hw, controller);
        let r = controller.tick_acquired(&mut hw, &frames, false);
        each(&r, hw.motors.iter().any(|m| m.is_enabled()));
    }
    Ok(())
}
