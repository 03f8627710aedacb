//! The force sensors' characteristic and the calibration the controller
//! reads them with. The simulator's ADC inputs follow the same
//! characteristic, so the calibration is exact there as on a freshly
//! calibrated device.

use gait_control::controller::FORCE_CAL_POINTS;
use gait_control::drivers::mcp3208::{CalibrationError, ForceCalibration};

/// Readings below this are an open sensor or cable (both sensor kinds).
pub const OPEN_BELOW_COUNTS: u16 = 100;
/// Readings above this are a shorted sensor or cable.
pub const SHORT_ABOVE_COUNTS: u16 = 4_000;

/// A load cell and its amplifier, as the ADC sees them: linear from
/// `zero_counts` at 0 N.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadCellSpec {
    /// What it is.
    pub name: &'static str,
    /// ADC counts at 0 N.
    pub zero_counts: f32,
    /// ADC counts per newton.
    pub counts_per_n: f32,
    /// Rated range, N.
    pub rated_min_n: f32,
    /// Rated range, N.
    pub rated_max_n: f32,
    /// Forces at which the clinic records the calibration table, N.
    pub calibration_points_n: [f32; FORCE_CAL_POINTS],
}

impl LoadCellSpec {
    /// ADC counts for a force (unrounded, unclamped).
    pub fn counts(&self, newtons: f32) -> f32 {
        self.zero_counts + self.counts_per_n * newtons
    }

    /// The calibration table the controller reads this sensor with: its
    /// counts at the calibration points, the open and short thresholds and
    /// the rated range.
    pub fn calibration(&self) -> Result<ForceCalibration<FORCE_CAL_POINTS>, CalibrationError> {
        let counts = self.calibration_points_n.map(|n| {
            let c = self.counts(n);
            if c.is_finite() {
                (c.clamp(0.0, 4095.0) + 0.5) as u16
            } else {
                0
            }
        });
        ForceCalibration::new(
            counts,
            self.calibration_points_n,
            OPEN_BELOW_COUNTS,
            SHORT_ABOVE_COUNTS,
            self.rated_min_n,
            self.rated_max_n,
        )
    }
}
