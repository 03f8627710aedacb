//! Fitting the device to a patient: the pilot's measures in, the combined
//! pilot-plus-exoskeleton model out ([`gait_core::bundle::Patient`], which
//! the table generator designs for, the simulator simulates and the bundle
//! carries to the board).
//!
//! The range of pilots is the exoskeleton's: its thigh and shank bars
//! adjust for statures of 1.45–2.00 m, and its drives and frame are rated
//! for pilots of 40–120 kg. Outside it the device is not fitted, whatever
//! the model could compute.

use gait_control::supervisor::ResponseCheck;
use gait_core::anthropometry::{AnthropometryError, Pilot, SegmentLengths};
use gait_core::bundle::Patient;
use gait_core::model::BodyModel;

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

impl Measures {
    /// Height and mass alone: every segment takes Winter's proportion.
    #[must_use]
    pub const fn height_and_mass(height_m: f64, mass_kg: f64) -> Self {
        Self {
            height_m,
            mass_kg,
            thigh_m: None,
            shank_m: None,
            foot_m: None,
        }
    }
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

/// The residual check's inertias (`ResponseCheck`, fault 0x0404) set for
/// the device's own body `was`, carried over to `body`: each in proportion
/// to what it stands for. A swing knee moves the shank and foot about the
/// knee (I₅ + m₅d₅²), a swing hip the straight leg about the hip, a stance
/// joint the body over the foot (its mass times the leg's length squared).
/// The check's limit stays: it is the torque a healthy drive never leaves
/// unexplained, whoever wears the device.
pub fn response_for(
    check: &ResponseCheck,
    was: &BodyModel<f64>,
    body: &BodyModel<f64>,
) -> ResponseCheck {
    let ratio = |f: fn(&BodyModel<f64>) -> f64| {
        let (now, before) = (f(body), f(was));
        let r = now / before;
        if r.is_finite() && r > 0.0 {
            r as f32
        } else {
            1.0
        }
    };
    let (stance, hip, knee) = (
        ratio(stance_inertia),
        ratio(swing_hip_inertia),
        ratio(swing_knee_inertia),
    );
    let [sh, sk] = check.stance_inertia_kgm2;
    let [wh, wk] = check.swing_inertia_kgm2;
    ResponseCheck {
        stance_inertia_kgm2: [sh * stance, sk * stance],
        swing_inertia_kgm2: [wh * hip, wk * knee],
        ..*check
    }
}

/// The body about the stance foot: total mass × (shank + thigh)², kg·m².
fn stance_inertia(body: &BodyModel<f64>) -> f64 {
    let [shank, thigh, ..] = body.links();
    let leg = shank.length_m + thigh.length_m;
    body.total_mass_kg() * leg * leg
}

/// The swing leg, straight, about its hip, kg·m².
fn swing_hip_inertia(body: &BodyModel<f64>) -> f64 {
    let [.., thigh, shank] = body.links();
    let shank_com = thigh.length_m + shank.com_m;
    thigh.inertia_kgm2
        + thigh.mass_kg * thigh.com_m * thigh.com_m
        + shank.inertia_kgm2
        + shank.mass_kg * shank_com * shank_com
}

/// The swing shank and foot about the knee, kg·m².
fn swing_knee_inertia(body: &BodyModel<f64>) -> f64 {
    let [.., shank] = body.links();
    shank.inertia_kgm2 + shank.mass_kg * shank.com_m * shank.com_m
}
