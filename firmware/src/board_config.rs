//! What the board runs with: the device configuration
//! (`exogait_device::DeviceConfig::exogait`, shared with the simulator and
//! the table generator) and the gait tables in flash. Both images build
//! their controller through [`build_controller`] and their drivers through
//! [`hardware`] over [`device`], so the QEMU benchmark runs exactly the
//! configuration the motor board runs.
//!
//! No numbers and no control logic here: this module only picks the flash
//! tables and hands the board's peripherals to the device's drivers.

use exogait_device::{DeviceConfig, DeviceError};
use gait_control::controller::Controller;
use gait_control::operator::Gait;
use gait_control::sequencer::GaitTables;

pub use exogait_device::{BoardIo, DT_S, TICK_HZ, hardware};

/// The gait tables this image carries (`gait_core::flash_tables`, made by
/// `cargo xtask tables`), each verified (magic, version, kind, length,
/// CRC-32, finite samples) before it can be selected: a table that fails is
/// left out, so its gait cannot start.
#[must_use]
pub fn flash_tables() -> GaitTables<'static> {
    GaitTables::by_kind(
        gait_core::flash_tables::walk().ok(),
        gait_core::flash_tables::stair_up().ok(),
        gait_core::flash_tables::stair_down().ok(),
    )
}

/// Whether the motor board re-plans each step in the tick's idle time
/// (`firmware::idle_replan`). Off: in the closed loop the re-planned steps
/// do not yet beat the tables for every pilot, and the board's idle time
/// at 1.0–1.5 cycles per instruction (not yet measured) may be below the
/// device model's
/// (`docs/replanning.md`). The QEMU image runs the same schedule with it
/// on.
pub const REPLANNING: bool = false;

/// The device configuration.
pub fn device() -> Result<DeviceConfig, DeviceError> {
    DeviceConfig::exogait()
}

/// The controller both boards run, over the tables in flash, walking
/// selected at power-up.
pub fn build_controller() -> Result<Controller<'static>, DeviceError> {
    exogait_device::build_controller(&device()?, flash_tables(), Gait::Walk)
}
