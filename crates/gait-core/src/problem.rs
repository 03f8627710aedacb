//! The paper's optimisation problem (section IV-B, eq. (dground)–(argcost)),
//! pinned down as "paper mode": every constant the paper leaves open is fixed
//! here, so that a J computed anywhere can be recomputed and compared.
//!
//! - P in the paper's row order, SI units; bounds B ≼ P ≼ U of eq. (cons)
//!   with the millimetre values converted (+300 mm → +0.3 m, 600 → 0.6 m);
//!   interior time control points non-decreasing.
//! - Sampling: Δt = 0.01 s, N = round(ts/Δt), 2,001-point u grid, linear
//!   interpolation in t; (x5, y5) is the path evaluated at z(t_k).
//! - Derivatives by eq. (ee2) backward differences, so τ_k exists for k ≥ 2.
//! - J = (1/(N−1)) Σ_{k=2…N} c_k τ_k² + v_p max_{k=1…N} ‖p5(k) − p5(k−1)‖/Δt,
//!   v_p = 1000 N²·m² per (m/s), τ = T_θ1, c_k of eq. (dground) with 2 mm.
//!
//! Lives in gait-core (no_std, generic scalar) so that the board can one day
//! re-plan a step from the ankle angle it measures; only the search is on
//! the host (crates/gait-opt).

use crate::foot::StanceFoot;
use crate::gait::{
    CONTACT_THRESHOLD_M, CONTROL_ROWS, ControlPoints, Differences, GaitError, Sampling,
    StanceAnkleProfile, Step, StepEvent, contact_weight, evaluate_step,
};
use crate::ik::{IkOptions, IkSolver, IkTarget, KneeRange};
use crate::kinematics::swap_legs;
use crate::model::BodyModel;
use crate::scalar::Real;

/// The paper's velocity weight v_p, N²·m² per (m/s).
pub const PAPER_VELOCITY_WEIGHT: f64 = 1000.0;

/// The two cases of the paper's experiments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PaperCase {
    /// Level walking: 600 mm stride, 2.24 s step.
    Walk,
    /// Stair ascent: 93.5 mm rise, 275 mm tread, 2.28 s step.
    StairUp,
}

/// One swing step's boundary conditions and assumptions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepCase<T> {
    /// Swing-ankle start (x5(0), y5(0)), m.
    pub start_m: [T; 2],
    /// Swing-ankle landing (x5(ts), y5(ts)), m.
    pub landing_m: [T; 2],
    /// Step time ts, s.
    pub step_time_s: T,
    /// Assumed stance-ankle profile φ1(t).
    pub stance: StanceAnkleProfile<T>,
    /// r2 at the start of the swing.
    pub r2_start: T,
    /// Torso angle φ3 at the start of the swing, rad.
    pub phi3_start_rad: T,
    /// The posture the step must land in, when fixed (periodic steps);
    /// `None` in the paper's cases, where r2(ts) and φ3(ts) are free.
    pub end_posture: Option<EndPosture<T>>,
    /// The step starts and ends at rest: r2, φ3 and the pace z have zero
    /// rate at t = 0 and t = ts (their second and second-to-last control
    /// values equal the end values), so the swing ankle's speed is zero at
    /// lift-off and landing. `false` in the paper's cases, whose optima
    /// leave the standing posture with a jump in joint speed.
    pub rest_at_ends: bool,
    /// The stance foot's toe rocker ([`crate::foot`]): the step's stance
    /// heel lifts once φ1 passes its stop, and the path's (x5, y5) are in
    /// the flat foot's frame. `None`: the paper's pinned, flat foot.
    pub foot: Option<StanceFoot<T>>,
    /// How the IK chooses the stance thigh (paper: [`IkOptions::paper`]).
    pub ik: IkOptions<T>,
}

/// r2 and φ3 at the landing, fixed by eq. (cons) with equal bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EndPosture<T> {
    /// r2(ts).
    pub r2: T,
    /// φ3(ts), rad.
    pub phi3_rad: T,
}

/// What defines a step that can repeat with the legs alternating.
///
/// In double support the posture has three degrees of freedom once both
/// feet are placed: the stance shank φ1, the torso φ3 and the knee choice
/// r2. A step is *periodic* when its landing posture, seen from the new
/// stance foot ([`crate::kinematics::swap_legs`]), is its start posture:
/// then the next step starts exactly where this one ended and the weight
/// transfer between steps moves no joint. The paper's cases are not
/// periodic (the walk lands with the new stance shank 0.3 rad ahead of where
/// the next step starts), so every transfer has to move the body backwards
/// over the new stance foot — through the crutches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeriodicStep<T> {
    /// The front ankle relative to the back one in double support, m
    /// (walk: (half the swing ankle's travel, 0); stair ascent: (tread,
    /// rise)). The swing ankle starts at −spacing and lands at +spacing.
    pub spacing_m: [T; 2],
    /// Step time ts, s.
    pub step_time_s: T,
    /// Stance shank φ1 at the start, rad.
    pub phi1_start_rad: T,
    /// r2 at the start.
    pub r2_start: T,
    /// Torso angle at the start and at the landing, rad.
    pub phi3_rad: T,
    /// Steepness k of the stance-shank logistic, 1/s.
    pub k_per_s: T,
    /// Midpoint t_c of the logistic, s.
    pub t_c_s: T,
    /// The feet's toe rocker (`None`: flat, pinned feet). With it, a
    /// trailing foot whose shank leans past the stop stands on its toe in
    /// double support, its ankle raised ([`crate::foot`]).
    pub foot: Option<StanceFoot<T>>,
    /// How the IK chooses the stance thigh (paper: [`IkOptions::paper`]).
    pub ik: IkOptions<T>,
}

impl<T: Real> PeriodicStep<T> {
    /// Level walking as the device plays it: the paper's step (the swing
    /// ankle travels 0.6 m, from 0.3 m behind to 0.3 m ahead),
    /// step time (2.24 s), logistic shape (k, t_c) and stance shank at the
    /// start (φ1(0) = −0.0932 rad, the paper profile's value), upright torso,
    /// and r2(0) = 1 (the paper's 0.94 would land with the trailing ankle at
    /// 16.8° of dorsiflexion, 1.2° inside the supervisor's envelope; r2 = 1
    /// lands at 10.9°).
    pub fn walk() -> Self {
        let l = T::lit;
        Self {
            spacing_m: [l(0.3), l(0.0)],
            step_time_s: l(2.24),
            phi1_start_rad: l(-0.0932),
            r2_start: l(1.0),
            phi3_rad: l(0.0),
            k_per_s: l(0.5638),
            t_c_s: l(2.24),
            foot: Some(StanceFoot::table_i()),
            ik: IkOptions::paper(),
        }
    }

    /// Stair ascent as the device plays it: the paper's stair (tread
    /// 0.275 m, rise 0.0935 m), step time (2.28 s), logistic shape, r2(0) =
    /// 0.5 and φ1(0) = 0.0017 rad (the paper profile's start). The paper's
    /// profile ends at 0.158 rad; the periodic landing needs 0.162 rad.
    pub fn stair_up() -> Self {
        let l = T::lit;
        Self {
            spacing_m: [l(0.275), l(0.0935)],
            step_time_s: l(2.28),
            phi1_start_rad: l(0.0017),
            r2_start: l(0.5),
            phi3_rad: l(0.0),
            k_per_s: l(4.0),
            t_c_s: l(1.14),
            foot: Some(StanceFoot::table_i()),
            ik: IkOptions::paper(),
        }
    }

    /// Stair descent, which the paper does not treat: the paper's stair
    /// (tread 0.275 m, rise 0.0935 m) walked down, the swing ankle going from
    /// the tread above the stance foot to the one below. The trailing foot
    /// stands on its toe in double support (with both feet flat its ankle
    /// would need about 30° of dorsiflexion; Table I allows 20°), so the
    /// stance heel lifts during the step. φ1(0), r2(0), (k, t_c) and ts are
    /// this project's choices (`docs/model.md`, "Stair descent").
    pub fn stair_down() -> Self {
        let l = T::lit;
        Self {
            spacing_m: [l(0.275), l(-0.0935)],
            step_time_s: l(STAIR_DOWN_STEP_S),
            phi1_start_rad: l(STAIR_DOWN_PHI1_START_RAD),
            r2_start: l(STAIR_DOWN_R2_START),
            phi3_rad: l(0.0),
            k_per_s: l(STAIR_DOWN_K_PER_S),
            t_c_s: l(STAIR_DOWN_T_C_S),
            foot: Some(StanceFoot::table_i()),
            ik: IkOptions {
                stance_knee_max_rad: l(STAIR_DOWN_KNEE_MAX_DEG.to_radians()),
                knee_range: KneeRange::Human,
            },
        }
    }
}

/// Stair descent's stance-knee cap, degrees: the trailing knee of the
/// double-support posture bends 60° (Table I allows 100°).
const STAIR_DOWN_KNEE_MAX_DEG: f64 = 90.0;

/// Stair descent's step time, s.
const STAIR_DOWN_STEP_S: f64 = 2.28;
/// Stair descent's stance shank at the start, rad.
const STAIR_DOWN_PHI1_START_RAD: f64 = 0.0;
/// Stair descent's r2 at the start.
const STAIR_DOWN_R2_START: f64 = 0.9;
/// Stair descent's logistic steepness, 1/s.
const STAIR_DOWN_K_PER_S: f64 = 4.0;
/// Stair descent's logistic midpoint, s.
const STAIR_DOWN_T_C_S: f64 = 1.14;

/// Why no periodic case exists for a [`PeriodicStep`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PeriodicError {
    /// The start posture has no IK solution.
    Start(crate::ik::IkError),
    /// The landing posture (the start seen from the other foot) lies outside
    /// the IK's human range: no r2 in [0, 1] describes it.
    LandingOutsideHumanRange,
    /// The logistic's shape (k, t_c) is flat over [0, ts] or not finite.
    FlatProfile,
    /// The trailing foot's raised ankle and its shank's lean did not settle
    /// on one posture (the secant iteration did not converge).
    TrailingFootNotSettled,
}

impl core::fmt::Display for PeriodicError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Start(e) => write!(f, "start posture: {e}"),
            Self::LandingOutsideHumanRange => {
                f.write_str("the landing posture is outside the IK's human range")
            }
            Self::FlatProfile => f.write_str("the stance-shank logistic is flat over the step"),
            Self::TrailingFootNotSettled => {
                f.write_str("the trailing foot's heel-up posture did not converge")
            }
        }
    }
}

impl<T: Real> StepCase<T> {
    /// The paper-mode case definitions.
    ///
    /// Walk: (−0.3, 0) → (0.3, 0) m, ts = 2.24 s, φ1 logistic
    /// (a, b, k, t_c) = (−0.3335 rad, 0.7564 rad, 0.5638 1/s, 2.24 s)
    /// (fitted to the walking baseline's stance shank), r2(0) = 0.94.
    /// Stair-up: (−0.275, −0.0935) → (0.275, 0.0935) m (stance foot on the
    /// first step), ts = 2.28 s, φ1 (0, 0.16 rad, 4.0 1/s, 1.14 s), r2(0) = 0.5.
    /// φ3(0) = 0 in both.
    pub fn paper(case: PaperCase) -> Self {
        let l = T::lit;
        match case {
            PaperCase::Walk => Self {
                start_m: [l(-0.3), l(0.0)],
                landing_m: [l(0.3), l(0.0)],
                step_time_s: l(2.24),
                stance: StanceAnkleProfile {
                    a_rad: l(-0.3335),
                    b_rad: l(0.7564),
                    k_per_s: l(0.5638),
                    t_c_s: l(2.24),
                },
                r2_start: l(0.94),
                phi3_start_rad: l(0.0),
                end_posture: None,
                rest_at_ends: false,
                foot: None,
                ik: IkOptions::paper(),
            },
            PaperCase::StairUp => Self {
                start_m: [l(-0.275), l(-0.0935)],
                landing_m: [l(0.275), l(0.0935)],
                step_time_s: l(2.28),
                stance: StanceAnkleProfile {
                    a_rad: l(0.0),
                    b_rad: l(0.16),
                    k_per_s: l(4.0),
                    t_c_s: l(1.14),
                },
                r2_start: l(0.5),
                phi3_start_rad: l(0.0),
                end_posture: None,
                rest_at_ends: false,
                foot: None,
                ik: IkOptions::paper(),
            },
        }
    }
}

impl<T: Real> StepCase<T> {
    /// The periodic case of `p` for `model`: start (−spacing) and landing
    /// (+spacing); the landing posture is the start posture with the legs
    /// swapped, which fixes φ1(ts), r2(ts) and φ3(ts). The stance-shank
    /// logistic keeps the shape (k, t_c) and its asymptotes are solved so
    /// that φ1(0) and φ1(ts) are the two postures' stance-shank angles.
    pub fn periodic(p: &PeriodicStep<T>, model: &BodyModel<T>) -> Result<Self, PeriodicError> {
        let ik = IkSolver::new(model).with_options(p.ik);
        let [sx, sy] = p.spacing_m;
        let ankle = |phi1: T| p.foot.map_or([T::zero(); 2], |f| f.ankle(phi1).position_m);
        let stance_ankle = ankle(p.phi1_start_rad);
        // The trailing (swing) foot stands at −spacing; on its toe its ankle
        // is raised by how far its own shank leans past the stop, which the
        // posture decides: lean = g(lean), solved by the secant method on
        // g(lean) − lean (bounded at 40 rounds; it converges in a few where
        // the plain fixed-point iteration can crawl).
        let solve = |lean: T| {
            let a = ankle(lean);
            let trailing = [a[0] - sx, a[1] - sy];
            ik.solve(&IkTarget {
                x5: trailing[0] - stance_ankle[0],
                y5: trailing[1] - stance_ankle[1],
                phi1: p.phi1_start_rad,
                phi3: p.phi3_rad,
                r2: p.r2_start,
            })
            .map(|sol| (trailing, sol))
            .map_err(PeriodicError::Start)
        };
        let residual = |lean: T| -> Result<T, PeriodicError> {
            let (_, sol) = solve(lean)?;
            Ok(swap_legs(&sol.phi)[0] - lean)
        };
        let flat_lean = swap_legs(&solve(T::lit(-10.0))?.1.phi)[0];
        // 1.5e-10 rad in f64, 3.5e-6 rad in f32 (the IK's own round-off).
        let tolerance = T::default_epsilon().sqrt() * T::lit(1e-2);
        let (mut x0, mut r0) = (flat_lean, residual(flat_lean)?);
        let mut x1 = x0 + r0;
        let mut lean = (r0.abs() <= tolerance).then_some(x0);
        for _ in 0..40 {
            if lean.is_some() {
                break;
            }
            let r1 = residual(x1)?;
            if r1.abs() <= tolerance {
                lean = Some(x1);
            } else if (r1 - r0).abs() > T::zero() {
                let next = x1 - r1 * (x1 - x0) / (r1 - r0);
                (x0, r0, x1) = (x1, r1, next);
            } else {
                break;
            }
        }
        let lean = lean.ok_or(PeriodicError::TrailingFootNotSettled)?;
        let (swing_start, start) = solve(lean)?;
        let landing = swap_legs(&start.phi);
        let [phi1_end, phi2_end, ..] = landing;
        // At the landing the old stance foot trails; its ankle may be up.
        let end_ankle = ankle(phi1_end);
        let (lo, hi) = ik
            .phi2_range(sx - end_ankle[0], sy - end_ankle[1], phi1_end)
            .map_err(|_| PeriodicError::LandingOutsideHumanRange)?;
        let r2_end = if hi - lo > ik.tolerance {
            (phi2_end - lo) / (hi - lo)
        } else if (phi2_end - hi).abs() <= ik.tolerance {
            T::one()
        } else {
            return Err(PeriodicError::LandingOutsideHumanRange);
        };
        if !(r2_end >= -ik.tolerance && r2_end <= T::one() + ik.tolerance) {
            return Err(PeriodicError::LandingOutsideHumanRange);
        }
        let r2_end = r2_end.max(T::zero()).min(T::one());
        let sigma = |t: T| T::one() / (T::one() + (-p.k_per_s * (t - p.t_c_s)).exp());
        let (s0, s1) = (sigma(T::zero()), sigma(p.step_time_s));
        let span = s1 - s0;
        if !span.finite() || span.abs() < T::lit(1e-6) {
            return Err(PeriodicError::FlatProfile);
        }
        let width = (phi1_end - p.phi1_start_rad) / span;
        let a = p.phi1_start_rad - width * s0;
        Ok(Self {
            start_m: swing_start,
            landing_m: [sx, sy],
            step_time_s: p.step_time_s,
            stance: StanceAnkleProfile {
                a_rad: a,
                b_rad: a + width,
                k_per_s: p.k_per_s,
                t_c_s: p.t_c_s,
            },
            r2_start: p.r2_start,
            phi3_start_rad: p.phi3_rad,
            end_posture: Some(EndPosture {
                r2: r2_end,
                phi3_rad: p.phi3_rad,
            }),
            rest_at_ends: true,
            foot: p.foot,
            ik: p.ik,
        })
    }
}

/// The value of J and its parts.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Cost<T> {
    /// J = torque + velocity.
    pub j: T,
    /// (1/(N−1)) Σ c_k τ_k², N²·m².
    pub torque: T,
    /// v_p · max ‖Δp5‖/Δt.
    pub velocity: T,
    /// The joint-motion term: [`JointMotionLimit`] and [`JointRangeLimit`]
    /// (0 without them, as in the paper).
    pub joint_motion: T,
    /// max_k ‖p5(k) − p5(k−1)‖/Δt, m/s.
    pub peak_ankle_speed_m_s: T,
    /// RMS of τ over the swing samples (c_k = 1), N·m.
    pub tau_rms_nm: T,
    /// Peak |τ| over the swing samples (c_k = 1), N·m.
    pub tau_peak_nm: T,
    /// Number of samples with c_k = 1.
    pub swing_samples: usize,
}

/// Why P is outside the feasible set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Infeasible {
    /// Entry (row, column) of P violates B ≼ P ≼ U.
    Bound {
        /// Row of P.
        row: usize,
        /// Column of P (0 = time or x, 1 = value or y).
        col: usize,
    },
    /// The interior time control points of a curve decrease (row of the
    /// second point of the offending pair).
    TimeOrder {
        /// Row of P.
        row: usize,
    },
    /// Sampling or IK failed (see [`GaitError`]).
    Gait(GaitError),
}

impl From<GaitError> for Infeasible {
    fn from(e: GaitError) -> Self {
        Self::Gait(e)
    }
}

impl core::fmt::Display for Infeasible {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Bound { row, col } => write!(f, "P[{row}][{col}] is outside its bounds"),
            Self::TimeOrder { row } => write!(f, "time control points decrease at row {row}"),
            Self::Gait(e) => write!(f, "{e}"),
        }
    }
}

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

impl<T: Real> JointRangeLimit<T> {
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

/// The reference problem: a case, the model, the sampling and v_p.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaperProblem<T> {
    /// Boundary conditions and assumptions of the step.
    pub case: StepCase<T>,
    /// Body model.
    pub model: BodyModel<T>,
    /// Time sampling.
    pub sampling: Sampling<T>,
    /// Velocity weight v_p.
    pub velocity_weight: T,
    /// Derivative scheme (paper: backward, eq. (ee2)).
    pub differences: Differences,
    /// Soft joint speed and acceleration limits (`None` in paper mode).
    pub joint_motion_limit: Option<JointMotionLimit<T>>,
    /// Soft joint-range limit (`None` in paper mode); counted in
    /// [`Cost::joint_motion`].
    pub joint_range_limit: Option<JointRangeLimit<T>>,
    /// Count τ² at every sample, also within 2 mm of the start and the
    /// landing (c_k = 1 throughout). `false` in paper mode. For steps that
    /// start and end at rest the foot lingers near the ground, and with the
    /// paper's c_k whatever the body does then is free.
    pub count_every_sample: bool,
}

/// Rows of P holding r2(ts) and φ3(ts) (the last control point of each).
const R2_END_ROW: usize = 4;
const PHI3_END_ROW: usize = 9;

/// Rows of P whose time column must be non-decreasing, per curve
/// (r2: 0–4, φ3: 5–9, z: 15–18).
const TIME_CURVES: [(usize, usize); 3] = [(0, 5), (5, 10), (15, 19)];

impl<T: Real> PaperProblem<T> {
    /// Paper mode for a case with Table III.
    pub fn paper(case: PaperCase) -> Self {
        Self::new(StepCase::paper(case), BodyModel::paper_table_iii())
    }

    /// Paper-mode definitions for any step case and model.
    pub fn new(case: StepCase<T>, model: BodyModel<T>) -> Self {
        Self {
            case,
            sampling: Sampling::paper(case.step_time_s),
            model,
            velocity_weight: T::lit(PAPER_VELOCITY_WEIGHT),
            differences: Differences::Backward,
            joint_motion_limit: None,
            joint_range_limit: None,
            count_every_sample: false,
        }
    }

    /// Eq. (cons): the lower and upper bound matrices (B, U), SI units.
    pub fn bounds(&self) -> (ControlPoints<T>, ControlPoints<T>) {
        let c = &self.case;
        let ts = c.step_time_s;
        let (z, one) = (T::zero(), T::one());
        let [x0, y0] = c.start_m;
        let [xs, ys] = c.landing_m;
        let lift = T::lit(0.3);
        let top = T::lit(0.6);
        let tilt = T::lit(core::f64::consts::PI / 12.0);
        let mut lo: ControlPoints<T> = [
            [z, c.r2_start],
            [z, z],
            [z, z],
            [z, z],
            [ts, z],
            [z, c.phi3_start_rad],
            [z, -tilt],
            [z, -tilt],
            [z, -tilt],
            [ts, -tilt],
            [x0, y0],
            [x0, y0 + lift],
            [x0, y0.min(ys)],
            [xs, ys + lift],
            [xs, ys],
            [z, z],
            [z, z],
            [z, z],
            [ts, one],
        ];
        let mut hi: ControlPoints<T> = [
            [z, c.r2_start],
            [ts, one],
            [ts, one],
            [ts, one],
            [ts, one],
            [z, c.phi3_start_rad],
            [ts, tilt],
            [ts, tilt],
            [ts, tilt],
            [ts, tilt],
            [x0, y0],
            [x0, top],
            [xs, top],
            [xs, top],
            [xs, ys],
            [z, z],
            [ts, one],
            [ts, one],
            [ts, one],
        ];
        let mut pin = |row: usize, v: T| {
            for m in [&mut lo, &mut hi] {
                if let Some(cell) = m.get_mut(row).and_then(|r| r.get_mut(1)) {
                    *cell = v;
                }
            }
        };
        if let Some(end) = c.end_posture {
            pin(R2_END_ROW, end.r2);
            pin(PHI3_END_ROW, end.phi3_rad);
            if c.rest_at_ends {
                pin(R2_END_ROW - 1, end.r2);
                pin(PHI3_END_ROW - 1, end.phi3_rad);
            }
        }
        if c.rest_at_ends {
            // Second control value = first: zero rate at t = 0; z's
            // second-to-last = 1: zero pace at the landing.
            pin(1, c.r2_start);
            pin(6, c.phi3_start_rad);
            pin(16, z);
            pin(17, one);
            // The rate is zero at an end only if the neighbouring time
            // control point is away from it (with t1 = t0 the ratio of the
            // two derivatives is 0/0 and its limit is not zero); keep the
            // neighbours a tenth of the step inside.
            let margin = ts * T::lit(0.1);
            for row in [1, 6, 16] {
                if let Some(cell) = lo.get_mut(row).and_then(|r| r.get_mut(0)) {
                    *cell = margin;
                }
            }
            for row in [3, 8, 17] {
                if let Some(cell) = hi.get_mut(row).and_then(|r| r.get_mut(0)) {
                    *cell = ts - margin;
                }
            }
        }
        (lo, hi)
    }

    /// Checks B ≼ P ≼ U (with a relative slack for rounding) and that each
    /// curve's time control points are non-decreasing.
    pub fn check_feasible(&self, p: &ControlPoints<T>) -> Result<(), Infeasible> {
        let (lo, hi) = self.bounds();
        let slack = T::lit(1e-9);
        for (row, ((pr, lr), hr)) in p.iter().zip(&lo).zip(&hi).enumerate() {
            for (col, ((&v, &l), &h)) in pr.iter().zip(lr).zip(hr).enumerate() {
                let tol = slack * (T::one() + l.abs().max(h.abs()));
                if !v.finite() || v < l - tol || v > h + tol {
                    return Err(Infeasible::Bound { row, col });
                }
            }
        }
        for (start, end) in TIME_CURVES {
            for row in start + 1..end {
                let (Some(a), Some(b)) = (p.get(row - 1), p.get(row)) else {
                    continue;
                };
                if b[0] < a[0] {
                    return Err(Infeasible::TimeOrder { row });
                }
            }
        }
        Ok(())
    }

    /// The step that P describes under this problem's assumptions.
    pub fn step(&self, p: &ControlPoints<T>) -> Step<T> {
        Step {
            control: *p,
            stance: self.case.stance,
            sampling: self.sampling,
            foot: self.case.foot,
            ik: self.case.ik,
        }
    }

    /// Eq. (cost): J(P) and its parts, after checking feasibility.
    pub fn cost(&self, p: &ControlPoints<T>) -> Result<Cost<T>, Infeasible> {
        self.check_feasible(p)?;
        self.cost_unchecked(p)
    }

    /// J(P) without the bound checks (sampling and IK are still checked).
    /// For evaluating human-data baselines, which need not respect eq. (cons).
    pub fn cost_unchecked(&self, p: &ControlPoints<T>) -> Result<Cost<T>, Infeasible> {
        let step = self.step(p);
        let n = self.sampling.intervals;
        if n + 1 > MAX_SAMPLES {
            return Err(Infeasible::Gait(GaitError::BadSampling));
        }
        let dt = self.sampling.dt_s;
        // One pass: the path's speed from every sample, and (p5, τ) of every
        // dynamics sample kept until p5(N) is known for c_k.
        let mut first: Option<[T; 2]> = None;
        let mut prev: Option<[T; 2]> = None;
        let mut peak_speed = T::zero();
        let mut taus: heapless::Vec<([T; 2], T), MAX_SAMPLES> = heapless::Vec::new();
        let mut joint_motion = T::zero();
        let limit = self.joint_motion_limit;
        let range = self.joint_range_limit;
        evaluate_step::<T, Infeasible>(&self.model, &step, self.differences, |ev| {
            match ev {
                StepEvent::Sample(s) => {
                    if first.is_none() {
                        first = Some(s.p5);
                    }
                    if let Some(q) = prev {
                        let dx = s.p5[0] - q[0];
                        let dy = s.p5[1] - q[1];
                        peak_speed = peak_speed.max((dx * dx + dy * dy).sqrt() / dt);
                    }
                    prev = Some(s.p5);
                }
                StepEvent::Dynamics(d) => {
                    if let Some(r) = &range {
                        joint_motion += r.penalty(&d.phi);
                    }
                    if let Some(l) = &limit {
                        joint_motion += l.penalty(&d.dphi, Some(&d.ddphi));
                        // The first interval's rate is in no dynamics
                        // sample; with backward differences it is
                        // Φ̇(k−1) = Φ̇(k) − Φ̈(k)·Δt at the first one.
                        if taus.is_empty() && self.differences == Differences::Backward {
                            let mut first_rate = d.dphi;
                            for (r, &a) in first_rate.iter_mut().zip(&d.ddphi) {
                                *r -= a * dt;
                            }
                            joint_motion += l.penalty(&first_rate, None);
                        }
                    }
                    // Capacity was checked against N above.
                    let _ = taus.push((d.gait.p5, d.torque[0]));
                }
            }
            Ok(())
        })?;
        let (Some(start), Some(landing)) = (first, prev) else {
            return Err(Infeasible::Gait(GaitError::BadSampling));
        };
        let threshold = T::lit(CONTACT_THRESHOLD_M);
        let mut sum_sq = T::zero();
        let mut peak_tau = T::zero();
        let mut swing = 0usize;
        for &(p5, tau) in &taus {
            if self.count_every_sample || contact_weight(p5, start, landing, threshold) > T::zero()
            {
                sum_sq += tau * tau;
                peak_tau = peak_tau.max(tau.abs());
                swing += 1;
            }
        }
        let denom = T::lit(n.saturating_sub(1).max(1) as f64);
        let torque = sum_sq / denom;
        let velocity = self.velocity_weight * peak_speed;
        let tau_rms = if swing > 0 {
            (sum_sq / T::lit(swing as f64)).sqrt()
        } else {
            T::zero()
        };
        Ok(Cost {
            j: torque + velocity + joint_motion,
            torque,
            velocity,
            joint_motion,
            peak_ankle_speed_m_s: peak_speed,
            tau_rms_nm: tau_rms,
            tau_peak_nm: peak_tau,
            swing_samples: swing,
        })
    }
}

/// Most samples one step may have (N + 1): 5.11 s at Δt = 0.01 s.
pub const MAX_SAMPLES: usize = 512;

/// Number of rows of P (re-exported for callers that flatten it).
pub const ROWS: usize = CONTROL_ROWS;

impl<T: Real> PaperProblem<T> {
    /// A simple feasible P: evenly spaced times, constant r2 and φ3, a path
    /// lifted by the bounds' minimum clearance and a linear pace. A starting
    /// point for searches and a fixture for tests, not a good gait.
    pub fn initial_guess(&self) -> ControlPoints<T> {
        let c = &self.case;
        let ts = c.step_time_s;
        let q = |i: f64, n: f64| T::lit(i / n) * ts;
        let [x0, y0] = c.start_m;
        let [xs, ys] = c.landing_m;
        let lift = T::lit(0.3);
        let half = T::lit(0.5);
        let r2 = c.r2_start;
        let p3 = c.phi3_start_rad;
        // A fixed landing posture is reached by a linear blend of the
        // values; otherwise they stay constant.
        let (r2e, p3e) = c.end_posture.map_or((r2, p3), |e| (e.r2, e.phi3_rad));
        // Blend weights of the middle control values: linear, or flat at
        // both ends when the step must start and end at rest.
        let w: [f64; 3] = if c.rest_at_ends {
            [0.0, 0.5, 1.0]
        } else {
            [0.25, 0.5, 0.75]
        };
        let mix = |a: T, b: T, i: usize| a + T::lit(w.get(i).copied().unwrap_or(0.5)) * (b - a);
        let (z1, z2) = if c.rest_at_ends {
            (T::zero(), T::one())
        } else {
            (T::lit(1.0 / 3.0), T::lit(2.0 / 3.0))
        };
        [
            [q(0.0, 4.0), r2],
            [q(1.0, 4.0), mix(r2, r2e, 0)],
            [q(2.0, 4.0), mix(r2, r2e, 1)],
            [q(3.0, 4.0), mix(r2, r2e, 2)],
            [ts, r2e],
            [q(0.0, 4.0), p3],
            [q(1.0, 4.0), mix(p3, p3e, 0)],
            [q(2.0, 4.0), mix(p3, p3e, 1)],
            [q(3.0, 4.0), mix(p3, p3e, 2)],
            [ts, p3e],
            [x0, y0],
            [x0, y0 + lift],
            [(x0 + xs) * half, (y0 + ys) * half + lift],
            [xs, ys + lift],
            [xs, ys],
            [T::zero(), T::zero()],
            [q(1.0, 3.0), z1],
            [q(2.0, 3.0), z2],
            [ts, T::one()],
        ]
    }
}
