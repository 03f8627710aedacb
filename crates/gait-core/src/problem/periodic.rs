//! Steps that repeat with the legs alternating ([`PeriodicStep`]): the
//! device's walk and stairs, whose landing posture is their start posture
//! seen from the other foot, and the [`StepCase`] each one fixes.

use super::{EndPosture, StepCase};
use crate::foot::StanceFoot;
use crate::gait::StanceAnkleProfile;
use crate::ik::{IkOptions, IkSolver, IkTarget, KneeRange};
use crate::kinematics::swap_legs;
use crate::model::BodyModel;
use crate::scalar::Real;

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
