//! The calibration procedure (`exogait_device::calibration`,
//! `docs/operation.md`, "Calibrating the device"): with the device on its
//! jig in the reference posture and MODE and GO held at power-up, the board
//! records every encoder's zero and every load cell's unloaded counts,
//! checks them, writes them to the calibration sector (sector 10) and
//! reads them back; then it waits for a restart.

use exogait_device::DeviceConfig;
use exogait_device::calibration::{Record, Refusal, measure};
use gait_control::controller::Hardware;
use stm32f4xx_hal::pac;
use stm32f4xx_hal::pac::flash::cr::PSIZE;

use firmware::flash_sectors;

/// The calibration sector's number (`memory.x`; its address is
/// `flash_sectors::CALIBRATION_ADDRESS`).
const SECTOR: u8 = 10;
/// FLASH_KEYR's unlock sequence (RM0090, 3.5.1).
const KEYS: [u32; 2] = [0x4567_0123, 0xCDEF_89AB];
/// Polls of the busy flag before an operation counts as failed: erasing a
/// 128 KiB sector takes a few seconds at most (the datasheet's sector
/// erase time), one poll at least 10 cycles at 168 MHz.
const BUSY_POLLS: u32 = 50_000_000;

/// Why a recording was not kept.
pub(crate) enum Failure {
    /// The readings were refused.
    Refused(Refusal),
    /// Erasing or programming the sector failed.
    Flash,
    /// The record read back differs from the one written.
    ReadBack,
}

/// Records the calibration through `hw` and writes it to its sector.
pub(crate) fn record<ENC, ADC, PWM, DIR, EN, IN, OUT>(
    device: &DeviceConfig,
    hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
    flash: &mut pac::FLASH,
) -> Result<Record, Failure>
where
    ENC: embedded_hal::spi::SpiDevice<u8>,
    ADC: embedded_hal::spi::SpiDevice<u8>,
{
    let (encoders, forces) = measure(hw).map_err(Failure::Refused)?;
    let record = Record::from_readings(device, &encoders, &forces).map_err(Failure::Refused)?;
    write(flash, &record.encode()).map_err(|()| Failure::Flash)?;
    match Record::parse(flash_sectors::calibration(), device) {
        Ok(back) if back == record => Ok(record),
        _ => Err(Failure::ReadBack),
    }
}

// The sector is erased and programmed through the PAC, not the HAL's
// `UnlockedFlash`: the HAL asserts that the unlock took (a panic path the
// image must not hold, `cargo xtask panics`); here it is an error.

/// Erases the calibration sector and programs `bytes` at its start, one
/// byte at a time (x8 parallelism: any supply voltage); locks the flash
/// again whatever happens.
fn write(flash: &mut pac::FLASH, bytes: &[u8]) -> Result<(), ()> {
    for key in KEYS {
        // SAFETY: FLASH_KEYR takes any 32-bit value; only the documented
        // key sequence unlocks, anything else locks until reset.
        flash.keyr().write(|w| unsafe { w.key().bits(key) });
    }
    if flash.cr().read().lock().bit() {
        return Err(());
    }
    let result = erase_and_program(flash, bytes);
    flash
        .cr()
        .modify(|_, w| w.pg().clear_bit().ser().clear_bit().lock().set_bit());
    result
}

fn erase_and_program(flash: &mut pac::FLASH, bytes: &[u8]) -> Result<(), ()> {
    flash.cr().modify(|_, w| {
        w.psize().variant(PSIZE::Psize8);
        // SAFETY: SNB takes sector numbers 0-11 on this part; 10 is ours.
        unsafe { w.snb().bits(SECTOR) };
        w.ser().set_bit();
        w.pg().clear_bit()
    });
    flash.cr().modify(|_, w| w.strt().set_bit());
    done(flash)?;
    flash.cr().modify(|_, w| w.ser().clear_bit().pg().set_bit());
    let base = flash_sectors::CALIBRATION_ADDRESS as *mut u8;
    for (i, &b) in bytes.iter().enumerate() {
        // SAFETY: `base + i` lies in the calibration sector (a record is 32
        // bytes of its 128 KiB), which the image never occupies (`memory.x`);
        // with PG set, a byte write there programs flash.
        unsafe { core::ptr::write_volatile(base.wrapping_add(i), b) };
        done(flash)?;
    }
    Ok(())
}

/// Waits, bounded, for the operation under way; `Err` on a time-out or an
/// error flag.
fn done(flash: &pac::FLASH) -> Result<(), ()> {
    let mut polls = 0u32;
    while flash.sr().read().bsy().bit() {
        polls += 1;
        if polls > BUSY_POLLS {
            return Err(());
        }
    }
    let sr = flash.sr().read();
    let failed = sr.pgserr().bit()
        || sr.pgperr().bit()
        || sr.pgaerr().bit()
        || sr.wrperr().bit()
        || sr.operr().bit();
    if failed { Err(()) } else { Ok(()) }
}
