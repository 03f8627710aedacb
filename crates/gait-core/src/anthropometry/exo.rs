//! The exoskeleton's own segments and how each one is combined with the
//! pilot's segment on the same link (mass-weighted centre of mass, parallel
//! axis theorem).

use super::{AnthropometryError, SegmentFractions};
use crate::model::Link;
use crate::scalar::Real;

/// One exoskeleton segment (one side for the legs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExoSegment<T> {
    /// Mass, kg (zero is allowed: no hardware on that segment).
    pub mass_kg: T,
    /// Centre of mass measured from the segment's upper joint (the hip for
    /// torso and thigh, upward for the torso; the knee for the shank), m.
    /// `None`: at the human segment's centre of mass.
    pub com_m: Option<T>,
    /// Moment of inertia about its own centre of mass, kg·m².
    /// `None`: a uniform slender rod over the link, `m l² / 12`.
    pub inertia_kgm2: Option<T>,
}

impl<T: Real> ExoSegment<T> {
    /// A segment of the given mass with unknown centre of mass and inertia.
    pub fn of_mass(mass_kg: f64) -> Self {
        Self {
            mass_kg: T::lit(mass_kg),
            com_m: None,
            inertia_kgm2: None,
        }
    }
}

/// The exoskeleton's segments. Legs are mirrored, so one thigh and one shank
/// describe both sides; the total is `torso + 2 thigh + 2 shank`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExoSegments<T> {
    /// Pelvis frame, back support, hip actuators' housings: rides on the torso.
    pub torso: ExoSegment<T>,
    /// One thigh: thigh bar, knee actuator.
    pub thigh: ExoSegment<T>,
    /// One shank: shank bar, ankle spring, foot plate.
    pub shank: ExoSegment<T>,
}

impl<T: Real> ExoSegments<T> {
    /// ASSUMPTION (not measured): the paper's 17 kg exoskeleton (without
    /// crutches and battery) split as torso 6.2 kg, each thigh 3.5 kg, each
    /// shank 1.9 kg, chosen so that Winter's pilot of 76.5 kg plus this split
    /// lands near Table III's link masses (see `docs/anthropometry.md`).
    /// Centres of mass and inertias unknown (`None`).
    pub fn paper_default() -> Self {
        Self {
            torso: ExoSegment::of_mass(6.2),
            thigh: ExoSegment::of_mass(3.5),
            shank: ExoSegment::of_mass(1.9),
        }
    }

    /// No exoskeleton: the pilot alone.
    pub fn none() -> Self {
        Self {
            torso: ExoSegment::of_mass(0.0),
            thigh: ExoSegment::of_mass(0.0),
            shank: ExoSegment::of_mass(0.0),
        }
    }

    /// Total exoskeleton mass, kg.
    pub fn total_mass_kg(&self) -> T {
        let two = T::lit(2.0);
        self.torso.mass_kg + two * self.thigh.mass_kg + two * self.shank.mass_kg
    }
}

impl<T: Real> Default for ExoSegments<T> {
    fn default() -> Self {
        Self::paper_default()
    }
}

/// Which exoskeleton segment an error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ExoPart {
    /// [`ExoSegments::torso`].
    Torso,
    /// [`ExoSegments::thigh`].
    Thigh,
    /// [`ExoSegments::shank`].
    Shank,
}

impl core::fmt::Display for ExoPart {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Torso => "torso",
            Self::Thigh => "thigh",
            Self::Shank => "shank",
        })
    }
}

/// A rigid body on a link: mass, centre of mass along the link from a chosen
/// end, inertia about its own centre of mass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Body<T> {
    pub(super) mass_kg: T,
    pub(super) com_m: T,
    pub(super) inertia_kgm2: T,
}

impl<T: Real> Body<T> {
    /// A segment from its Winter row: `length` is the row's reference length.
    pub(super) fn from_winter(row: &SegmentFractions, body_mass_kg: T, length_m: T) -> Self {
        let m = T::lit(row.mass) * body_mass_kg;
        let k = T::lit(row.radius_of_gyration) * length_m;
        Self {
            mass_kg: m,
            com_m: T::lit(row.com_from_proximal) * length_m,
            inertia_kgm2: m * k * k,
        }
    }

    /// Two bodies on the same link as one: masses add, the centre of mass is
    /// mass-weighted, and the inertia about the new centre of mass follows the
    /// parallel-axis theorem, `I = Σ (I_k + m_k (d_k − d)²)`. A massless pair
    /// keeps `a`'s centre of mass.
    pub(super) fn combine(a: Self, b: Self) -> Self {
        let m = a.mass_kg + b.mass_kg;
        if m <= T::zero() {
            return a;
        }
        let d = (a.mass_kg * a.com_m + b.mass_kg * b.com_m) / m;
        let da = a.com_m - d;
        let db = b.com_m - d;
        Self {
            mass_kg: m,
            com_m: d,
            inertia_kgm2: a.inertia_kgm2
                + a.mass_kg * da * da
                + b.inertia_kgm2
                + b.mass_kg * db * db,
        }
    }

    /// The same body measured from the link's other end.
    pub(super) fn flipped(self, length_m: T) -> Self {
        Self {
            com_m: length_m - self.com_m,
            ..self
        }
    }

    pub(super) fn link(self, length_m: T) -> Link<T> {
        Link {
            length_m,
            com_m: self.com_m,
            mass_kg: self.mass_kg,
            inertia_kgm2: self.inertia_kgm2,
        }
    }
}

/// The exoskeleton segment as a [`Body`] on a link of `length_m`, with the
/// human segment's centre of mass `human_com_m` (same origin) as the default.
pub(super) fn exo_body<T: Real>(
    seg: &ExoSegment<T>,
    part: ExoPart,
    length_m: T,
    human_com_m: T,
) -> Result<Body<T>, AnthropometryError> {
    let com = seg.com_m.unwrap_or(human_com_m);
    let inertia = seg
        .inertia_kgm2
        .unwrap_or(seg.mass_kg * length_m * length_m / T::lit(12.0));
    if !(seg.mass_kg.finite() && com.finite() && inertia.finite()) {
        return Err(AnthropometryError::ExoNonFinite { part });
    }
    if seg.mass_kg < T::zero() || inertia < T::zero() {
        return Err(AnthropometryError::ExoNegative { part });
    }
    if com < T::zero() || com > length_m {
        return Err(AnthropometryError::ExoComOutsideLink { part });
    }
    Ok(Body {
        mass_kg: seg.mass_kg,
        com_m: com,
        inertia_kgm2: inertia,
    })
}
