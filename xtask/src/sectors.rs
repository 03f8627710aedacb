//! The board's data sectors, apart from its image: the calibration record
//! QEMU boots with (the simulated device's own), a patient's bundle booted
//! under QEMU (`cargo xtask qemu --bundle FILE`) or written to the motor
//! board's sector (`cargo xtask flash-bundle FILE`), and CI's checks of a
//! good and a corrupted bundle and of a board without a calibration.
//!
//! The addresses are the firmware's (`firmware/src/flash_sectors.rs`,
//! `memory.x`, `firmware/qemu/memory.x`).

use std::path::{Path, PathBuf};
use std::process::Command;

use gait_core::bundle::{Bundle, MAX_BUNDLE_LEN};

use crate::qemu::run_qemu;
use crate::{Result, Toolchain, cargo, root, run};

/// Where the QEMU image reads the bundle sector.
const QEMU_BUNDLE_ADDR: u32 = 0x0030_0000;
/// Where the QEMU image reads its calibration record.
const QEMU_CALIBRATION_ADDR: u32 = 0x0032_0000;
/// Where the QEMU image reads the recording of the bundle's first step.
const QEMU_RECORDING_ADDR: u32 = 0x0034_0000;
/// The motor board's bundle sector (sector 11).
const BOARD_BUNDLE_ADDR: u32 = 0x080E_0000;
/// The motor board's chip, as probe-rs names it.
const CHIP: &str = "STM32F405RGTx";

/// Boots the QEMU image with `file` in its bundle sector. When the host
/// verifies the bundle, one step of its first gait is recorded in the
/// simulator (the device fitted to its patient) and loaded too: the image
/// must print `bundle: ok …` and replay that step with the host's motor
/// commands. When the host refuses it, the image must print
/// `bundle: refused reason=…` and hold with GO ignored.
pub fn qemu_with_bundle(tc: &Toolchain, file: &Path) -> Result<String> {
    let recording = root().join("target/replay/bundle-step.bin");
    let status = cargo()
        .args([
            "run",
            "-q",
            "-p",
            "sim",
            "--example",
            "record_bundle_step",
            "--",
        ])
        .arg(file)
        .arg(&recording)
        .status()
        .map_err(|e| format!("cannot record the bundle's step: {e}"))?;
    let verified = match status.code() {
        Some(0) => true,
        Some(2) => false,
        _ => return Err(format!("recording the bundle's step failed ({status})")),
    };
    let mut loads: Vec<(PathBuf, u32)> =
        vec![(file.to_path_buf(), QEMU_BUNDLE_ADDR), calibration_load()?];
    if verified {
        loads.push((recording, QEMU_RECORDING_ADDR));
    }
    let text = run_qemu(tc, &loads)?;
    let has = |prefix: &str| text.lines().any(|l| l.trim().starts_with(prefix));
    if verified {
        if !has("bundle: ok gaits=") {
            return Err("the host verifies the bundle, the board did not".into());
        }
        let played = text
            .lines()
            .find(|l| l.trim().starts_with("bundle: played"))
            .ok_or("the board did not play the bundle's first step")?;
        if !played.contains("differing_ticks=0 ") {
            return Err(format!(
                "the board's motor commands differ from the host's: {played}"
            ));
        }
    } else {
        if !has("bundle: refused reason=") {
            return Err("the host refuses the bundle, the board did not".into());
        }
        if !has("bundle: board holds, GO ignored") {
            return Err("a refused bundle did not leave the board holding".into());
        }
    }
    Ok(text)
}

/// Writes `file` to the motor board's bundle sector with probe-rs, after
/// verifying it for this device (a bundle the board would refuse is not
/// written).
pub fn flash_bundle(file: &Path) -> Result {
    let bytes = std::fs::read(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let device = exogait_device::DeviceConfig::exogait()
        .map_err(|e| format!("device configuration refused: {e:?}"))?;
    let bundle = Bundle::parse(&bytes, device.fingerprint())
        .map_err(|e| format!("{}: bundle refused: {e}", file.display()))?;
    if bytes.len() > MAX_BUNDLE_LEN {
        return Err(format!("{}: larger than the sector", file.display()));
    }
    println!(
        "writing {} ({} gaits, {} bytes, CRC 0x{:08x}) to the bundle sector at 0x{BOARD_BUNDLE_ADDR:08x}",
        file.display(),
        bundle.len(),
        bytes.len(),
        bundle.crc()
    );
    run(Command::new("probe-rs")
        .args(["download", "--chip", CHIP, "--binary-format", "bin"])
        .args(["--base-address", &format!("0x{BOARD_BUNDLE_ADDR:08x}")])
        .arg(file))
}

/// CI: a small family for a 1.60 m, 55 kg patient made with `exogait`,
/// booted as it is (its first step played), then with one byte of a
/// table flipped (refused: the board holds).
pub fn ci_bundle_boot(tc: &Toolchain) -> Result {
    let dir = root().join("target/qemu-bundle");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let patient = dir.join("patient.json");
    let good = dir.join("patient.bundle");
    let exogait = |args: &[&str]| {
        let mut c = cargo();
        c.args(["run", "-q", "-p", "exogait-cli", "--"]).args(args);
        c
    };
    let path = |p: &Path| p.display().to_string();
    run(exogait(&[
        "fit",
        "--height",
        "1.60",
        "--mass",
        "55",
        "--out",
        &path(&patient),
    ])
    .stdout(std::process::Stdio::null()))?;
    run(&mut exogait(&[
        "tables",
        "--patient",
        &path(&patient),
        "--paces",
        "0.25",
        "--stairs",
        "0.15:0.28",
        "--out",
        &path(&good),
    ]))?;
    qemu_with_bundle(tc, &good)?;
    let mut bytes = std::fs::read(&good).map_err(|e| format!("{}: {e}", good.display()))?;
    let middle = bytes.len() / 2;
    if let Some(b) = bytes.get_mut(middle) {
        *b ^= 0x40;
    }
    let bad = dir.join("corrupted.bundle");
    std::fs::write(&bad, &bytes).map_err(|e| format!("{}: {e}", bad.display()))?;
    let text = qemu_with_bundle(tc, &bad)?;
    if !text.contains("bundle: refused reason=crc") {
        return Err("the corrupted bundle was not refused for its CRC".into());
    }
    Ok(())
}

/// The simulated device's calibration record (`Record::of_device`) as a
/// file, and where QEMU loads it: what a calibrated board holds.
pub fn calibration_load() -> Result<(PathBuf, u32)> {
    let device = exogait_device::DeviceConfig::exogait()
        .map_err(|e| format!("device configuration refused: {e:?}"))?;
    let dir = root().join("target/qemu-data");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let file = dir.join("calibration.bin");
    let record = exogait_device::calibration::Record::of_device(&device).encode();
    std::fs::write(&file, record).map_err(|e| format!("{}: {e}", file.display()))?;
    Ok((file, QEMU_CALIBRATION_ADDR))
}

/// CI: the QEMU image without a calibration record must say so and keep
/// its motors off (its self-test still runs).
pub fn ci_uncalibrated_boot(tc: &Toolchain) -> Result {
    let text = run_qemu(tc, &[])?;
    let has = |s: &str| text.lines().any(|l| l.trim().starts_with(s));
    if !has("calibration: refused reason=missing") {
        return Err("the board booted without a calibration and did not refuse it".into());
    }
    if !has("calibration: without a record the motors stay off") {
        return Err("a board without a calibration enabled a motor".into());
    }
    Ok(())
}
