//! Reading a bundle file for any command: verified for this device (its
//! fingerprint), refused with the reason otherwise.

use std::path::Path;

use exogait_device::DeviceConfig;
use gait_core::bundle::Bundle;

/// A bundle file's bytes, verified once for this device.
pub struct BundleFile {
    /// The image.
    pub bytes: Vec<u8>,
    /// The device as built (its fingerprint is the bundle's).
    pub device: DeviceConfig,
}

impl BundleFile {
    /// Reads and verifies `path`.
    pub fn load(path: &Path) -> Result<Self, String> {
        let device = DeviceConfig::exogait().map_err(|e| format!("device: {e:?}"))?;
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Bundle::parse(&bytes, device.fingerprint())
            .map_err(|e| format!("{}: bundle refused: {e}", path.display()))?;
        Ok(Self { bytes, device })
    }

    /// The bundle at `path`, if one is given, and the device a command
    /// plays on: fitted to the bundle's patient, else the device as built.
    /// `Err` is the message a command prints before exiting with 2.
    pub fn and_device(path: Option<&Path>) -> Result<(Option<Self>, DeviceConfig), String> {
        let Some(path) = path else {
            let device =
                DeviceConfig::exogait().map_err(|e| format!("device configuration: {e:?}"))?;
            return Ok((None, device));
        };
        let file = Self::load(path)?;
        let device = file.fitted_device()?;
        Ok((Some(file), device))
    }

    /// The verified bundle.
    pub fn bundle(&self) -> Result<Bundle<'_>, String> {
        Bundle::parse(&self.bytes, self.device.fingerprint()).map_err(|e| e.to_string())
    }

    /// The device fitted to the bundle's patient.
    pub fn fitted_device(&self) -> Result<DeviceConfig, String> {
        let b = self.bundle()?;
        self.device
            .fitted(&b.patient().model)
            .map_err(|e| format!("patient model: {e}"))
    }

    /// The names of the bundle's gaits, in order.
    pub fn names(&self) -> Vec<String> {
        self.bundle()
            .map(|b| {
                (0..b.len())
                    .filter_map(|i| b.gait(i))
                    .map(|g| g.info.name.as_str().to_string())
                    .collect()
            })
            .unwrap_or_default()
    }
}
