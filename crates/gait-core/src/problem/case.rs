//! The step a problem describes: the paper's two cases and the boundary
//! conditions and assumptions ([`StepCase`]) every problem is built from.

use crate::foot::StanceFoot;
use crate::gait::StanceAnkleProfile;
use crate::ik::IkOptions;
use crate::scalar::Real;

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
