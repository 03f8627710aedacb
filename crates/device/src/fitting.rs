//! Fitting the device to a patient: the pilot's measures in, the combined
//! pilot-plus-exoskeleton model out ([`gait_core::bundle::Patient`], which
//! the table generator designs for, the simulator simulates and the bundle
//! carries to the board).
//!
//! The range of pilots is the exoskeleton's: its thigh and shank bars
//! adjust for statures of 1.45–2.00 m, and its drives and frame are rated
//! for pilots of 40–120 kg. Outside it the device is not fitted, whatever
//! the model could compute.

use gait_core::anthropometry::{AnthropometryError, Pilot, SegmentLengths};
use gait_core::bundle::Patient;

use crate::DeviceConfig;

/// Statures the device adjusts to, m.
pub const HEIGHT_RANGE_M: (f64, f64) = (1.45, 2.00);
/// Pilot masses (without the exoskeleton) the device is rated for, kg.
pub const MASS_RANGE_KG: (f64, f64) = (40.0, 120.0);

/// What the clinic measures; a segment not measured takes Winter's
/// proportion of the height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measures {
    /// Standing height, m.
    pub height_m: f64,
    /// Body mass, kg.
    pub mass_kg: f64,
    /// Greater trochanter to knee joint, m.
    pub thigh_m: Option<f64>,
    /// Knee joint to lateral malleolus, m.
    pub shank_m: Option<f64>,
    /// Heel to toe tip, m.
    pub foot_m: Option<f64>,
}

/// Why a patient cannot be fitted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FitError {
    /// The height is outside [`HEIGHT_RANGE_M`] (or not a number).
    Height(f64),
    /// The mass is outside [`MASS_RANGE_KG`] (or not a number).
    Mass(f64),
    /// The model refused the measures (a segment inconsistent with the
    /// height, or a model check).
    Model(AnthropometryError),
}

impl core::fmt::Display for FitError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Height(h) => write!(
                f,
                "height {h} m is outside what the device adjusts to ({}-{} m)",
                HEIGHT_RANGE_M.0, HEIGHT_RANGE_M.1
            ),
            Self::Mass(m) => write!(
                f,
                "mass {m} kg is outside what the device is rated for ({}-{} kg)",
                MASS_RANGE_KG.0, MASS_RANGE_KG.1
            ),
            Self::Model(e) => write!(f, "{e}"),
        }
    }
}

/// The patient of `measures` on `device`.
pub fn fit(device: &DeviceConfig, measures: &Measures) -> Result<Patient, FitError> {
    let Measures {
        height_m,
        mass_kg,
        thigh_m,
        shank_m,
        foot_m,
    } = *measures;
    let inside = |v: f64, (lo, hi): (f64, f64)| v.is_finite() && (lo..=hi).contains(&v);
    if !inside(height_m, HEIGHT_RANGE_M) {
        return Err(FitError::Height(height_m));
    }
    if !inside(mass_kg, MASS_RANGE_KG) {
        return Err(FitError::Mass(mass_kg));
    }
    let winter = SegmentLengths::winter(height_m);
    let lengths = SegmentLengths {
        thigh_m: thigh_m.unwrap_or(winter.thigh_m),
        shank_m: shank_m.unwrap_or(winter.shank_m),
        foot_m: foot_m.unwrap_or(winter.foot_m),
    };
    let pilot = Pilot { height_m, mass_kg };
    let model = device
        .patient_model(&pilot, &lengths)
        .map_err(FitError::Model)?;
    Ok(Patient {
        height_m,
        mass_kg,
        segments_m: [lengths.thigh_m, lengths.shank_m, lengths.foot_m],
        model,
    })
}
