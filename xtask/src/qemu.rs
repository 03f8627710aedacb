//! The QEMU image (`mps2-an386`): built, run with data loaded into its
//! memory, and its output checked.

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::{BOARDS, QEMU_TIMEOUT_S, Result, Toolchain, build_firmware, sectors, tick_replay};

/// The QEMU image with the device's calibration: self-test, benchmarks,
/// the replay of recorded ticks (budget and host agreement checked), the
/// configuration's fingerprint against the host's.
pub fn self_test(tc: &Toolchain) -> Result {
    let text = run_qemu(tc, &[sectors::calibration_load()?])?;
    check_device_fingerprint(&text)?;
    tick_replay::check(&text)
}

/// Builds and runs the QEMU image, with each (file, address) of `loads`
/// placed in its memory by QEMU's loader before the reset (the data
/// sectors: `firmware/src/flash_sectors.rs`); its output, printed too.
/// Fails when QEMU times out or the image reports a failure.
pub fn run_qemu(tc: &Toolchain, loads: &[(PathBuf, u32)]) -> Result<String> {
    let board = BOARDS
        .iter()
        .find(|b| b.name == "qemu")
        .copied()
        .ok_or("no qemu board")?;
    let elf = build_firmware(tc, board)?;
    let mut cmd = Command::new("timeout");
    cmd.arg(QEMU_TIMEOUT_S.to_string())
        .arg("qemu-system-arm")
        .args(["-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic"])
        .args(["-monitor", "none", "-serial", "none"])
        .args(["-semihosting-config", "enable=on,target=native"])
        // One instruction per virtual nanosecond: SysTick counts
        // instructions; a WFI skips to the next timer event, not real time.
        .args(["-icount", "shift=0,sleep=off"])
        .arg("-kernel")
        .arg(&elf);
    for (file, addr) in loads {
        cmd.arg("-device")
            .arg(format!("loader,file={},addr=0x{addr:x}", file.display()));
    }
    let t = Instant::now();
    let out = cmd
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("cannot start qemu-system-arm: {e}"))?;
    let took = t.elapsed();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    print!("{text}");
    let status = out.status;
    if status.code() == Some(124) || took > Duration::from_secs(QEMU_TIMEOUT_S) {
        return Err(format!("QEMU timed out after {QEMU_TIMEOUT_S} s"));
    }
    if !status.success() {
        return Err(format!("QEMU self-test failed ({status})"));
    }
    Ok(text)
}

/// The firmware prints the CRC of the device configuration it was built
/// with; the host's (which the simulator runs, `host-tests`'
/// `the_simulator_runs_the_device_configuration`) must be the same number.
fn check_device_fingerprint(qemu_stdout: &str) -> Result {
    let host = exogait_device::DeviceConfig::exogait()
        .map_err(|e| format!("device configuration refused on the host: {e:?}"))?
        .fingerprint();
    let target = qemu_stdout
        .lines()
        .find_map(|l| l.trim().strip_prefix("device: fingerprint=0x"))
        .and_then(|h| u32::from_str_radix(h.trim(), 16).ok())
        .ok_or("the QEMU image printed no device fingerprint")?;
    if target == host {
        println!("device configuration: firmware and host agree (0x{host:08x})");
        Ok(())
    } else {
        Err(format!(
            "the firmware runs another device configuration (0x{target:08x}) than the host \
             and the simulator (0x{host:08x})"
        ))
    }
}
