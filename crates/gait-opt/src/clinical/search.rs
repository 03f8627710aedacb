//! The clinical search: the decision vector ([`DIM`] coordinates in a box,
//! [`decode`]d into a [`ClinicalStep`]), its starting point and the seeded,
//! evaluation-budgeted CMA-ES run ([`optimize_clinical`]).

use std::cell::RefCell;

use cmaes::{CMAESOptions, DVector};
use gait_core::clinical::{ClinicalError, ClinicalStep, StartPosture, SwingPath};
use gait_core::kinematics::Phi;

use crate::compass::compass_search;

use super::ClinicalCase;
use super::evaluate::{EvalError, Evaluation, evaluate_phi, step_phi};

/// Free variables of the search.
pub const DIM: usize = 17;

/// Ranges of the start posture and of the curves' deviations.
const PHI1_START: (f64, f64) = (-0.25, 0.35);
const PHI3_START: (f64, f64) = (-0.25, 0.45);
const LIFT: (f64, f64) = (0.05, 0.6);
/// Largest deviation of an interior control value from the straight line
/// between the ends: φ1, φ3 (rad), r2.
const CURVE_SPAN: [f64; 3] = [0.35, 0.35, 0.8];
const PROGRESS: (f64, f64) = (-0.4, 1.4);
const LIFT_HEIGHT: (f64, f64) = (-0.05, 0.2);
/// The paper's rise, m: stairs higher than it widen the swing's lift.
const PAPER_RISE_M: f64 = 0.0935;

/// The swing's lift-height range of a case: [`LIFT_HEIGHT`], its top
/// raised by 2.5 m per m of rise above the paper's stair, so that a foot
/// starting just behind a higher riser can rise over its nosing before it
/// moves on.
fn lift_height(case: &ClinicalCase) -> (f64, f64) {
    let extra = (case.spacing_m[1].abs() - PAPER_RISE_M).max(0.0);
    (LIFT_HEIGHT.0, LIFT_HEIGHT.1 + 2.5 * extra)
}

fn lerp((a, b): (f64, f64), x: f64) -> f64 {
    a + (b - a) * x.clamp(0.0, 1.0)
}

/// The step a point x ∈ [0, 1]^DIM of the search box describes.
pub fn decode(case: &ClinicalCase, x: &[f64; DIM]) -> Result<ClinicalStep<f64>, ClinicalError> {
    let start = StartPosture {
        phi1_rad: lerp(PHI1_START, x[0]),
        phi3_rad: lerp(PHI3_START, x[1]),
        r2: x[2].clamp(0.0, 1.0),
    };
    let mut step = ClinicalStep {
        spacing_m: case.spacing_m,
        step_time_s: case.step_time_s,
        foot: case.foot,
        ik: case.ik,
        start,
        lift_fraction: lerp(LIFT, x[3]),
        curves: [[0.0; 3]; 3],
        path: SwingPath {
            progress: [lerp(PROGRESS, x[13]), lerp(PROGRESS, x[14])],
            lift_m: [
                lerp(lift_height(case), x[15]),
                lerp(lift_height(case), x[16]),
            ],
        },
    };
    let ends = step.ends(&case.model)?;
    for (c, curve) in step.curves.iter_mut().enumerate() {
        let (a, b) = (ends.values[0][c], ends.values[1][c]);
        for (j, v) in curve.iter_mut().enumerate() {
            // Control point j + 2 of 0 … 6 on the straight line, moved.
            let along = a + (b - a) * (j as f64 + 2.0) / 6.0;
            let dev = CURVE_SPAN[c] * (2.0 * x[4 + 3 * c + j].clamp(0.0, 1.0) - 1.0);
            *v = along + dev;
        }
    }
    Ok(step)
}

/// A plausible start of the search: shank upright, torso slightly forward,
/// knee nearly straight, half the step in double support, a plain swing.
pub fn initial_point(case: &ClinicalCase) -> [f64; DIM] {
    let mut x = [0.5; DIM];
    let inv = |(a, b): (f64, f64), v: f64| ((v - a) / (b - a)).clamp(0.0, 1.0);
    x[0] = inv(PHI1_START, 0.0);
    x[1] = inv(PHI3_START, 0.1);
    x[2] = if case.spacing_m[1] < 0.0 { 0.8 } else { 0.3 };
    x[3] = inv(LIFT, 0.35);
    x[13] = inv(PROGRESS, 0.0);
    x[14] = inv(PROGRESS, 1.0);
    let lift = 0.08 + 1.5 * (case.spacing_m[1].abs() - PAPER_RISE_M).max(0.0);
    x[15] = inv(lift_height(case), lift);
    x[16] = inv(lift_height(case), lift);
    x
}

/// The score of a search point: J, or a large value that still ranks
/// failures (a later IK failure is better), plus the distance to the box.
fn score(case: &ClinicalCase, x: &[f64]) -> (f64, Option<Evaluation>) {
    let mut xc = [0.0; DIM];
    let mut outside = 0.0;
    for (o, &v) in xc.iter_mut().zip(x) {
        let c = v.clamp(0.0, 1.0);
        outside += (v - c) * (v - c);
        *o = c;
    }
    let box_pen = 1e5 * outside;
    let result = decode(case, &xc)
        .map_err(EvalError::from)
        .and_then(|step| step_phi(case, &step))
        .and_then(|phi| evaluate_phi(case, &phi));
    match result {
        Ok(ev) => (ev.j + box_pen, Some(ev)),
        Err(EvalError::Step(ClinicalError::Ik { k, .. })) => {
            (1e8 + 1e5 * (1000.0 - k as f64).max(0.0) + box_pen, None)
        }
        Err(_) => (1e9 + box_pen, None),
    }
}

/// Search settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClinicalConfig {
    /// Seed.
    pub seed: u64,
    /// Cost evaluations in all.
    pub max_evals: usize,
}

impl Default for ClinicalConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            max_evals: 12_000,
        }
    }
}

/// What the search found.
#[derive(Clone, Debug, PartialEq)]
pub struct ClinicalResult {
    /// The best point of the box.
    pub x: [f64; DIM],
    /// Its step.
    pub step: ClinicalStep<f64>,
    /// Its Φ samples.
    pub phi: Vec<Phi<f64>>,
    /// Its evaluation.
    pub evaluation: Evaluation,
    /// Evaluations used.
    pub evaluations: usize,
}

/// Why the search failed.
#[derive(Clone, Debug, PartialEq)]
pub enum ClinicalSearchError {
    /// The CMA-ES library refused its options.
    Cmaes(String),
    /// No point could be evaluated.
    NoFeasiblePoint,
}

impl std::fmt::Display for ClinicalSearchError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Cmaes(m) => write!(f, "CMA-ES: {m}"),
            Self::NoFeasiblePoint => f.write_str("no point of the box could be evaluated"),
        }
    }
}

impl std::error::Error for ClinicalSearchError {}

struct Best {
    evals: usize,
    best: Option<(f64, [f64; DIM])>,
}

/// Minimises the clinical cost of `case`: CMA-ES from [`initial_point`]
/// (σ 0.2), then runs from the best point with a smaller step and a
/// doubled population (IPOP), then a compass search. Deterministic.
pub fn optimize_clinical(
    case: &ClinicalCase,
    config: &ClinicalConfig,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<ClinicalResult, ClinicalSearchError> {
    let state = RefCell::new(Best {
        evals: 0,
        best: None,
    });
    let polish_budget = config.max_evals / 6;
    let cma_budget = config.max_evals - polish_budget;
    let objective = |x: &DVector<f64>| {
        let (v, _) = score(case, x.as_slice());
        let mut s = state.borrow_mut();
        s.evals += 1;
        if s.best.is_none_or(|(b, _)| v < b) {
            let mut xb = [0.0; DIM];
            for (o, &vi) in xb.iter_mut().zip(x.iter()) {
                *o = vi.clamp(0.0, 1.0);
            }
            s.best = Some((v, xb));
        }
        v
    };
    let default_lambda = 4 + (3.0 * (DIM as f64).ln()).floor() as usize;
    let mut lambda = default_lambda;
    let mut sigma = 0.2;
    let mut run = 0u64;
    while state.borrow().evals + 20 * lambda <= cma_budget {
        let mean = state
            .borrow()
            .best
            .map_or_else(|| initial_point(case), |(_, x)| x);
        let left = cma_budget - state.borrow().evals;
        let mut cma = CMAESOptions::new(mean.to_vec(), sigma)
            .population_size(lambda)
            .seed(
                config
                    .seed
                    .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                    .wrapping_add(run),
            )
            .max_function_evals(left)
            .tol_fun(1e-4)
            .tol_x(1e-6)
            .build(objective)
            .map_err(|e| ClinicalSearchError::Cmaes(format!("{e:?}")))?;
        loop {
            let done = cma.next();
            let s = state.borrow();
            progress(s.evals, s.best.map_or(f64::INFINITY, |(b, _)| b));
            if done.is_some() || s.evals + lambda > cma_budget {
                break;
            }
        }
        run += 1;
        lambda *= 2;
        sigma = 0.05;
    }
    // Compass search around the best point.
    let Some((fbest, x)) = state.borrow().best else {
        return Err(ClinicalSearchError::NoFeasiblePoint);
    };
    let mut evals = state.borrow().evals;
    let budget = config.max_evals.saturating_sub(evals);
    let (x, _, _) = compass_search(
        &mut evals,
        x,
        fbest,
        1e-5,
        budget,
        |evals, y| {
            *evals += 1;
            score(case, y).0
        },
        |evals, f| progress(*evals, f),
    );
    let step_found = decode(case, &x).map_err(|_| ClinicalSearchError::NoFeasiblePoint)?;
    let phi = step_phi(case, &step_found).map_err(|_| ClinicalSearchError::NoFeasiblePoint)?;
    let evaluation = evaluate_phi(case, &phi).map_err(|_| ClinicalSearchError::NoFeasiblePoint)?;
    Ok(ClinicalResult {
        x,
        step: step_found,
        phi,
        evaluation,
        evaluations: evals,
    })
}
