//! What the board runs with, decided once at boot from its data sectors:
//! its calibration (`crate::calibration`; without one the motors stay off,
//! fault 0x0605), and what it plays, from the bundle sector: the
//! device's own tables when the sector is erased (no patient fitted), a
//! patient's verified bundle, or nothing at all when a bundle is there but
//! fails verification (fault 0x0604: the board holds, GO does nothing).
//!
//! The bundle is verified against the device as built
//! ([`DeviceConfig::fingerprint`] of [`DeviceConfig::exogait`]); the
//! controller then runs the device fitted to the bundle's patient
//! ([`DeviceConfig::fitted`]).

use gait_control::controller::Controller;
use gait_control::faults::FaultCode;
use gait_control::operator::{AllowedGaits, Gait, OperatorConfig};
use gait_control::sequencer::{GaitTables, gait_of_kind};
use gait_core::bundle::{Bundle, BundleError, MAX_GAITS};
use gait_core::tables::GaitTable;

use crate::calibration::{Record, Refusal};
use crate::{DeviceConfig, DeviceError};

/// Where the board's gaits come from.
// One value at boot, on the stack of `main`; no heap to box it into.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Gaits<'a> {
    /// The sector is erased: the device's own tables (the paper's body).
    BuiltIn,
    /// A verified patient's bundle.
    Patient(Bundle<'a>),
    /// A bundle is there but refused: nothing is played.
    Refused(BundleError),
}

/// Whether a sector's first word is erased flash (0xFF, or 0x00 where the
/// memory starts cleared, as QEMU's does).
fn erased(sector: &[u8]) -> bool {
    matches!(
        sector.get(..4),
        Some([0xFF, 0xFF, 0xFF, 0xFF] | [0, 0, 0, 0]) | None
    )
}

/// What the bundle `sector` gives `device` (the device as built).
pub fn gaits_in<'a>(device: &DeviceConfig, sector: &'a [u8]) -> Gaits<'a> {
    if erased(sector) {
        return Gaits::BuiltIn;
    }
    match Bundle::parse_sector(sector, device.fingerprint()) {
        Ok(b) => Gaits::Patient(b),
        Err(e) => Gaits::Refused(e),
    }
}

/// Where the board keeps a patient's verified tables while it runs (the
/// controller borrows them: [`GaitTables::in_order`]).
pub type TableSlots<'a> = [Option<GaitTable<'a>>; MAX_GAITS];

/// A patient's tables in the bundle's order, put in `slots`, and the
/// clinician's list over them (MODE cycles in that order; gait *i*
/// flashes *i* + 1 times).
pub fn patient_gaits<'a>(
    bundle: &Bundle<'a>,
    slots: &'a mut TableSlots<'a>,
    reset_hold_ticks: u32,
) -> Result<(GaitTables<'a>, OperatorConfig), DeviceError> {
    let mut kinds = [Gait::Walk; MAX_GAITS];
    let mut n = 0;
    // Bounded: a verified bundle holds at most MAX_GAITS gaits.
    for (i, (k, slot)) in kinds.iter_mut().zip(slots.iter_mut()).enumerate() {
        *slot = bundle.gait(i).map(|g| g.table);
        if let Some(t) = slot {
            *k = gait_of_kind(t.kind());
            n += 1;
        }
    }
    let allowed =
        AllowedGaits::in_order(kinds.get(..n).unwrap_or(&[])).map_err(DeviceError::Operator)?;
    Ok((
        GaitTables::in_order(slots),
        OperatorConfig {
            allowed,
            reset_hold_ticks,
        },
    ))
}

/// The calibration record in its sector, verified for `device`.
pub fn calibration_in(device: &DeviceConfig, sector: &[u8]) -> Result<Record, Refusal> {
    Record::parse(sector, device)
}

/// The device and controller the board runs with `gaits` over the
/// device's own `built_in` tables: fitted to the patient and over their
/// bundle; as built over the built-in tables; as built over no table with
/// fault 0x0604 latched when the bundle was refused. The device is first
/// given its `calibration`; without one (refused), fault 0x0605 is
/// latched and the motors stay off. `slots` holds a patient's tables while
/// the controller runs.
pub fn build<'a>(
    device: &DeviceConfig,
    gaits: &Gaits<'a>,
    calibration: &Result<Record, Refusal>,
    built_in: GaitTables<'a>,
    slots: &'a mut TableSlots<'a>,
) -> Result<(DeviceConfig, Controller<'a>), DeviceError> {
    let device = match calibration {
        Ok(r) => device.calibrated(r)?,
        Err(_) => *device,
    };
    let (cfg, mut controller) = with_gaits(&device, gaits, built_in, slots)?;
    if calibration.is_err() {
        controller.report_boot_fault(FaultCode::CalibrationRefused);
    }
    Ok((cfg, controller))
}

fn with_gaits<'a>(
    device: &DeviceConfig,
    gaits: &Gaits<'a>,
    built_in: GaitTables<'a>,
    slots: &'a mut TableSlots<'a>,
) -> Result<(DeviceConfig, Controller<'a>), DeviceError> {
    match gaits {
        Gaits::BuiltIn => Ok((
            *device,
            crate::build_controller(device, built_in, Gait::Walk)?,
        )),
        Gaits::Patient(b) => {
            let fitted = device
                .fitted(&b.patient().model)
                .map_err(DeviceError::Patient)?;
            let (tables, operator) = patient_gaits(b, slots, device.reset_hold_ticks)?;
            let controller =
                Controller::new(fitted.controller, tables, operator, fitted.supervisor()?)
                    .map_err(DeviceError::Controller)?;
            Ok((fitted, controller))
        }
        Gaits::Refused(_) => {
            let mut c = crate::build_controller(device, GaitTables::default(), Gait::Walk)?;
            c.report_boot_fault(FaultCode::BundleRefused);
            Ok((*device, c))
        }
    }
}
