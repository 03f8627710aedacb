//! What the two recording examples (`record_ticks`, `record_bundle_step`)
//! share: the device, the recording file, and how a failure ends them
//! (`cargo xtask qemu` reads the exit code).

use std::process::ExitCode;

use exogait_device::DeviceConfig;
use sim::replay::Recording;

/// Why an example stops early: its message and exit code (2: the input
/// was refused, 1: something else failed).
pub struct Stop {
    pub code: ExitCode,
    pub message: String,
}

impl Stop {
    /// The input (arguments, bundle) was refused: exit 2.
    pub fn refused(message: String) -> Self {
        Self {
            code: ExitCode::from(2),
            message,
        }
    }

    /// Something else failed: exit 1.
    pub fn failed(message: String) -> Self {
        Self {
            code: ExitCode::FAILURE,
            message,
        }
    }
}

/// The exogait device.
pub fn device() -> Result<DeviceConfig, Stop> {
    DeviceConfig::exogait()
        .map_err(|e| Stop::failed(format!("device configuration refused: {e:?}")))
}

/// Writes `recordings` to `path` in the replay format; the file's size,
/// bytes.
pub fn write(path: &str, recordings: &[Recording]) -> Result<usize, Stop> {
    let bytes = sim::replay::encode(recordings);
    std::fs::write(path, &bytes).map_err(|e| Stop::failed(format!("cannot write {path}: {e}")))?;
    Ok(bytes.len())
}

/// Prints what `run` gave (its report, or its failure on stderr) and
/// returns the exit code.
pub fn finish(run: Result<String, Stop>) -> ExitCode {
    match run {
        Ok(report) => {
            println!("{report}");
            ExitCode::SUCCESS
        }
        Err(stop) => {
            eprintln!("{}", stop.message);
            stop.code
        }
    }
}
