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
//!
//! One concern per file: `case` (the step's boundary conditions),
//! `periodic` (steps that repeat), `bounds` (eq. (cons), the feasible set),
//! `cost` (eq. (cost), J from samples) and `limits` (the device tables'
//! soft limits). Their items are re-exported here.

mod bounds;
mod case;
mod cost;
mod limits;
mod periodic;

pub use bounds::{BoundsMismatch, Infeasible, TIME_ORDERED_ROWS};
pub use case::{EndPosture, PaperCase, StepCase};
pub use cost::{Cost, CostAccumulator, CostSample, MAX_SAMPLES};
pub use limits::{JointMotionLimit, JointRangeLimit, LimitError};
pub use periodic::{PeriodicError, PeriodicStep};

use crate::gait::{CONTROL_ROWS, ControlPoints, Differences, Sampling, Step};
use crate::model::BodyModel;
use crate::scalar::Real;

/// The paper's velocity weight v_p, N²·m² per (m/s).
pub const PAPER_VELOCITY_WEIGHT: f64 = 1000.0;

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
}

/// Number of rows of P (re-exported for callers that flatten it).
pub const ROWS: usize = CONTROL_ROWS;
