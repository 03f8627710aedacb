//! Winter's anthropometric data (*Biomechanics and Motor Control of Human
//! Movement*, 4th ed., 2009): Table 4.1's segment fractions and Fig. 4.1's
//! joint heights, as fractions of body mass and height. Data only, so the
//! numbers can be checked against the book in one place.

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
