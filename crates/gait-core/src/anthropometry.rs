//! A pilot-specific [`BodyModel`] from height and mass, plus the
//! exoskeleton's own segments.
//!
//! Clinics fit the device to each pilot; the paper's Table III is one fitted
//! model (pilot plus exoskeleton, 1.75 m, 93.5 kg). This module builds such a
//! model for any pilot from Winter's anthropometric data (D. A. Winter,
//! *Biomechanics and Motor Control of Human Movement*, 4th ed., 2009:
//! Table 4.1 after Dempster for masses, centres of mass and radii of
//! gyration; Fig. 4.1 after Drillis and Contini for lengths as fractions of
//! height), then adds the exoskeleton's segments by mass-weighted centre of
//! mass and the parallel-axis theorem.
//!
//! Choices (reasons and the measured comparison with Table III are in
//! `docs/anthropometry.md`):
//!
//! - shank = knee to ankle (0.246 H); the foot is lumped at the ankle as a
//!   rigid body whose centre of mass sits on the ankle joint, so total mass is
//!   kept and the stance foot adds no moment about the stance ankle;
//! - thigh = hip (greater trochanter) to knee (0.245 H);
//! - torso (link 3) = head, arms and trunk (HAT) from the hip; its mass
//!   properties are Winter's HAT row, measured along hip → shoulder; the link's
//!   length (which only places the point p3 — the torso's end carries nothing,
//!   so the dynamics do not depend on it) is chosen by [`TorsoSpan`], hip to
//!   head vertex by default;
//! - legs are mirrored: both shanks and both thighs get the same properties.
//!
//! Winter's numbers are in `winter.rs`, the exoskeleton's segments and how
//! they combine with the pilot's in `exo.rs`; this file turns a pilot into
//! links and a validated model.

use crate::model::{BodyModel, JointLimits, LINKS, Link, ModelError};
use crate::scalar::Real;

/// Smallest pilot height accepted, m.
pub const MIN_HEIGHT_M: f64 = 1.2;
/// Largest pilot height accepted, m.
pub const MAX_HEIGHT_M: f64 = 2.2;
/// Smallest pilot mass accepted, kg.
pub const MIN_MASS_KG: f64 = 30.0;
/// Largest pilot mass accepted, kg.
pub const MAX_MASS_KG: f64 = 200.0;

mod exo;
#[cfg(test)]
mod tests;
mod winter;

pub use exo::{ExoPart, ExoSegment, ExoSegments};
pub use winter::*;

use exo::{Body, exo_body};

/// The pilot's measured stature and body mass (without the exoskeleton).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pilot<T> {
    /// Standing height, floor to head vertex, m.
    pub height_m: T,
    /// Body mass, kg.
    pub mass_kg: T,
}

impl<T: Real> Pilot<T> {
    /// The paper's pilot: 1.75 m, 93.5 kg with the 17 kg exoskeleton, so
    /// 76.5 kg alone.
    pub fn paper() -> Self {
        Self {
            height_m: T::lit(1.75),
            mass_kg: T::lit(76.5),
        }
    }

    /// Checks finite, positive and plausible values.
    pub fn check(&self) -> Result<(), AnthropometryError> {
        if !self.height_m.finite() {
            return Err(AnthropometryError::NonFiniteHeight);
        }
        if !self.mass_kg.finite() {
            return Err(AnthropometryError::NonFiniteMass);
        }
        if self.height_m <= T::zero() {
            return Err(AnthropometryError::NonPositiveHeight);
        }
        if self.mass_kg <= T::zero() {
            return Err(AnthropometryError::NonPositiveMass);
        }
        if self.height_m < T::lit(MIN_HEIGHT_M) || self.height_m > T::lit(MAX_HEIGHT_M) {
            return Err(AnthropometryError::ImplausibleHeight);
        }
        if self.mass_kg < T::lit(MIN_MASS_KG) || self.mass_kg > T::lit(MAX_MASS_KG) {
            return Err(AnthropometryError::ImplausibleMass);
        }
        Ok(())
    }
}

/// Largest departure of a measured segment from Winter's proportion of
/// the pilot's height, as a share of that proportion: Winter's segment
/// fractions vary between adults by a few percent (one standard deviation
/// is about 5 %), so a measurement 20 % away is a mistake in the measuring
/// or in the height, not a body.
pub const SEGMENT_TOLERANCE: f64 = 0.2;

/// The leg segments' lengths, m: the model's thigh (hip to knee) and shank
/// (knee to ankle) links, and the foot (heel to toe tip; it sets only the
/// foot's radius of gyration: the foot is lumped at the ankle).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SegmentLengths<T> {
    /// Greater trochanter to knee joint, m.
    pub thigh_m: T,
    /// Knee joint to lateral malleolus, m.
    pub shank_m: T,
    /// Heel to the tip of the longest toe, m.
    pub foot_m: T,
}

/// Which leg segment a length is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Segment {
    /// [`SegmentLengths::thigh_m`].
    Thigh,
    /// [`SegmentLengths::shank_m`].
    Shank,
    /// [`SegmentLengths::foot_m`].
    Foot,
}

impl Segment {
    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Thigh => "thigh",
            Self::Shank => "shank",
            Self::Foot => "foot",
        }
    }

    /// Winter's proportion of the height.
    pub fn fraction(self) -> f64 {
        match self {
            Self::Thigh => THIGH_LENGTH,
            Self::Shank => SHANK_LENGTH,
            Self::Foot => FOOT_LENGTH,
        }
    }
}

impl<T: Real> SegmentLengths<T> {
    /// Winter's proportions of `height_m`.
    pub fn winter(height_m: T) -> Self {
        Self {
            thigh_m: T::lit(THIGH_LENGTH) * height_m,
            shank_m: T::lit(SHANK_LENGTH) * height_m,
            foot_m: T::lit(FOOT_LENGTH) * height_m,
        }
    }

    /// Each length finite and within [`SEGMENT_TOLERANCE`] of Winter's
    /// proportion of `height_m`.
    pub fn check(&self, height_m: T) -> Result<(), AnthropometryError> {
        let given = [
            (Segment::Thigh, self.thigh_m),
            (Segment::Shank, self.shank_m),
            (Segment::Foot, self.foot_m),
        ];
        for (segment, length) in given {
            let expected = T::lit(segment.fraction()) * height_m;
            let off = (length - expected).abs();
            if !length.finite() || off > T::lit(SEGMENT_TOLERANCE) * expected {
                return Err(AnthropometryError::SegmentInconsistent { segment });
            }
        }
        Ok(())
    }
}

/// What the torso link (link 3) spans. Only the point p3 depends on it: the
/// torso's free end carries no link, so D, H and G do not.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TorsoSpan {
    /// Hip to shoulder (glenohumeral joint): 0.288 H, the HAT row's own
    /// reference length (0.504 m at 1.75 m; Table III has 0.714 m).
    HipToShoulder,
    /// Hip to head vertex: 0.470 H (0.8225 m at 1.75 m), the whole upper body,
    /// so p3 is the top of the head (stair and door clearance).
    #[default]
    HipToVertex,
}

/// Options of [`body_model_with`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options<T> {
    /// What link 3 spans.
    pub torso: TorsoSpan,
    /// Joint limits to put in the model.
    pub limits: JointLimits<T>,
}

impl<T: Real> Default for Options<T> {
    /// Hip to vertex, Table I's joint limits.
    fn default() -> Self {
        Self {
            torso: TorsoSpan::default(),
            limits: JointLimits::paper_table_i(),
        }
    }
}

/// Why a body model could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AnthropometryError {
    /// Height is NaN or infinite.
    NonFiniteHeight,
    /// Mass is NaN or infinite.
    NonFiniteMass,
    /// Height is zero or negative.
    NonPositiveHeight,
    /// Mass is zero or negative.
    NonPositiveMass,
    /// Height outside [`MIN_HEIGHT_M`]–[`MAX_HEIGHT_M`].
    ImplausibleHeight,
    /// Mass outside [`MIN_MASS_KG`]–[`MAX_MASS_KG`].
    ImplausibleMass,
    /// An exoskeleton value is NaN or infinite.
    ExoNonFinite {
        /// Which segment.
        part: ExoPart,
    },
    /// An exoskeleton mass or inertia is negative.
    ExoNegative {
        /// Which segment.
        part: ExoPart,
    },
    /// An exoskeleton centre of mass lies outside its link.
    ExoComOutsideLink {
        /// Which segment.
        part: ExoPart,
    },
    /// A segment's length is not finite or departs from Winter's
    /// proportion of the height by more than [`SEGMENT_TOLERANCE`].
    SegmentInconsistent {
        /// Which segment.
        segment: Segment,
    },
    /// The assembled links failed [`BodyModel::new`]'s checks.
    Model(ModelError),
}

impl From<ModelError> for AnthropometryError {
    fn from(e: ModelError) -> Self {
        Self::Model(e)
    }
}

impl core::fmt::Display for AnthropometryError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NonFiniteHeight => f.write_str("pilot height is not a finite number"),
            Self::NonFiniteMass => f.write_str("pilot mass is not a finite number"),
            Self::NonPositiveHeight => f.write_str("pilot height must be > 0"),
            Self::NonPositiveMass => f.write_str("pilot mass must be > 0"),
            Self::ImplausibleHeight => write!(
                f,
                "pilot height must be within {MIN_HEIGHT_M}-{MAX_HEIGHT_M} m"
            ),
            Self::ImplausibleMass => write!(
                f,
                "pilot mass must be within {MIN_MASS_KG}-{MAX_MASS_KG} kg"
            ),
            Self::ExoNonFinite { part } => write!(f, "exoskeleton {part}: a value is not finite"),
            Self::ExoNegative { part } => {
                write!(f, "exoskeleton {part}: mass and inertia must be >= 0")
            }
            Self::ExoComOutsideLink { part } => write!(
                f,
                "exoskeleton {part}: centre of mass must lie on the link (0 <= com_m <= length)"
            ),
            Self::SegmentInconsistent { segment } => write!(
                f,
                "the {} length is not within {:.0} % of {:.3} x height (Winter's proportion): measured wrongly, or the height is wrong",
                segment.name(),
                SEGMENT_TOLERANCE * 100.0,
                segment.fraction()
            ),
            Self::Model(e) => write!(f, "assembled model rejected: {e}"),
        }
    }
}

/// The five links (stance shank, stance thigh, torso, swing thigh, swing
/// shank) for a pilot wearing the exoskeleton, before validation.
///
/// Each link's `com_m` is from its proximal joint along the chain: link 1
/// from the ankle, link 2 from the knee, links 3 and 4 from the hip, link 5
/// from the knee; inertias are about the combined centre of mass.
pub fn links_for<T: Real>(
    pilot: &Pilot<T>,
    exo: &ExoSegments<T>,
    torso: TorsoSpan,
) -> Result<[Link<T>; LINKS], AnthropometryError> {
    pilot.check()?;
    links_with_lengths(pilot, &SegmentLengths::winter(pilot.height_m), exo, torso)
}

/// [`links_for`] with the leg segments' lengths given (measured on the
/// pilot, or Winter's proportions where not), each checked against the
/// height by [`SegmentLengths::check`].
pub fn links_with_lengths<T: Real>(
    pilot: &Pilot<T>,
    lengths: &SegmentLengths<T>,
    exo: &ExoSegments<T>,
    torso: TorsoSpan,
) -> Result<[Link<T>; LINKS], AnthropometryError> {
    pilot.check()?;
    lengths.check(pilot.height_m)?;
    let h = pilot.height_m;
    let m = pilot.mass_kg;

    // Shank, measured from the knee: Winter's leg plus the foot as a rigid
    // body whose centre of mass is at the ankle.
    let l_shank = lengths.shank_m;
    let leg = Body::from_winter(&LEG, m, l_shank);
    let foot_row = Body::from_winter(&FOOT, m, lengths.foot_m);
    let foot = Body {
        com_m: l_shank,
        ..foot_row
    };
    let human_shank = Body::combine(leg, foot);
    let exo_shank = exo_body(&exo.shank, ExoPart::Shank, l_shank, human_shank.com_m)?;
    let shank = Body::combine(human_shank, exo_shank);

    // Thigh, measured from the hip.
    let l_thigh = lengths.thigh_m;
    let human_thigh = Body::from_winter(&THIGH, m, l_thigh);
    let exo_thigh = exo_body(&exo.thigh, ExoPart::Thigh, l_thigh, human_thigh.com_m)?;
    let thigh = Body::combine(human_thigh, exo_thigh);

    // Torso, measured from the hip: HAT along hip → shoulder.
    let l_torso = match torso {
        TorsoSpan::HipToShoulder => T::lit(HIP_TO_SHOULDER),
        TorsoSpan::HipToVertex => T::lit(HIP_TO_VERTEX),
    } * h;
    let human_torso = Body::from_winter(&HAT, m, T::lit(HIP_TO_SHOULDER) * h);
    let exo_torso = exo_body(&exo.torso, ExoPart::Torso, l_torso, human_torso.com_m)?;
    let torso_body = Body::combine(human_torso, exo_torso);

    Ok([
        shank.flipped(l_shank).link(l_shank),
        thigh.flipped(l_thigh).link(l_thigh),
        torso_body.link(l_torso),
        thigh.link(l_thigh),
        shank.link(l_shank),
    ])
}

/// A validated model for this pilot and exoskeleton, with the default
/// [`Options`] (torso to the head vertex, Table I's joint limits).
pub fn body_model_for<T: Real>(
    pilot: &Pilot<T>,
    exo: &ExoSegments<T>,
) -> Result<BodyModel<T>, AnthropometryError> {
    body_model_with(pilot, exo, &Options::default())
}

/// A validated model for this pilot and exoskeleton with explicit options.
pub fn body_model_with<T: Real>(
    pilot: &Pilot<T>,
    exo: &ExoSegments<T>,
    options: &Options<T>,
) -> Result<BodyModel<T>, AnthropometryError> {
    let links = links_for(pilot, exo, options.torso)?;
    Ok(BodyModel::new(links, options.limits)?)
}

/// A validated model for this pilot with measured leg lengths (see
/// [`links_with_lengths`]).
pub fn body_model_with_lengths<T: Real>(
    pilot: &Pilot<T>,
    lengths: &SegmentLengths<T>,
    exo: &ExoSegments<T>,
    options: &Options<T>,
) -> Result<BodyModel<T>, AnthropometryError> {
    let links = links_with_lengths(pilot, lengths, exo, options.torso)?;
    Ok(BodyModel::new(links, options.limits)?)
}
