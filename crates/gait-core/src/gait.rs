//! The Bézier gait description of one swing step and its sampling in time
//! (paper section IV-A).
//!
//! A step is the paper's 19×2 control-point matrix P (rows 0–4 (t, r2),
//! 5–9 (t, φ3), 10–14 (x5, y5), 15–18 (t, z)), in SI units. Time is itself a
//! Bézier coordinate, so a value at time t is found by evaluating the curve
//! on a fine grid of u and interpolating linearly in t; the swing-ankle path
//! is evaluated at the pace variable z(t). The stance ankle φ1 is not
//! controlled by the exoskeleton and follows an assumed logistic profile.
//!
//! Everything streams: no sample is stored, so the same code evaluates a
//! step on the board (no heap) and inside the optimiser's inner loop.

use crate::bezier::Bezier;
use crate::dynamics::Contact;
use crate::foot::StanceFoot;
use crate::ik::{IkError, IkOptions, IkSolution, IkSolver, IkTarget};
use crate::kinematics::{Phi, joint_torques};
use crate::model::{BodyModel, LINKS};
use crate::scalar::Real;

mod control_points;

pub use control_points::{
    CONTROL_ROWS, ControlPoints, CurveRows, PACE_ROWS, PATH_ROWS, PHI3_ROWS, R2_ROWS,
};

/// Which Bézier curve of a step (for error reports).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Curve {
    /// (t, r2), rows 0–4.
    R2,
    /// (t, φ3), rows 5–9.
    Phi3,
    /// (t, z), rows 15–18.
    Pace,
}

/// Why a step could not be sampled or evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GaitError {
    /// A control point or parameter is NaN or infinite.
    NonFinite,
    /// Time step, step time, grid size or sample count unusable.
    BadSampling,
    /// The curve's time coordinate t(u) decreases somewhere on the grid:
    /// time would run backwards (the paper's bounds alone allow this).
    TimeNotMonotonic(Curve),
    /// The IK has no posture at sample `k`.
    Ik {
        /// Sample index.
        k: usize,
        /// The IK's reason.
        error: IkError,
    },
}

impl core::fmt::Display for GaitError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NonFinite => f.write_str("a control point or parameter is not finite"),
            Self::BadSampling => f.write_str("unusable sampling (time step, step time or grid)"),
            Self::TimeNotMonotonic(c) => write!(f, "time runs backwards along the {c:?} curve"),
            Self::Ik { k, error } => write!(f, "sample {k}: {error}"),
        }
    }
}

/// The assumed stance-ankle angle during the swing (paper section IV-A):
/// φ1(t) = a + (b − a) / (1 + e^(−k (t − t_c))).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StanceAnkleProfile<T> {
    /// Lower asymptote a, rad.
    pub a_rad: T,
    /// Upper asymptote b, rad.
    pub b_rad: T,
    /// Steepness k, 1/s.
    pub k_per_s: T,
    /// Midpoint t_c, s.
    pub t_c_s: T,
}

impl<T: Real> StanceAnkleProfile<T> {
    /// φ1 at time `t` (s after the swing starts).
    pub fn at(&self, t: T) -> T {
        self.a_rad
            + (self.b_rad - self.a_rad) / (T::one() + (-self.k_per_s * (t - self.t_c_s)).exp())
    }
}

/// The contact indicator c() of eq. (dground): 0 while the swing ankle is
/// within `threshold` (the paper's 2 mm) of its start or landing point.
pub fn contact_weight<T: Real>(p5: [T; 2], start: [T; 2], landing: [T; 2], threshold: T) -> T {
    let near = |q: [T; 2]| {
        let dx = p5[0] - q[0];
        let dy = p5[1] - q[1];
        dx * dx + dy * dy <= threshold * threshold
    };
    if near(start) || near(landing) {
        T::zero()
    } else {
        T::one()
    }
}

/// The paper's contact threshold, 2 mm.
pub const CONTACT_THRESHOLD_M: f64 = 0.002;

/// Most samples one step may have (N + 1): 5.11 s at Δt = 0.01 s. The
/// cost keeps one (p5, τ) pair per sample ([`crate::problem::CostAccumulator`]).
pub const MAX_SAMPLES: usize = 512;

/// Why a [`Sampling`] is refused ([`Sampling::new`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SamplingError {
    /// Δt is not finite and > 0 s.
    Period,
    /// N is not within 2..=MAX_SAMPLES − 1.
    Intervals,
    /// The u grid has fewer than 2 points.
    Grid,
}

impl core::fmt::Display for SamplingError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Period => f.write_str("the sample period must be finite and > 0 s"),
            Self::Intervals => write!(
                f,
                "the number of intervals N must be in 2..={}",
                MAX_SAMPLES.saturating_sub(1)
            ),
            Self::Grid => f.write_str("the u grid must have at least 2 points"),
        }
    }
}

/// How a step is turned into time samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling<T> {
    /// Sample period Δt, s (the paper: 0.01 s).
    pub dt_s: T,
    /// Number of intervals N; samples are t_k = k Δt, k = 0…N.
    pub intervals: usize,
    /// Points of the uniform u grid each curve is evaluated on (≥ 2).
    pub grid: usize,
}

impl<T: Real> Sampling<T> {
    /// A sampling, checked: Δt finite and > 0 s, 2 ≤ N and N + 1 ≤
    /// [`MAX_SAMPLES`], at least 2 grid points.
    pub fn new(dt_s: T, intervals: usize, grid: usize) -> Result<Self, SamplingError> {
        if !(dt_s.finite() && dt_s > T::zero()) {
            return Err(SamplingError::Period);
        }
        if intervals < 2 || intervals.saturating_add(1) > MAX_SAMPLES {
            return Err(SamplingError::Intervals);
        }
        if grid < 2 {
            return Err(SamplingError::Grid);
        }
        Ok(Self {
            dt_s,
            intervals,
            grid,
        })
    }

    /// The paper's sampling for a step of `step_time_s`: Δt = 0.01 s,
    /// N = round(ts / Δt), 2,001 grid points.
    pub fn paper(step_time_s: T) -> Self {
        let dt = T::lit(0.01);
        let n = (step_time_s / dt).round().to_f64();
        Self {
            dt_s: dt,
            intervals: if n.is_finite() && n > 0.0 {
                n as usize
            } else {
                0
            },
            grid: 2001,
        }
    }

    fn check(&self) -> Result<(), GaitError> {
        if !self.dt_s.finite() || self.dt_s <= T::zero() || self.intervals < 2 || self.grid < 2 {
            return Err(GaitError::BadSampling);
        }
        Ok(())
    }
}

/// Finds the value of a (t, v) Bézier curve at non-decreasing times by
/// walking its u grid once (linear interpolation in t between grid points).
#[derive(Clone, Copy, Debug)]
struct TimeWalker<T, const N: usize> {
    curve: Bezier<T, N>,
    which: Curve,
    step: T,
    tol: T,
    last: usize,
    j: usize,
    prev: [T; 2],
    cur: [T; 2],
}

impl<T: Real, const N: usize> TimeWalker<T, N> {
    fn new(control: [[T; 2]; N], grid: usize, which: Curve) -> Self {
        let curve = Bezier::new(control);
        let first = curve.eval(T::zero());
        let last = grid.saturating_sub(1).max(1);
        // Rounding in the Horner sums may make a flat stretch of t(u) wobble
        // by a few ulp; only a decrease beyond that counts as time reversal.
        let span = control
            .iter()
            .fold(T::zero(), |m, p| m.max(p[0].abs()))
            .max(T::one());
        Self {
            curve,
            which,
            step: T::one() / T::lit(last as f64),
            tol: T::default_epsilon() * T::lit(64.0) * span,
            last,
            j: 0,
            prev: first,
            cur: first,
        }
    }

    fn advance(&mut self) -> Result<bool, GaitError> {
        if self.j >= self.last {
            return Ok(false);
        }
        self.j += 1;
        let u = if self.j == self.last {
            T::one()
        } else {
            T::lit(self.j as f64) * self.step
        };
        self.prev = self.cur;
        self.cur = self.curve.eval(u);
        if self.cur[0] < self.prev[0] - self.tol {
            return Err(GaitError::TimeNotMonotonic(self.which));
        }
        Ok(true)
    }

    /// The curve's value at time `t` (callers pass non-decreasing t):
    /// interpolated between the first grid point with t_j ≥ t and the one
    /// before it; held at the ends.
    fn at(&mut self, t: T) -> Result<T, GaitError> {
        while self.cur[0] < t {
            if !self.advance()? {
                break;
            }
        }
        if self.j == 0 || self.cur[0] <= t {
            return Ok(self.cur[1]);
        }
        let dt = self.cur[0] - self.prev[0];
        if dt <= T::zero() {
            return Ok(self.cur[1]);
        }
        let w = (t - self.prev[0]) / dt;
        Ok(self.prev[1] + w * (self.cur[1] - self.prev[1]))
    }

    /// Walks the rest of the grid so that time reversal anywhere is caught.
    fn finish(&mut self) -> Result<(), GaitError> {
        while self.advance()? {}
        Ok(())
    }
}

/// The gait variables at one time sample (before IK).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GaitSample<T> {
    /// Sample index k.
    pub k: usize,
    /// Time t_k = k Δt, s.
    pub t_s: T,
    /// Knee-choice ratio r2.
    pub r2: T,
    /// Torso angle φ3, rad.
    pub phi3: T,
    /// Pace variable z.
    pub z: T,
    /// Swing-ankle target (x5, y5), m.
    pub p5: [T; 2],
    /// Assumed stance-ankle angle φ1, rad.
    pub phi1: T,
    /// Where the stance ankle is: the origin while the foot is flat, on its
    /// circle about the toe once the heel is up ([`crate::foot`]), m.
    pub stance_ankle_m: [T; 2],
}

impl<T: Real> GaitSample<T> {
    /// The posture this sample asks for: the IK at its (x5, y5, φ1, φ3, r2),
    /// with an IK failure reported against the sample's index.
    pub fn solve(&self, ik: &IkSolver<T>) -> Result<IkSolution<T>, GaitError> {
        // The IK works from the stance ankle; the path is in the flat
        // foot's frame.
        ik.solve(&IkTarget {
            x5: self.p5[0] - self.stance_ankle_m[0],
            y5: self.p5[1] - self.stance_ankle_m[1],
            phi1: self.phi1,
            phi3: self.phi3,
            r2: self.r2,
        })
        .map_err(|error| GaitError::Ik { k: self.k, error })
    }
}

/// A step: control points, the stance-ankle profile and the sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step<T> {
    /// The control-point matrix P.
    pub control: ControlPoints<T>,
    /// The assumed φ1(t).
    pub stance: StanceAnkleProfile<T>,
    /// Time sampling.
    pub sampling: Sampling<T>,
    /// The stance foot's toe rocker, or `None` for the paper's flat foot
    /// (pinned ankle).
    pub foot: Option<StanceFoot<T>>,
    /// How the IK chooses the stance thigh (paper: [`IkOptions::paper`]).
    /// Stair descent lands on a stance knee bent past 45° and needs the
    /// continuous [`crate::ik::KneeRange::Human`].
    pub ik: IkOptions<T>,
}

fn rows<T: Copy, const N: usize>(p: &ControlPoints<T>, start: usize) -> Option<[[T; 2]; N]> {
    let slice = p.get(start..start + N)?;
    <[[T; 2]; N]>::try_from(slice).ok()
}

impl<T: Real> Step<T> {
    /// The IK solver this step's samples are solved with.
    pub fn ik(&self, model: &BodyModel<T>) -> IkSolver<T> {
        IkSolver::new(model).with_options(self.ik)
    }

    /// The swing-ankle path (x5, y5) as a curve of z (rows 10–14).
    pub fn path(&self) -> Option<Bezier<T, 5>> {
        rows::<T, 5>(&self.control, PATH_ROWS.start()).map(Bezier::new)
    }

    /// Streams the samples k = 0…N in order to `visit`, stopping at the first
    /// error (from sampling or from `visit`). Bounded: 3 × grid curve
    /// evaluations plus N + 1 calls.
    pub fn for_each_sample<E>(
        &self,
        mut visit: impl FnMut(&GaitSample<T>) -> Result<(), E>,
    ) -> Result<(), E>
    where
        E: From<GaitError>,
    {
        self.sampling.check()?;
        if !self.control.iter().flatten().all(|v| v.finite()) {
            return Err(GaitError::NonFinite.into());
        }
        let grid = self.sampling.grid;
        let (Some(r2c), Some(phc), Some(zc), Some(path)) = (
            rows::<T, 5>(&self.control, R2_ROWS.start()),
            rows::<T, 5>(&self.control, PHI3_ROWS.start()),
            rows::<T, 4>(&self.control, PACE_ROWS.start()),
            self.path(),
        ) else {
            return Err(GaitError::BadSampling.into());
        };
        let mut r2w = TimeWalker::new(r2c, grid, Curve::R2);
        let mut phw = TimeWalker::new(phc, grid, Curve::Phi3);
        let mut zw = TimeWalker::new(zc, grid, Curve::Pace);
        for k in 0..=self.sampling.intervals {
            let t = T::lit(k as f64) * self.sampling.dt_s;
            let z = zw.at(t)?;
            let phi1 = self.stance.at(t);
            let sample = GaitSample {
                k,
                t_s: t,
                r2: r2w.at(t)?,
                phi3: phw.at(t)?,
                z,
                p5: path.eval(z),
                phi1,
                stance_ankle_m: self
                    .foot
                    .map_or([T::zero(); 2], |f| f.ankle(phi1).position_m),
            };
            visit(&sample)?;
        }
        r2w.finish()?;
        phw.finish()?;
        zw.finish()?;
        Ok(())
    }
}

/// How joint velocities and accelerations are estimated from sampled angles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Differences {
    /// Eq. (ee2): Φ̇(k) = (Φ(k) − Φ(k−1))/Δt, Φ̈(k) = (Φ̇(k) − Φ̇(k−1))/Δt;
    /// exists for k ≥ 2 (the paper's choice; lags by about one sample).
    Backward,
    /// Central: Φ̇(k) = (Φ(k+1) − Φ(k−1))/2Δt,
    /// Φ̈(k) = (Φ(k+1) − 2Φ(k) + Φ(k−1))/Δt²; exists for 1 ≤ k ≤ N−1.
    Central,
}

impl Differences {
    /// The scheme's name in reports: "backward" or "central".
    pub const fn name(self) -> &'static str {
        match self {
            Self::Backward => "backward",
            Self::Central => "central",
        }
    }

    /// The scheme of a report's name ([`Differences::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        [Self::Backward, Self::Central]
            .into_iter()
            .find(|d| d.name() == name)
    }
}

/// One evaluated sample: posture, rates and torques.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DynamicSample<T> {
    /// The gait variables.
    pub gait: GaitSample<T>,
    /// Absolute angles Φ, rad.
    pub phi: Phi<T>,
    /// Φ̇, rad/s.
    pub dphi: Phi<T>,
    /// Φ̈, rad/s².
    pub ddphi: Phi<T>,
    /// Relative angles Θ, rad.
    pub theta: Phi<T>,
    /// Joint torques T_Θ, N·m; `[0]` is the stance pivot torque τ = T_θ1
    /// (about the ankle, or about the toe once the heel is up).
    pub torque: [T; LINKS],
}

/// What [`evaluate_step`] reports, in time order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepEvent<'a, T> {
    /// Every sample k = 0…N, as soon as it is sampled (and solved by IK).
    Sample(&'a GaitSample<T>),
    /// A sample whose derivatives exist (k ≥ 2 backward, 1 ≤ k ≤ N−1
    /// central), with posture, rates and torques.
    Dynamics(&'a DynamicSample<T>),
}

/// Evaluates a step: IK at every sample, finite differences, inverse
/// dynamics, joint torques, streamed to `visit` as [`StepEvent`]s.
pub fn evaluate_step<T: Real, E: From<GaitError>>(
    model: &BodyModel<T>,
    step: &Step<T>,
    differences: Differences,
    mut visit: impl FnMut(StepEvent<'_, T>) -> Result<(), E>,
) -> Result<(), E> {
    let ik = step.ik(model);
    let dt = step.sampling.dt_s;
    let inv_dt = T::one() / dt;
    // Window of the last three samples (oldest first).
    let mut window: [Option<(GaitSample<T>, Phi<T>)>; 3] = [None, None, None];
    let mut prev_dphi: Option<Phi<T>> = None;
    step.for_each_sample(|s| {
        let sol = s.solve(&ik)?;
        visit(StepEvent::Sample(s))?;
        window = [window[1], window[2], Some((*s, sol.phi))];
        // The sample the window gives derivatives of, with them.
        let derived = match differences {
            Differences::Backward => {
                let (Some((_, p1)), Some((g2, p2))) = (window[1], window[2]) else {
                    return Ok(());
                };
                let dphi = zip_map(&p2, &p1, |a, b| (a - b) * inv_dt);
                let ddphi = prev_dphi.map(|prev| zip_map(&dphi, &prev, |a, b| (a - b) * inv_dt));
                prev_dphi = Some(dphi);
                ddphi.map(|ddphi| (g2, p2, dphi, ddphi))
            }
            Differences::Central => {
                let (Some((_, p0)), Some((g1, p1)), Some((_, p2))) =
                    (window[0], window[1], window[2])
                else {
                    return Ok(());
                };
                let half = inv_dt * T::lit(0.5);
                let dphi = zip_map(&p2, &p0, |a, b| (a - b) * half);
                let mut ddphi = [T::zero(); LINKS];
                for (((o, &a), &b), &c) in ddphi.iter_mut().zip(&p2).zip(&p1).zip(&p0) {
                    *o = (a - b - b + c) * inv_dt * inv_dt;
                }
                Some((g1, p1, dphi, ddphi))
            }
        };
        let Some((g, phi, dphi, ddphi)) = derived else {
            return Ok(());
        };
        visit(StepEvent::Dynamics(&dynamic_sample(
            model,
            step.foot.as_ref(),
            g,
            phi,
            dphi,
            ddphi,
        )))
    })
}

fn dynamic_sample<T: Real>(
    model: &BodyModel<T>,
    foot: Option<&StanceFoot<T>>,
    gait: GaitSample<T>,
    phi: Phi<T>,
    dphi: Phi<T>,
    ddphi: Phi<T>,
) -> DynamicSample<T> {
    let contact = Contact::from(foot.copied());
    let t_phi = crate::dynamics::inverse_dynamics(model, &contact, &phi, &dphi, &ddphi);
    let torque = joint_torques(&t_phi);
    DynamicSample {
        gait,
        phi,
        dphi,
        ddphi,
        theta: crate::kinematics::theta_from_phi(&phi),
        torque,
    }
}

fn zip_map<T: Real>(a: &Phi<T>, b: &Phi<T>, f: impl Fn(T, T) -> T) -> Phi<T> {
    let mut o = [T::zero(); LINKS];
    for ((oi, &x), &y) in o.iter_mut().zip(a).zip(b) {
        *oi = f(x, y);
    }
    o
}
