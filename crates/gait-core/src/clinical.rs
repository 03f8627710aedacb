//! Clinical steps: the device's own gait description, for tables that
//! lighten the pilot's arms on the drives it has (the paper's description
//! is kept, untouched, for paper mode in [`crate::problem`]).
//!
//! What differs from the paper, and why (`docs/optimiser.md`, "Clinical
//! mode"):
//!
//! - **Double support first.** The swing foot stays planted for the first
//!   `lift_fraction` of the step while the body shifts over the stance foot
//!   (the ground under both feet carries it, not the crutches); then it
//!   lifts and swings. The paper's step lifts the foot at once, so the body
//!   has to travel over the stance ankle in single support, on the pilot's
//!   arms.
//! - **Smooth curves in time.** φ1 (the stance shank, a decision variable
//!   here, not an assumed logistic), φ3 and r2 are Bézier polynomials of
//!   t/ts with rest at both ends; the swing path is a Bézier of the time
//!   since lift-off, with rest at lift-off and landing. No time control
//!   points, so no monotonicity to enforce and no kinks.
//! - **The IK's continuous knee range** ([`KneeRange::Human`]): r2 is the
//!   stance knee's flexion as a fraction of its cap.
//! - **Periodic**: the landing posture is the start posture seen from the
//!   other foot ([`StepCase::periodic`]), so steps chain and the weight
//!   transfer between them moves nothing.
//!
//! Sampled at the tables' 10 ms into Φ by the IK, streamed (no heap).

use crate::bezier::Bezier;
use crate::foot::StanceFoot;
use crate::ik::{IkError, IkOptions, IkSolver, IkTarget};
use crate::kinematics::Phi;
use crate::model::BodyModel;
use crate::playback::swing_toe;
use crate::problem::{PeriodicError, PeriodicStep, StepCase};
use crate::scalar::Real;

/// A rise smaller than this is level walking, m.
pub const LEVEL_RISE_M: f64 = 0.005;
/// How far behind the riser ahead of it the trailing foot's toe stands, m.
pub const TOE_BEHIND_RISER_M: f64 = 0.015;
/// The heel's length behind the ankle, m (the sole runs from here to the
/// toe; Winter's proportions, as [`crate::foot::TOE_M`]).
pub const HEEL_M: f64 = 0.05;

/// Where the staircase a step of `spacing` (tread, rise) climbs or
/// descends has its riser just behind the stance foot, as x from the
/// stance ankle, m; `None` on level ground. Just ahead of the trailing
/// foot's toe, which stands [`TOE_BEHIND_RISER_M`] behind it (on the floor
/// going up, on the top floor's edge going down); the stance foot stands on
/// the tread beyond, its heel well on it. The simulator lays its staircases
/// out by this rule.
pub fn riser_behind_stance_x<T: Real>(spacing: [T; 2], foot: &StanceFoot<T>) -> Option<T> {
    let [tread, rise] = spacing;
    if rise.abs() < T::lit(LEVEL_RISE_M) {
        None
    } else {
        Some(-tread + foot.toe_m + T::lit(TOE_BEHIND_RISER_M))
    }
}

/// The ground's level under `x` (from the stance ankle) in the ankle-level
/// convention (where an ankle standing there is), relative to the stance
/// foot's, for a step of `spacing` on its staircase
/// ([`riser_behind_stance_x`]) or on level ground, m.
pub fn ground_level<T: Real>(spacing: [T; 2], foot: &StanceFoot<T>, x: T) -> T {
    let [tread, rise] = spacing;
    match riser_behind_stance_x(spacing, foot) {
        None => T::zero(),
        Some(riser) => rise * ((x - riser) / tread).floor(),
    }
}

/// Rounds of the planted trailing foot's ankle (rolling about its toe):
/// the ankle's offset changes by less than 1 mm per 0.1 rad of lean, so
/// each round shrinks the error tenfold or more.
const PLANTED_ROUNDS: usize = 4;

/// Control values of each time curve: start, start (rest), three free,
/// end (rest), end: a degree-6 Bézier of t/ts.
pub const CURVE_POINTS: usize = 7;
/// Free interior control values per time curve.
pub const CURVE_FREE: usize = 3;

/// The start posture of a periodic step in double support.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StartPosture<T> {
    /// Stance shank φ1, rad.
    pub phi1_rad: T,
    /// Torso φ3, rad.
    pub phi3_rad: T,
    /// Knee choice r2 (the stance knee's flexion over its cap).
    pub r2: T,
}

/// The swing path's shape between lift-off and landing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwingPath<T> {
    /// Interior control values of the forward progress (0 at lift-off, 1 at
    /// landing; a degree-5 Bézier [0, 0, a, b, 1, 1] of the swing time).
    pub progress: [T; 2],
    /// Heights of the two interior vertical control points above the start
    /// and the landing point, m (a degree-5 Bézier [y0, y0, y0 + h1,
    /// y1 + h2, y1, y1]).
    pub lift_m: [T; 2],
}

/// A clinical step: geometry, timing, start posture and curve shapes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClinicalStep<T> {
    /// The front ankle relative to the back one in double support, m.
    pub spacing_m: [T; 2],
    /// Step time ts, s.
    pub step_time_s: T,
    /// The feet's toe rocker.
    pub foot: StanceFoot<T>,
    /// The IK's options (the human knee range and its cap).
    pub ik: IkOptions<T>,
    /// The posture at the start (and, seen from the other foot, at the
    /// landing).
    pub start: StartPosture<T>,
    /// Share of the step with the swing foot planted, 0 … 1.
    pub lift_fraction: T,
    /// Interior control values of φ1(t), φ3(t), r2(t).
    pub curves: [[T; CURVE_FREE]; 3],
    /// The swing path's shape.
    pub path: SwingPath<T>,
}

/// Why a clinical step cannot be sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ClinicalError {
    /// The start posture has no periodic case.
    Periodic(PeriodicError),
    /// The IK has no posture at a sample.
    Ik {
        /// Sample index.
        k: usize,
        /// The IK's reason.
        error: IkError,
    },
    /// Step time, sample period or lift fraction unusable, or a value not
    /// finite.
    BadParameters,
}

/// The boundary conditions a start posture fixes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ends<T> {
    /// Swing-ankle start and landing (stance foot's flat frame), m.
    pub start_m: [T; 2],
    /// Landing point, m.
    pub landing_m: [T; 2],
    /// (φ1, φ3, r2) at the start and at the landing.
    pub values: [[T; 3]; 2],
}

impl<T: Real> ClinicalStep<T> {
    /// The start and landing points and postures of this step's periodic
    /// case.
    pub fn ends(&self, model: &BodyModel<T>) -> Result<Ends<T>, ClinicalError> {
        let ts = self.step_time_s;
        let periodic = PeriodicStep {
            spacing_m: self.spacing_m,
            step_time_s: ts,
            phi1_start_rad: self.start.phi1_rad,
            r2_start: self.start.r2,
            phi3_rad: self.start.phi3_rad,
            // Only the postures are used; any non-flat logistic will do.
            k_per_s: T::lit(4.0) / ts,
            t_c_s: ts * T::lit(0.5),
            foot: Some(self.foot),
            ik: self.ik,
        };
        let case = StepCase::periodic(&periodic, model).map_err(ClinicalError::Periodic)?;
        let end = case.end_posture.ok_or(ClinicalError::Periodic(
            PeriodicError::LandingOutsideHumanRange,
        ))?;
        Ok(Ends {
            start_m: case.start_m,
            landing_m: case.landing_m,
            values: [
                [self.start.phi1_rad, self.start.phi3_rad, self.start.r2],
                [case.stance.at(ts), end.phi3_rad, end.r2],
            ],
        })
    }

    /// Streams Φ at t_k = k·`dt_s`, k = 0 … round(ts/dt), to `visit`.
    /// Bounded: one IK per sample.
    pub fn for_each_sample<E>(
        &self,
        model: &BodyModel<T>,
        dt_s: T,
        mut visit: impl FnMut(usize, &Phi<T>) -> Result<(), E>,
    ) -> Result<(), E>
    where
        E: From<ClinicalError>,
    {
        let ts = self.step_time_s;
        let lift = self.lift_fraction;
        let ok = |v: T| v.finite();
        if !(ok(ts) && ok(dt_s) && ok(lift))
            || ts <= T::zero()
            || dt_s <= T::zero()
            || lift < T::zero()
            || lift >= T::one()
            || !self.curves.iter().flatten().all(|v| v.finite())
        {
            return Err(ClinicalError::BadParameters.into());
        }
        let n = (ts / dt_s).round().to_f64();
        if !(2.0..=4096.0).contains(&n) {
            return Err(ClinicalError::BadParameters.into());
        }
        let n = n as usize;
        let ends = self.ends(model)?;
        let [[f1, f3, fr], [t1, t3, tr]] = ends.values;
        let curve = |a: T, b: T, [c1, c2, c3]: [T; CURVE_FREE]| {
            let v = [a, a, c1, c2, c3, b, b];
            let mut points = [[T::zero(); 2]; CURVE_POINTS];
            for (j, (p, &value)) in points.iter_mut().zip(&v).enumerate() {
                *p = [T::lit(j as f64 / (CURVE_POINTS - 1) as f64), value];
            }
            Bezier::new(points)
        };
        let [c_phi1, c_phi3, c_r2] = self.curves;
        let curves: [Bezier<T, CURVE_POINTS>; 3] = [
            curve(f1, t1, c_phi1),
            curve(f3, t3, c_phi3),
            curve(fr, tr, c_r2),
        ];
        let ik = IkSolver::new(model).with_options(self.ik);
        let values = |t: T| -> [T; 3] {
            let s = (t / ts).min(T::one());
            curves.map(|c| c.eval(s)[1])
        };
        let solve = |k: usize, [phi1, phi3, r2]: [T; 3], ankle_target: [T; 2]| {
            let ankle = self.foot.ankle(phi1).position_m;
            ik.solve(&IkTarget {
                x5: ankle_target[0] - ankle[0],
                y5: ankle_target[1] - ankle[1],
                phi1,
                phi3,
                r2: r2.max(T::zero()).min(T::one()),
            })
            .map(|sol| sol.phi)
            .map_err(|error| ClinicalError::Ik { k, error })
        };
        // Double support: the swing foot stays planted. Its toe stays where
        // it started while the ankle rolls about it (a trailing foot whose
        // shank leans past the stop stands on its toe): the ankle target
        // depends on the lean the IK gives, found in a few rounds.
        let start_phi = solve(0, values(T::zero()), ends.start_m)?;
        let toe_start = swing_toe(model, &self.foot, &start_phi);
        let planted = |k: usize, v: [T; 3], guess: &Phi<T>| -> Result<Phi<T>, ClinicalError> {
            let mut phi = *guess;
            for _ in 0..PLANTED_ROUNDS {
                let [.., phi5] = phi;
                let lean = crate::kinematics::wrap_pi(phi5 - T::pi());
                let toe = self.foot.toe();
                let a = self.foot.ankle(lean).position_m;
                let target = [toe_start[0] - toe[0] + a[0], toe_start[1] - toe[1] + a[1]];
                phi = solve(k, v, target)?;
            }
            Ok(phi)
        };
        let t_lift = lift * ts;
        let lift_phi = planted(0, values(t_lift), &start_phi)?;
        let [x0, y0] = crate::playback::swing_ankle(model, &self.foot, &lift_phi);
        let [x1, y1] = ends.landing_m;
        let [pa, pb] = self.path.progress;
        let [h1, h2] = self.path.lift_m;
        let path: Bezier<T, 6> = Bezier::new([
            [T::zero(), y0],
            [T::zero(), y0],
            [pa, y0 + h1],
            [pb, y1 + h2],
            [T::one(), y1],
            [T::one(), y1],
        ]);
        let mut last = start_phi;
        for k in 0..=n {
            let t = T::lit(k as f64) * dt_s;
            let v = values(t);
            let phi = if t < t_lift {
                planted(k, v, &last)?
            } else {
                let sigma = ((t - t_lift) / (ts - t_lift)).max(T::zero()).min(T::one());
                let [progress, y5] = path.eval(sigma);
                solve(k, v, [x0 + (x1 - x0) * progress, y5])?
            };
            visit(k, &phi)?;
            last = phi;
        }
        Ok(())
    }
}
