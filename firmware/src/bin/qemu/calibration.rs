//! The QEMU image's check of the calibration: the record in its sector,
//! a board without one (motors off), and the recording procedure on the
//! rig set to the jig's posture.

use exogait_device::boot;
use exogait_device::calibration::Record;
use firmware::{board_config, flash_sectors, qemu_bundle};

use crate::{Out, line};

/// Prints the checks; returns the number of failures.
pub(crate) fn check(out: &mut Out) -> usize {
    let Ok(device) = board_config::device() else {
        out.put(&mut line("FAIL calibration: device configuration refused"));
        return 1;
    };
    let mut failed = 0;
    let refusal = match boot::calibration_in(&device, flash_sectors::calibration()) {
        Ok(_) => {
            out.put(&mut line("calibration: ok"));
            None
        }
        Err(e) => {
            out.put(line("calibration: refused reason=").str(e.reason()));
            Some(e)
        }
    };
    // Whatever the sector holds, a board without a calibration keeps its
    // motors off.
    let refusal = refusal.unwrap_or(exogait_device::calibration::Refusal::Missing);
    match qemu_bundle::uncalibrated_board(&device, refusal) {
        Ok(c) if !c.any_enabled && c.refusal_latched => out.put(
            line("calibration: without a record the motors stay off (")
                .u32(c.ticks)
                .str(" ticks, 0x0605 latched)"),
        ),
        _ => {
            out.put(&mut line(
                "FAIL calibration: a board without a record enabled a motor",
            ));
            failed += 1;
        }
    }
    match qemu_bundle::record_on_jig(&device) {
        Ok(r) if r == Record::of_device(&device) => {
            out.put(&mut line(
                "calibration: recorded on the jig: matches the device's",
            ));
        }
        Ok(_) => {
            out.put(&mut line(
                "FAIL calibration: the recording differs from the jig's values",
            ));
            failed += 1;
        }
        Err(e) => {
            out.put(line("FAIL calibration: recording refused reason=").str(e.reason()));
            failed += 1;
        }
    }
    failed
}
