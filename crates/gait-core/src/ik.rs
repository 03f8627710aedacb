//! Inverse kinematics (paper section III-B, eq. (dfsadf)–(dssgf)):
//! (x5, y5, φ1, φ3, r2) → Φ, Θ and the joint points.
//!
//! The steps, as the paper describes them, with the defects of the printed
//! equations resolved (each choice is argued in `docs/model.md`):
//!
//! 1. p1 = l1 (sin φ1, cos φ1) (eq. (lll)).
//! 2. If the swing leg is folded so far that no hip circle intersects
//!    (‖p5 − p1‖ + l2 ≤ l4 + l5), the φ2 range is [φ1 − π/4, φ1]. This case is
//!    tested *first* (the printed case list puts it last, where it can never
//!    be reached).
//! 3. Otherwise the two-circle intersection (ψ, B1, B2; eq. (qw), (dsfgf))
//!    gives the φ2 at which the swing leg is fully stretched, with
//!    B2 = sgn(x5 − x1) √(l2² − B1²) — the printed sgn(x5) is measured from
//!    the stance ankle where the geometry needs the stance knee, and empties
//!    the range for reachable targets. The same sign picks which bound the
//!    stretch limits (eq. (aaa), (aba)); a zero sign gives [φ1 − π/4, φ1].
//! 4. φ2 = r2 φ2max + (1 − r2) φ2min (eq. (diiii)); p2 by eq. (llll).
//! 5. The swing knee p4 from the second intersection (C1, C2; eq. (leell),
//!    (dssgf)) with C2 = +√(l4² − C1²): knee in front of the hip–ankle line.
//! 6. Every φ_i from consecutive points (eq. (dfsadf)), Θ = A⁻¹(Φ − b).
//!
//! Properties worth knowing (tested): the min/max of eq. (aaa)/(aba) make the
//! map non-smooth (kinks where the stretch bound crosses φ1 or φ1 − π/4), and
//! it jumps where step 2's condition switches. φ2min = φ1 − π/4 caps stance
//! knee flexion at 45° although Table I allows 100°.

use crate::kinematics::{Phi, Point, Theta, theta_from_phi, wrap_pi};
use crate::model::{BodyModel, LINKS};
use crate::scalar::Real;

/// What the gait description fixes at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IkTarget<T> {
    /// Swing-ankle x, m (stance ankle at the origin, x forward).
    pub x5: T,
    /// Swing-ankle y, m (y up).
    pub y5: T,
    /// Stance-shank absolute angle φ1, rad (clockwise from vertical-up).
    pub phi1: T,
    /// Torso absolute angle φ3, rad.
    pub phi3: T,
    /// Knee-choice ratio r2 in [0, 1]: where in the feasible φ2 range the
    /// stance thigh sits (1 = φ2max, 0 = φ2min).
    pub r2: T,
}

/// A solved posture.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IkSolution<T> {
    /// Absolute angles Φ, rad.
    pub phi: Phi<T>,
    /// Relative (joint) angles Θ, rad.
    pub theta: Theta<T>,
    /// Joint points p1…p5, m.
    pub points: [Point<T>; LINKS],
    /// The feasible stance-thigh range [φ2min, φ2max] that r2 chose from.
    pub phi2_range: (T, T),
}

/// Why a target has no posture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum IkError {
    /// An input was NaN or infinite.
    NonFinite,
    /// r2 outside [0, 1] (beyond the solver's tolerance).
    RatioOutOfRange,
    /// The swing ankle is farther from the stance knee than the stretched
    /// thigh and swing leg can reach (‖p5 − p1‖ > l2 + l4 + l5).
    Unreachable,
    /// The human-range limits leave no φ2 (φ2min > φ2max).
    EmptyHipRange,
    /// With the chosen φ2, the swing leg cannot reach p5 from the hip
    /// (‖p5 − p2‖ outside [|l4 − l5|, l4 + l5]).
    SwingLegUnreachable,
}

impl core::fmt::Display for IkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "an input is not finite",
            Self::RatioOutOfRange => "r2 must be in [0, 1]",
            Self::Unreachable => "swing ankle out of reach of the stance knee",
            Self::EmptyHipRange => {
                "no stance-thigh angle within the human range reaches the target"
            }
            Self::SwingLegUnreachable => "the swing leg cannot reach the target from the hip",
        })
    }
}

/// Which stance-thigh range r2 chooses from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum KneeRange {
    /// The paper's: the human range narrowed by where the swing leg, fully
    /// stretched, can still reach the target (eq. (aaa)/(aba)). Which bound
    /// the stretch limits depends on the sign of x5 − x1, and the range
    /// jumps where that sign changes with the bound active.
    Reach,
    /// The human range alone, [φ1 − cap, φ1]: r2 is the stance knee's
    /// flexion as a fraction of the cap (flexion = (1 − r2)·cap), a
    /// continuous function of the target. A posture the swing leg cannot
    /// reach is reported ([`IkError::SwingLegUnreachable`]) instead of
    /// being avoided by the range. Stair descent needs it: there the stance
    /// knee, leaning on its toe, passes over the swing foot with the bound
    /// active, and the paper's range made the stance thigh jump 0.3 rad in
    /// one sample (docs/model.md, "Stair descent").
    Human,
}

/// How the IK chooses the stance thigh: the paper's choices, or the
/// descent's.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IkOptions<T> {
    /// Largest stance-knee flexion, rad (paper: π/4).
    pub stance_knee_max_rad: T,
    /// The φ2 range r2 maps onto.
    pub knee_range: KneeRange,
}

/// Why [`IkOptions`] are refused ([`IkOptions::new`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum IkOptionsError {
    /// The stance-knee cap is not finite and within (0, π/2] rad.
    StanceKneeCap,
}

impl core::fmt::Display for IkOptionsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::StanceKneeCap => f.write_str("the stance-knee cap must be in (0, pi/2] rad"),
        }
    }
}

impl<T: Real> IkOptions<T> {
    /// Options with a stance-knee cap, checked to be finite and within
    /// (0, π/2] rad.
    pub fn new(stance_knee_max_rad: T, knee_range: KneeRange) -> Result<Self, IkOptionsError> {
        let cap = stance_knee_max_rad;
        if !(cap.finite() && cap > T::zero() && cap <= T::lit(core::f64::consts::FRAC_PI_2)) {
            return Err(IkOptionsError::StanceKneeCap);
        }
        Ok(Self {
            stance_knee_max_rad,
            knee_range,
        })
    }

    /// The paper's human range: 45° of stance knee, the reach-narrowed range.
    pub fn paper() -> Self {
        Self {
            stance_knee_max_rad: T::frac_pi_4(),
            knee_range: KneeRange::Reach,
        }
    }

    /// The same options in another precision (as [`crate::BodyModel::cast`]).
    pub fn cast<U: Real>(&self) -> IkOptions<U> {
        IkOptions {
            stance_knee_max_rad: U::lit(self.stance_knee_max_rad.to_f64()),
            knee_range: self.knee_range,
        }
    }
}

/// The IK solver: the model's lengths and the tolerances it works to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkSolver<T> {
    l: [T; LINKS],
    /// Slack accepted on r2 ∈ [0, 1] and on circle-intersection radicands,
    /// so that targets exactly at a boundary (rounded) still solve.
    pub tolerance: T,
    /// Largest stance-knee flexion the φ2 range allows, rad: φ2min =
    /// φ1 − this. The paper's human range is π/4 (the default); stair
    /// descent needs more (the trailing knee bends past 45° while the foot
    /// is still on the upper step; docs/model.md).
    pub stance_knee_max_rad: T,
    /// The φ2 range r2 maps onto (paper: [`KneeRange::Reach`]).
    pub knee_range: KneeRange,
}

impl<T: Real> IkSolver<T> {
    /// A solver for this model with the default tolerance (1e-9 in f64,
    /// 1e-5 in f32, chosen by the scalar's precision).
    pub fn new(model: &BodyModel<T>) -> Self {
        let tolerance = T::sqrt_epsilon() * T::lit(1e-1);
        Self {
            l: model.lengths(),
            tolerance,
            stance_knee_max_rad: T::frac_pi_4(),
            knee_range: KneeRange::Reach,
        }
    }

    /// The same solver with another stance-knee flexion cap (clamped to
    /// [0, π/2]: beyond a right angle the stance thigh would point below
    /// the knee's horizontal and the range formulas no longer describe a
    /// standing leg).
    #[must_use]
    pub fn with_stance_knee_max(mut self, max_rad: T) -> Self {
        let v = if max_rad.finite() {
            max_rad
        } else {
            T::frac_pi_4()
        };
        self.stance_knee_max_rad = v.max(T::zero()).min(T::frac_pi_2());
        self
    }

    /// The same solver with these options (the cap clamped as in
    /// [`Self::with_stance_knee_max`]).
    #[must_use]
    pub fn with_options(mut self, options: IkOptions<T>) -> Self {
        self.knee_range = options.knee_range;
        self.with_stance_knee_max(options.stance_knee_max_rad)
    }

    /// The feasible φ2 range [φ2min, φ2max] for a swing-ankle target and φ1
    /// (eq. (qw), (dsfgf), (aaa), (aba), with the defects resolved as in the
    /// module documentation).
    pub fn phi2_range(&self, x5: T, y5: T, phi1: T) -> Result<(T, T), IkError> {
        let [l1, l2, _, l4, l5] = self.l;
        let (s1, c1) = phi1.sin_cos_fast();
        let p1 = [l1 * s1, l1 * c1];
        let dx = x5 - p1[0];
        let dy = y5 - p1[1];
        let dist = (dx * dx + dy * dy).sqrt();
        let leg = l4 + l5;
        let lo = phi1 - self.stance_knee_max_rad;
        if self.knee_range == KneeRange::Human {
            if dist > l2 + leg + self.tolerance * (l2 + leg) {
                return Err(IkError::Unreachable);
            }
            return Ok((lo, phi1));
        }
        // Step 2 first: no circle intersection, the whole human range works.
        if dist + l2 <= leg {
            return Ok((lo, phi1));
        }
        let b1 = (l2 * l2 - leg * leg + dist * dist) / (T::lit(2.0) * dist);
        let rad = l2 * l2 - b1 * b1;
        if rad < -self.tolerance * l2 * l2 {
            return Err(IkError::Unreachable);
        }
        let side = dx.signum();
        if dx == T::zero() {
            return Ok((lo, phi1));
        }
        let b2 = side * rad.max(T::zero()).sqrt();
        // Rotate the unit vector towards p5 by [B1 −B2; B2 B1] (eq. (qw)).
        let ux = dx / dist;
        let uy = dy / dist;
        let vx = b1 * ux - b2 * uy;
        let vy = b2 * ux + b1 * uy;
        // ψ is the standard angle of that vector; φ2 = π/2 − ψ.
        let stretch = T::frac_pi_2() - vy.atan2(vx);
        if side > T::zero() {
            // Foot ahead of the knee: stretch limits how far back the thigh
            // may lean (eq. (aba)).
            Ok((stretch.max(lo), phi1))
        } else {
            // Foot behind the knee: stretch limits how far forward (eq. (aaa)).
            Ok((lo, stretch.min(phi1)))
        }
    }

    /// Solves one target (steps 1–6 of the module documentation).
    ///
    /// Never panics and never returns NaN: every failure is an [`IkError`].
    pub fn solve(&self, target: &IkTarget<T>) -> Result<IkSolution<T>, IkError> {
        let IkTarget {
            x5,
            y5,
            phi1,
            phi3,
            r2,
        } = *target;
        if ![x5, y5, phi1, phi3, r2].iter().all(|v| v.finite()) {
            return Err(IkError::NonFinite);
        }
        if r2 < -self.tolerance || r2 > T::one() + self.tolerance {
            return Err(IkError::RatioOutOfRange);
        }
        let r2 = r2.max(T::zero()).min(T::one());
        let (lo, hi) = self.phi2_range(x5, y5, phi1)?;
        if lo > hi {
            return Err(IkError::EmptyHipRange);
        }
        let phi2 = r2 * hi + (T::one() - r2) * lo;
        let [l1, l2, l3, l4, l5] = self.l;
        let (s1, c1) = phi1.sin_cos_fast();
        let (s2, c2) = phi2.sin_cos_fast();
        let (s3, c3) = phi3.sin_cos_fast();
        let p1 = [l1 * s1, l1 * c1];
        let p2 = [p1[0] + l2 * s2, p1[1] + l2 * c2];
        let p3 = [p2[0] + l3 * s3, p2[1] + l3 * c3];
        // Swing knee: second two-circle intersection (eq. (leell), (dssgf)).
        let ex = x5 - p2[0];
        let ey = y5 - p2[1];
        let de = (ex * ex + ey * ey).sqrt();
        let slack = self.tolerance * (l4 + l5);
        if de > l4 + l5 + slack || de < (l4 - l5).abs() - slack || de <= T::zero() {
            return Err(IkError::SwingLegUnreachable);
        }
        let cc1 = (l4 * l4 - l5 * l5 + de * de) / (T::lit(2.0) * de);
        let cc2 = (l4 * l4 - cc1 * cc1).max(T::zero()).sqrt();
        let ux = ex / de;
        let uy = ey / de;
        let p4 = [p2[0] + cc1 * ux - cc2 * uy, p2[1] + cc2 * ux + cc1 * uy];
        let p5 = [x5, y5];
        // Eq. (dfsadf): φ_i = π/2 − atan2 of the link vector. φ1, φ2, φ3 are
        // the inputs/choices themselves; φ4, φ5 come from the points.
        // φ4 is kept in (0, 2π] around π (the thigh hangs down) and φ5 within
        // ±π of φ4, so the angles stay continuous through any swing the knee
        // can make (atan2 alone would wrap at the backward horizontal).
        let half_pi = T::frac_pi_2();
        let raw4 = half_pi - (p4[1] - p2[1]).atan2(p4[0] - p2[0]);
        let raw5 = half_pi - (p5[1] - p4[1]).atan2(p5[0] - p4[0]);
        let phi4 = T::pi() + wrap_pi(raw4 - T::pi());
        let phi5 = phi4 + wrap_pi(raw5 - phi4);
        let phi = [phi1, phi2, phi3, phi4, phi5];
        if !phi.iter().all(|v| v.finite()) {
            return Err(IkError::NonFinite);
        }
        Ok(IkSolution {
            phi,
            theta: theta_from_phi(&phi),
            points: [p1, p2, p3, p4, p5],
            phi2_range: (lo, hi),
        })
    }
}
