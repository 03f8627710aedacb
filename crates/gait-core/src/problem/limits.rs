//! Soft limits added to J for tables the device plays (both `None` in paper
//! mode): joint speeds and accelerations ([`JointMotionLimit`]) and joint
//! ranges ([`JointRangeLimit`]).

use crate::scalar::Real;

/// Soft limits on the hip and knee speeds and accelerations of a step, for
/// tables the device plays. The paper's cost does not see the samples near
/// the start and the landing (c_k = 0 within 2 mm of either), so its optima
/// may finish with a joint snapping into place (10–20 rad/s), or, when the
/// ankle comes to rest early, with the torso braking at 20 rad/s² — which
/// asks the stance leg and the pilot for 600–800 N·m that J never counts.
///
/// Term added to J, over the four hip and knee joints (θ2…θ5) at every
/// dynamics sample: `speed_weight · Σ max(0, |θ̇| − speed)²
/// + accel_weight · Σ max(0, |θ̈| − accel)²`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointMotionLimit<T> {
    /// Speed above which the term grows, rad/s.
    pub speed_rad_s: T,
    /// Weight of the speed excess, N²·m² per (rad/s)².
    pub speed_weight: T,
    /// Acceleration above which the term grows, rad/s².
    pub accel_rad_s2: T,
    /// Weight of the acceleration excess, N²·m² per (rad/s²)².
    pub accel_weight: T,
}

impl<T: Real> JointMotionLimit<T> {
    /// The term's contribution of one sample with absolute rates Φ̇ and
    /// accelerations Φ̈ (`None`: rates only, for the first interval).
    pub fn penalty(&self, dphi: &[T; 5], ddphi: Option<&[T; 5]>) -> T {
        let speed = excess_sq(dphi, self.speed_rad_s);
        let accel = ddphi.map_or(T::zero(), |a| excess_sq(a, self.accel_rad_s2));
        self.speed_weight * speed + self.accel_weight * accel
    }
}

/// Σ over θ2…θ5 of max(0, |θ̇_j| − limit)², with Θ̇ the linear part of the
/// map Φ → Θ applied to Φ̇ (the map's constant offsets cancel).
fn excess_sq<T: Real>(dphi: &[T; 5], limit: T) -> T {
    let zero = [T::zero(); 5];
    let rates = crate::kinematics::theta_from_phi(dphi);
    let offset = crate::kinematics::theta_from_phi(&zero);
    let mut sum = T::zero();
    for (r, o) in rates.iter().zip(&offset).skip(1) {
        let excess = ((*r - *o).abs() - limit).max(T::zero());
        sum += excess * excess;
    }
    sum
}

/// A soft joint-range limit for tables the device plays: the paper's IK
/// keeps only the stance knee inside a human range, and a descent's swing
/// knee folds to 108° (Table I: 100°) to clear the step edge. Term added to
/// J at every dynamics sample: `weight · Σ excess²` over the stance knee and
/// hip and the swing hip and knee, where the excess is how far an
/// anatomical angle lies beyond `limits` less `margin_rad` (flexion side;
/// on the extension side, beyond the stop less the margin, never past a
/// stop at 0°: a straight knee costs nothing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointRangeLimit<T> {
    /// The joints' stops (Table I).
    pub limits: crate::model::JointLimits<T>,
    /// How far inside a stop the term starts, rad.
    pub margin_rad: T,
    /// Weight of the squared excess, N²·m² per rad² per sample.
    pub weight: T,
}

/// Why a [`JointRangeLimit`] is refused ([`JointRangeLimit::new`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LimitError {
    /// The margin is not finite and ≥ 0 rad.
    Margin,
    /// The weight is not finite and ≥ 0.
    Weight,
}

impl core::fmt::Display for LimitError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Margin => "the margin must be finite and >= 0 rad",
            Self::Weight => "the weight must be finite and >= 0",
        })
    }
}

impl<T: Real> JointRangeLimit<T> {
    /// A range limit inside `limits`, checked: margin and weight finite and
    /// ≥ 0.
    pub fn new(
        limits: crate::model::JointLimits<T>,
        margin_rad: T,
        weight: T,
    ) -> Result<Self, LimitError> {
        if !(margin_rad.finite() && margin_rad >= T::zero()) {
            return Err(LimitError::Margin);
        }
        if !(weight.finite() && weight >= T::zero()) {
            return Err(LimitError::Weight);
        }
        Ok(Self {
            limits,
            margin_rad,
            weight,
        })
    }

    /// The term at one posture.
    pub fn penalty(&self, phi: &crate::kinematics::Phi<T>) -> T {
        let a = crate::kinematics::anatomical_angles(&crate::kinematics::theta_from_phi(phi));
        let l = &self.limits;
        let m = self.margin_rad;
        let knee = (
            (l.knee_extension_rad - m).max(T::zero()),
            l.knee_flexion_rad - m,
        );
        let hip = (
            (l.hip_extension_rad - m).max(T::zero()),
            l.hip_flexion_rad - m,
        );
        let [_, stance_knee, stance_hip, swing_hip, swing_knee] = a;
        let mut sum = T::zero();
        for (q, (ext, flex)) in [
            (stance_knee, knee),
            (stance_hip, hip),
            (swing_hip, hip),
            (swing_knee, knee),
        ] {
            let excess = (q - flex).max(-ext - q).max(T::zero());
            sum += excess * excess;
        }
        self.weight * sum
    }
}
