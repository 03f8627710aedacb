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

/// One row of Winter's Table 4.1: fractions of body mass and of segment
/// length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentFractions {
    /// Segment mass / total body mass.
    pub mass: f64,
    /// Centre of mass distance from the proximal end / segment length.
    pub com_from_proximal: f64,
    /// Radius of gyration about the centre of mass / segment length.
    pub radius_of_gyration: f64,
}

/// Winter Table 4.1, "Thigh" (greater trochanter to femoral condyles).
pub const THIGH: SegmentFractions = SegmentFractions {
    mass: 0.100,
    com_from_proximal: 0.433,
    radius_of_gyration: 0.323,
};

/// Winter Table 4.1, "Leg" (femoral condyles to medial malleolus).
pub const LEG: SegmentFractions = SegmentFractions {
    mass: 0.0465,
    com_from_proximal: 0.433,
    radius_of_gyration: 0.302,
};

/// Winter Table 4.1, "Foot" (lateral malleolus to head of metatarsal II).
pub const FOOT: SegmentFractions = SegmentFractions {
    mass: 0.0145,
    com_from_proximal: 0.50,
    radius_of_gyration: 0.475,
};

/// Winter Table 4.1, "Head, arms and trunk" (greater trochanter to
/// glenohumeral joint).
pub const HAT: SegmentFractions = SegmentFractions {
    mass: 0.678,
    com_from_proximal: 0.626,
    radius_of_gyration: 0.496,
};

/// Winter Fig. 4.1: hip (greater trochanter) height / body height.
pub const HIP_HEIGHT: f64 = 0.530;
/// Winter Fig. 4.1: knee height / body height.
pub const KNEE_HEIGHT: f64 = 0.285;
/// Winter Fig. 4.1: ankle height / body height.
pub const ANKLE_HEIGHT: f64 = 0.039;
/// Winter Fig. 4.1: shoulder (glenohumeral) height / body height.
pub const SHOULDER_HEIGHT: f64 = 0.818;
/// Winter Fig. 4.1: foot length / body height.
pub const FOOT_LENGTH: f64 = 0.152;

/// Thigh length (hip to knee) / height: 0.530 − 0.285 = 0.245.
pub const THIGH_LENGTH: f64 = HIP_HEIGHT - KNEE_HEIGHT;
/// Shank length (knee to ankle) / height: 0.285 − 0.039 = 0.246.
pub const SHANK_LENGTH: f64 = KNEE_HEIGHT - ANKLE_HEIGHT;
/// Hip to shoulder / height: 0.818 − 0.530 = 0.288 (the HAT row's length).
pub const HIP_TO_SHOULDER: f64 = SHOULDER_HEIGHT - HIP_HEIGHT;
/// Hip to head vertex / height: 1 − 0.530 = 0.470.
pub const HIP_TO_VERTEX: f64 = 1.0 - HIP_HEIGHT;

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
    /// The assembled links failed [`BodyModel::new`]'s checks.
    Model(ModelError),
}

impl From<ModelError> for AnthropometryError {
    fn from(e: ModelError) -> Self {
        Self::Model(e)
    }
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
            Self::Model(e) => write!(f, "assembled model rejected: {e}"),
        }
    }
}

/// A rigid body on a link: mass, centre of mass along the link from a chosen
/// end, inertia about its own centre of mass.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Body<T> {
    mass_kg: T,
    com_m: T,
    inertia_kgm2: T,
}

impl<T: Real> Body<T> {
    /// A segment from its Winter row: `length` is the row's reference length.
    fn from_winter(row: &SegmentFractions, body_mass_kg: T, length_m: T) -> Self {
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
    fn combine(a: Self, b: Self) -> Self {
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
    fn flipped(self, length_m: T) -> Self {
        Self {
            com_m: length_m - self.com_m,
            ..self
        }
    }

    fn link(self, length_m: T) -> Link<T> {
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
fn exo_body<T: Real>(
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
    let h = pilot.height_m;
    let m = pilot.mass_kg;

    // Shank, measured from the knee: Winter's leg plus the foot as a rigid
    // body whose centre of mass is at the ankle.
    let l_shank = T::lit(SHANK_LENGTH) * h;
    let leg = Body::from_winter(&LEG, m, l_shank);
    let foot_row = Body::from_winter(&FOOT, m, T::lit(FOOT_LENGTH) * h);
    let foot = Body {
        com_m: l_shank,
        ..foot_row
    };
    let human_shank = Body::combine(leg, foot);
    let exo_shank = exo_body(&exo.shank, ExoPart::Shank, l_shank, human_shank.com_m)?;
    let shank = Body::combine(human_shank, exo_shank);

    // Thigh, measured from the hip.
    let l_thigh = T::lit(THIGH_LENGTH) * h;
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

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use proptest::prelude::*;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b) / b
    }

    /// Table III lengths and masses within 10 % for the paper's pilot; the
    /// numbers printed here are the ones quoted in docs/anthropometry.md
    /// (`cargo test -p gait-core anthropometry -- --nocapture`).
    #[test]
    fn reproduces_table_iii_lengths_and_masses() -> Result<(), AnthropometryError> {
        let model = body_model_for(&Pilot::<f64>::paper(), &ExoSegments::paper_default())?;
        let ours = model.links();
        let paper = BodyModel::<f64>::paper_table_iii();
        let theirs = paper.links();
        for i in 0..LINKS {
            let (a, b) = (ours[i], theirs[i]);
            std::println!(
                "link {}: l {:.4} vs {:.3} ({:+.1} %), d {:.4} vs {:.3} ({:+.1} %), \
                 m {:.3} vs {:.2} ({:+.1} %), I {:.4} vs {:.3} ({:+.1} %)",
                i + 1,
                a.length_m,
                b.length_m,
                100.0 * rel(a.length_m, b.length_m),
                a.com_m,
                b.com_m,
                100.0 * rel(a.com_m, b.com_m),
                a.mass_kg,
                b.mass_kg,
                100.0 * rel(a.mass_kg, b.mass_kg),
                a.inertia_kgm2,
                b.inertia_kgm2,
                100.0 * rel(a.inertia_kgm2, b.inertia_kgm2),
            );
        }
        // Leg lengths within 10 %.
        for i in [0, 1, 3, 4] {
            assert!(
                rel(ours[i].length_m, theirs[i].length_m).abs() < 0.10,
                "l{}",
                i + 1
            );
        }
        // The torso's length is a convention (TorsoSpan); hip to vertex is
        // within 16 % of Table III, hip to shoulder 30 % short.
        assert!(rel(ours[2].length_m, theirs[2].length_m).abs() < 0.16);
        // Masses within 10 % of each link (Table III's legs differ by 1 kg
        // between stance and swing; ours are mirrored).
        for i in 0..LINKS {
            assert!(
                rel(ours[i].mass_kg, theirs[i].mass_kg).abs() < 0.10,
                "m{}",
                i + 1
            );
        }
        // Totals: 76.5 + 17 = 93.5 kg (the paper's text), Table III sums to 92.8.
        assert!((model.total_mass_kg() - 93.5).abs() < 1e-9);
        // Hip height standing, ankle to hip: 0.491 H = 0.859 m vs 0.836 m.
        let hip = ours[0].length_m + ours[1].length_m;
        assert!(rel(hip, 0.836).abs() < 0.03);
        Ok(())
    }

    #[test]
    fn hip_to_shoulder_option() -> Result<(), AnthropometryError> {
        let opts = Options {
            torso: TorsoSpan::HipToShoulder,
            ..Options::default()
        };
        let m = body_model_with(&Pilot::<f64>::paper(), &ExoSegments::paper_default(), &opts)?;
        assert!((m.links()[2].length_m - 0.288 * 1.75).abs() < 1e-12);
        // Same dynamics-relevant torso properties as the default span, apart
        // from the default exo inertia (a rod over the link).
        let d = body_model_for(&Pilot::<f64>::paper(), &ExoSegments::paper_default())?;
        assert!((m.links()[2].com_m - d.links()[2].com_m).abs() < 1e-12);
        assert!((m.links()[2].mass_kg - d.links()[2].mass_kg).abs() < 1e-12);
        Ok(())
    }

    #[test]
    fn pilot_alone_matches_winter_by_hand() -> Result<(), AnthropometryError> {
        let p = Pilot {
            height_m: 1.80_f64,
            mass_kg: 80.0,
        };
        let m = body_model_for(&p, &ExoSegments::none())?;
        let l = m.links();
        // Thigh: 0.245 H, 0.100 M, COM 0.433 l from the hip, k = 0.323 l.
        let lt: f64 = 0.245 * 1.80;
        assert!((l[3].length_m - lt).abs() < 1e-12);
        assert!((l[3].mass_kg - 8.0).abs() < 1e-12);
        assert!((l[3].com_m - 0.433 * lt).abs() < 1e-12);
        assert!((l[3].inertia_kgm2 - 8.0 * (0.323 * lt).powi(2)).abs() < 1e-12);
        assert!((l[1].com_m - 0.567 * lt).abs() < 1e-12);
        // Shank: leg 0.0465 M plus foot 0.0145 M at the ankle.
        let ls: f64 = 0.246 * 1.80;
        let (ml, mf): (f64, f64) = (0.0465 * 80.0, 0.0145 * 80.0);
        let d = (ml * 0.433 * ls + mf * ls) / (ml + mf);
        let i = ml * (0.302 * ls).powi(2)
            + ml * (0.433 * ls - d).powi(2)
            + mf * (0.475 * 0.152 * 1.80_f64).powi(2)
            + mf * (ls - d).powi(2);
        assert!((l[4].mass_kg - 0.061 * 80.0).abs() < 1e-12);
        assert!((l[4].com_m - d).abs() < 1e-12);
        assert!((l[0].com_m - (ls - d)).abs() < 1e-12);
        assert!((l[4].inertia_kgm2 - i).abs() < 1e-12);
        // HAT: 0.678 M, COM 0.626 × 0.288 H from the hip, k = 0.496 × 0.288 H.
        let lh: f64 = 0.288 * 1.80;
        assert!((l[2].mass_kg - 0.678 * 80.0).abs() < 1e-9);
        assert!((l[2].com_m - 0.626 * lh).abs() < 1e-12);
        assert!((l[2].inertia_kgm2 - 0.678 * 80.0 * (0.496 * lh).powi(2)).abs() < 1e-9);
        // The table's fractions sum to the whole body.
        assert!((m.total_mass_kg() - 80.0).abs() < 1e-9);
        Ok(())
    }

    #[test]
    fn exo_parallel_axis_by_hand() -> Result<(), AnthropometryError> {
        let p = Pilot {
            height_m: 1.75_f64,
            mass_kg: 70.0,
        };
        let exo = ExoSegments {
            torso: ExoSegment::of_mass(0.0),
            thigh: ExoSegment {
                mass_kg: 3.0,
                com_m: Some(0.30),
                inertia_kgm2: Some(0.05),
            },
            shank: ExoSegment::of_mass(0.0),
        };
        let m = body_model_for(&p, &exo)?;
        let lt: f64 = 0.245 * 1.75;
        let (mh, dh, ih): (f64, f64, f64) = (7.0, 0.433 * lt, 7.0 * (0.323 * lt).powi(2));
        let d = (mh * dh + 3.0 * 0.30) / 10.0;
        let i = ih + mh * (dh - d).powi(2) + 0.05 + 3.0 * (0.30 - d).powi(2);
        let t = m.links()[3];
        assert!((t.mass_kg - 10.0).abs() < 1e-12);
        assert!((t.com_m - d).abs() < 1e-12);
        assert!((t.inertia_kgm2 - i).abs() < 1e-12);
        // Stance thigh: same body measured from the knee.
        assert!((m.links()[1].com_m - (lt - d)).abs() < 1e-12);
        Ok(())
    }

    #[test]
    fn rejects_bad_input() {
        let exo = ExoSegments::<f64>::paper_default();
        let bad = |h: f64, m: f64| {
            body_model_for(
                &Pilot {
                    height_m: h,
                    mass_kg: m,
                },
                &exo,
            )
        };
        use AnthropometryError as E;
        assert_eq!(bad(f64::NAN, 70.0), Err(E::NonFiniteHeight));
        assert_eq!(bad(1.7, f64::INFINITY), Err(E::NonFiniteMass));
        assert_eq!(bad(0.0, 70.0), Err(E::NonPositiveHeight));
        assert_eq!(bad(1.7, -1.0), Err(E::NonPositiveMass));
        assert_eq!(bad(1.1, 70.0), Err(E::ImplausibleHeight));
        assert_eq!(bad(2.3, 70.0), Err(E::ImplausibleHeight));
        assert_eq!(bad(1.7, 29.0), Err(E::ImplausibleMass));
        assert_eq!(bad(1.7, 201.0), Err(E::ImplausibleMass));
        let p = Pilot::<f64>::paper();
        let mut e = exo;
        e.thigh.mass_kg = -1.0;
        assert_eq!(
            body_model_for(&p, &e),
            Err(E::ExoNegative {
                part: ExoPart::Thigh
            })
        );
        let mut e = exo;
        e.shank.com_m = Some(0.9);
        assert_eq!(
            body_model_for(&p, &e),
            Err(E::ExoComOutsideLink {
                part: ExoPart::Shank
            })
        );
        let mut e = exo;
        e.torso.inertia_kgm2 = Some(f64::NAN);
        assert_eq!(
            body_model_for(&p, &e),
            Err(E::ExoNonFinite {
                part: ExoPart::Torso
            })
        );
    }

    #[test]
    fn f32_matches_f64() -> Result<(), AnthropometryError> {
        let a = body_model_for(&Pilot::<f32>::paper(), &ExoSegments::paper_default())?;
        let b = body_model_for(&Pilot::<f64>::paper(), &ExoSegments::paper_default())?;
        for (x, y) in a.links().iter().zip(b.links()) {
            assert!((f64::from(x.mass_kg) - y.mass_kg).abs() < 1e-4);
            assert!((f64::from(x.inertia_kgm2) - y.inertia_kgm2).abs() < 1e-5);
        }
        Ok(())
    }

    fn exo_strategy() -> impl Strategy<Value = ExoSegments<f64>> {
        (0.0..15.0_f64, 0.0..6.0_f64, 0.0..4.0_f64).prop_map(|(t, th, s)| ExoSegments {
            torso: ExoSegment::of_mass(t),
            thigh: ExoSegment::of_mass(th),
            shank: ExoSegment::of_mass(s),
        })
    }

    proptest! {
        #[test]
        fn any_valid_pilot_builds_a_valid_model(
            h in MIN_HEIGHT_M..=MAX_HEIGHT_M,
            m in MIN_MASS_KG..=MAX_MASS_KG,
            exo in exo_strategy(),
            shoulder in any::<bool>(),
        ) {
            let pilot = Pilot { height_m: h, mass_kg: m };
            let torso = if shoulder { TorsoSpan::HipToShoulder } else { TorsoSpan::HipToVertex };
            let opts = Options { torso, ..Options::default() };
            let model = body_model_with(&pilot, &exo, &opts);
            prop_assert!(model.is_ok(), "{:?}", model);
            let model = model.map_err(|e| TestCaseError::fail(std::format!("{e}")))?;
            // Passes BodyModel::new again (the builder went through it).
            prop_assert!(BodyModel::new(*model.links(), *model.limits()).is_ok());
            let expected = m + exo.total_mass_kg();
            prop_assert!((model.total_mass_kg() - expected).abs() < 1e-9 * expected);
        }

        #[test]
        fn default_exo_total_is_pilot_plus_17_kg(
            h in MIN_HEIGHT_M..=MAX_HEIGHT_M,
            m in MIN_MASS_KG..=MAX_MASS_KG,
        ) {
            let pilot = Pilot { height_m: h, mass_kg: m };
            let model = body_model_for(&pilot, &ExoSegments::paper_default()).map_err(|e| TestCaseError::fail(std::format!("{e}")))?;
            prop_assert!((model.total_mass_kg() - (m + 17.0)).abs() < 1e-9);
        }
    }
}
