//! J evaluated from a sequence of absolute angles Φ(t_k), k = 0…N, instead
//! of from control points: for human-data baselines, which are angle
//! trajectories and need no IK.
//!
//! Only the samples are made here: swing-ankle position by forward
//! kinematics, eq. (ee2) backward differences (τ_k for k ≥ 2), τ = T_θ1
//! from `inverse_dynamics` + `joint_torques`. J itself,
//! J = (1/(N−1)) Σ_{k=2…N} c_k τ_k² + v_p max_{k=1…N} ‖p5(k) − p5(k−1)‖/Δt
//! with c_k = 0 within 2 mm of p5(0) or p5(N), is gait-core's
//! `CostAccumulator`, which `PaperProblem::cost` feeds too. Cross-checked
//! against `PaperProblem::cost` on optimised steps (tests).

use gait_core::dynamics::{Contact, inverse_dynamics};
use gait_core::kinematics::{Phi, forward_kinematics, joint_torques};
use gait_core::problem::{Cost, CostAccumulator, CostSample, MAX_SAMPLES, PaperProblem};

/// Why a Φ sequence cannot be evaluated.
#[derive(Clone, Debug, PartialEq)]
pub enum PhiCostError {
    /// The sequence must hold N + 1 samples (N = the problem's intervals).
    Length {
        /// Samples expected.
        expected: usize,
        /// Samples given.
        got: usize,
    },
    /// Sample `k` holds a NaN or infinite angle.
    NonFinite {
        /// Sample index.
        k: usize,
    },
    /// More samples than the cost can hold (gait-core's `MAX_SAMPLES`).
    TooMany {
        /// Most samples the cost holds.
        max: usize,
        /// Samples given.
        got: usize,
    },
}

impl std::fmt::Display for PhiCostError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Length { expected, got } => {
                write!(f, "expected {expected} angle samples (N + 1), got {got}")
            }
            Self::NonFinite { k } => write!(f, "sample {k} holds a non-finite angle"),
            Self::TooMany { max, got } => {
                write!(f, "at most {max} angle samples fit the cost, got {got}")
            }
        }
    }
}

impl std::error::Error for PhiCostError {}

/// The per-sample quantities of a Φ sequence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhiSample {
    /// Swing-ankle position p5 by forward kinematics, m.
    pub p5: [f64; 2],
    /// Joint torques T_Θ, N·m (None for k < 2, where eq. (ee2) has no
    /// second difference).
    pub torque: Option<[f64; 5]>,
    /// Φ̇ by the backward difference (None for k = 0).
    pub dphi: Option<Phi<f64>>,
    /// Φ̈ by the backward difference (None for k < 2).
    pub ddphi: Option<Phi<f64>>,
}

/// Evaluates every sample of `phi` (positions and torques).
pub fn phi_samples(problem: &PaperProblem<f64>, phi: &[Phi<f64>]) -> Vec<PhiSample> {
    let inv_dt = 1.0 / problem.sampling.dt_s;
    let mut out = Vec::with_capacity(phi.len());
    let mut prev_dphi: Option<Phi<f64>> = None;
    let mut prev: Option<&Phi<f64>> = None;
    for p in phi {
        // With the toe rocker the stance ankle moves (docs/model.md).
        let foot = problem.case.foot;
        let ankle = foot.map_or([0.0; 2], |f| f.ankle(p[0]).position_m);
        let fk = forward_kinematics(&problem.model, p)[4];
        let p5 = [fk[0] + ankle[0], fk[1] + ankle[1]];
        let mut torque = None;
        let mut rates = None;
        let mut accels = None;
        if let Some(q) = prev {
            let mut dphi = [0.0; 5];
            for ((d, &a), &b) in dphi.iter_mut().zip(p).zip(q) {
                *d = (a - b) * inv_dt;
            }
            if let Some(pd) = prev_dphi {
                let mut ddphi = [0.0; 5];
                for ((d, &a), &b) in ddphi.iter_mut().zip(&dphi).zip(&pd) {
                    *d = (a - b) * inv_dt;
                }
                accels = Some(ddphi);
                torque = Some(joint_torques(&inverse_dynamics(
                    &problem.model,
                    &Contact::from(foot),
                    p,
                    &dphi,
                    &ddphi,
                )));
            }
            rates = Some(dphi);
            prev_dphi = Some(dphi);
        }
        prev = Some(p);
        out.push(PhiSample {
            p5,
            torque,
            dphi: rates,
            ddphi: accels,
        });
    }
    out
}

/// J and its parts from Φ(t_k), k = 0…N (see the module documentation):
/// the samples of [`phi_samples`] fed to gait-core's [`CostAccumulator`],
/// the same computation as `PaperProblem::cost`.
pub fn cost_from_phi(
    problem: &PaperProblem<f64>,
    phi: &[Phi<f64>],
) -> Result<Cost<f64>, PhiCostError> {
    let n = problem.sampling.intervals;
    if phi.len() != n + 1 || n < 2 {
        return Err(PhiCostError::Length {
            expected: n + 1,
            got: phi.len(),
        });
    }
    if let Some(k) = phi.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(PhiCostError::NonFinite { k });
    }
    let too_many = |_| PhiCostError::TooMany {
        max: MAX_SAMPLES,
        got: phi.len(),
    };
    let mut acc = CostAccumulator::new(problem).map_err(too_many)?;
    let samples = phi_samples(problem, phi);
    // Φ̇ of the first interval (k = 1), which no dynamics sample holds.
    let first_rate = samples.get(1).and_then(|s| s.dphi);
    for (s, p) in samples.iter().zip(phi) {
        acc.position(s.p5);
        if let (Some(torque), Some(dphi), Some(ddphi)) = (s.torque, s.dphi, s.ddphi) {
            let sample = CostSample {
                p5: s.p5,
                phi: p,
                dphi: &dphi,
                ddphi: &ddphi,
                ankle_torque_nm: torque[0],
            };
            acc.dynamics(&sample, || first_rate);
        }
    }
    acc.finish().map_err(too_many)
}
