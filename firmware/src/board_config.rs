//! What the board runs with: the device configuration
//! (`exogait_device::DeviceConfig::exogait`, shared with the simulator and
//! the table generator) and the gait tables in flash. Both images build
//! their controller and their [`Hardware`] through [`build_controller`]
//! and [`hardware`], so the QEMU benchmark runs exactly the configuration
//! the motor board runs.
//!
//! No numbers and no control logic here: this module only picks the flash
//! tables and hands the board's peripherals to the device's drivers.

use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::pwm::SetDutyCycle;
use embedded_hal::spi::SpiDevice;
use exogait_device::{DeviceConfig, DeviceError};
use gait_control::controller::{Controller, Hardware};
use gait_control::operator::Gait;
use gait_control::sequencer::GaitTables;

pub use exogait_device::{BoardIo, DT_S, TICK_HZ};

/// The gait tables this image carries (`gait_core::flash_tables`, made by
/// `cargo xtask tables`), each verified (magic, version, kind, length,
/// CRC-32, finite samples) before it can be selected: a table that fails is
/// left out, so its gait cannot start.
#[must_use]
pub fn flash_tables() -> GaitTables<'static> {
    GaitTables {
        walk: gait_core::flash_tables::walk().ok(),
        stair_up: gait_core::flash_tables::stair_up().ok(),
        stair_down: gait_core::flash_tables::stair_down().ok(),
    }
}

/// The device configuration.
pub fn device() -> Result<DeviceConfig, DeviceError> {
    DeviceConfig::exogait()
}

/// The controller both boards run, over the tables in flash, walking
/// selected at power-up.
pub fn build_controller() -> Result<Controller<'static>, DeviceError> {
    exogait_device::build_controller(&device()?, flash_tables(), Gait::Walk)
}

/// What [`hardware`] returns.
pub type HardwareResult<ENC, ADC, PWM, DIR, EN, IN, OUT> =
    Result<Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>, DeviceError>;

/// Hands the board's peripherals to gait-control's drivers with the
/// device's calibrations and limits, every motor output disabled.
pub fn hardware<ENC, ADC, PWM, DIR, EN, IN, OUT, PwmE, PinE>(
    io: BoardIo<ENC, ADC, PWM, DIR, EN, IN, OUT>,
) -> HardwareResult<ENC, ADC, PWM, DIR, EN, IN, OUT>
where
    ENC: SpiDevice<u8>,
    ADC: SpiDevice<u8>,
    PWM: SetDutyCycle<Error = PwmE>,
    DIR: OutputPin<Error = PinE>,
    EN: OutputPin<Error = PinE>,
    IN: InputPin,
    OUT: OutputPin,
{
    exogait_device::hardware(&device()?, io)
}
