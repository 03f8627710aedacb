//! The force sensors' and the drives' current monitors' characteristics
//! and the calibrations the controller reads them with. The simulator's
//! ADC inputs follow the same characteristics, so the calibrations are
//! exact there as on a freshly calibrated device.

use gait_control::controller::FORCE_CAL_POINTS;
use gait_control::drivers::mcp3208::{CalibrationError, DriveCurrentCalibration, ForceCalibration};

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
        let counts = self
            .calibration_points_n
            .map(|n| adc_counts(self.counts(n)));
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

/// A servo amplifier's analog monitor output of its actual current, scaled
/// and offset by the board onto an ADC channel:
/// `V_adc = offset_v + divider_gain · V_out`, `V_out = I · output_full_scale_v
/// / current_full_scale_a`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurrentMonitorSpec {
    /// What it is.
    pub name: &'static str,
    /// The current the amplifier's output reports at full scale, A.
    pub current_full_scale_a: f32,
    /// The output's full scale, V (either sign).
    pub output_full_scale_v: f32,
    /// The board's divider from the output to the ADC input.
    pub divider_gain: f32,
    /// The board's offset at the ADC input (0 A), V.
    pub offset_v: f32,
    /// The ADC's reference, V (4,096 counts).
    pub adc_reference_v: f32,
}

impl CurrentMonitorSpec {
    /// ADC counts per ampere.
    pub fn counts_per_amp(&self) -> f32 {
        4096.0 / self.adc_reference_v * self.divider_gain * self.output_full_scale_v
            / self.current_full_scale_a
    }

    /// ADC counts at 0 A.
    pub fn zero_counts(&self) -> f32 {
        4096.0 * self.offset_v / self.adc_reference_v
    }

    /// ADC counts for a joint torque through a drive giving
    /// `joint_nm_per_amp` (unrounded, unclamped).
    pub fn counts(&self, torque_nm: f32, joint_nm_per_amp: f32) -> f32 {
        self.zero_counts() + self.counts_per_amp() * torque_nm / joint_nm_per_amp
    }

    /// The calibration the controller reads it with, as joint torque, for
    /// a drive giving `joint_nm_per_amp`; the same open and short
    /// thresholds as the force channels (the amplifier's current limit
    /// stays inside them: `parts::DRIVE_CURRENT_MONITOR`).
    pub fn calibration(
        &self,
        joint_nm_per_amp: f32,
    ) -> Result<DriveCurrentCalibration, CalibrationError> {
        DriveCurrentCalibration::new(
            adc_counts(self.zero_counts()),
            joint_nm_per_amp / self.counts_per_amp(),
            OPEN_BELOW_COUNTS,
            SHORT_ABOVE_COUNTS,
        )
    }
}

/// Unrounded counts as the ADC's 12-bit reading (rounded, clamped; not a
/// number reads 0, which every calibration refuses).
fn adc_counts(c: f32) -> u16 {
    if c.is_finite() {
        (c.clamp(0.0, 4095.0) + 0.5) as u16
    } else {
        0
    }
}
