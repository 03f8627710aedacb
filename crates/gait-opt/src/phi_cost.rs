//! J evaluated from a sequence of absolute angles Φ(t_k), k = 0…N, instead
//! of from control points: for human-data baselines, which are angle
//! trajectories and need no IK.
//!
//! The same definitions as `PaperProblem::cost_unchecked`: swing-ankle
//! position by forward kinematics, eq. (ee2) backward differences (τ_k for
//! k ≥ 2), τ = T_θ1 from `inverse_dynamics` + `joint_torques`,
//! J = (1/(N−1)) Σ_{k=2…N} c_k τ_k² + v_p max_{k=1…N} ‖p5(k) − p5(k−1)‖/Δt,
//! c_k = 0 within 2 mm of p5(0) or p5(N). Cross-checked against
//! `PaperProblem::cost` on optimised steps (tests).

use gait_core::gait::{CONTACT_THRESHOLD_M, contact_weight};
use gait_core::kinematics::{Phi, forward_kinematics, joint_torques};
use gait_core::mechanics::inverse_dynamics;
use gait_core::problem::{Cost, PaperProblem};

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
}

impl std::fmt::Display for PhiCostError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Length { expected, got } => {
                write!(f, "expected {expected} angle samples (N + 1), got {got}")
            }
            Self::NonFinite { k } => write!(f, "sample {k} holds a non-finite angle"),
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
                    foot.as_ref(),
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

/// J and its parts from Φ(t_k), k = 0…N (see the module documentation).
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
    let samples = phi_samples(problem, phi);
    let dt = problem.sampling.dt_s;
    let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
        return Err(PhiCostError::Length {
            expected: n + 1,
            got: phi.len(),
        });
    };
    let (start, landing) = (first.p5, last.p5);
    let mut peak_speed = 0.0f64;
    for w in samples.windows(2) {
        if let [a, b] = w {
            let dx = b.p5[0] - a.p5[0];
            let dy = b.p5[1] - a.p5[1];
            peak_speed = peak_speed.max((dx * dx + dy * dy).sqrt() / dt);
        }
    }
    let mut sum_sq = 0.0;
    let mut peak_tau = 0.0f64;
    let mut swing = 0usize;
    for s in &samples {
        let Some(t) = s.torque else { continue };
        if problem.count_every_sample
            || contact_weight(s.p5, start, landing, CONTACT_THRESHOLD_M) > 0.0
        {
            sum_sq += t[0] * t[0];
            peak_tau = peak_tau.max(t[0].abs());
            swing += 1;
        }
    }
    let torque = sum_sq / (n.saturating_sub(1).max(1) as f64);
    let velocity = problem.velocity_weight * peak_speed;
    let motion: f64 = problem.joint_motion_limit.map_or(0.0, |l| {
        samples
            .iter()
            .filter_map(|s| s.dphi.map(|d| l.penalty(&d, s.ddphi.as_ref())))
            .sum()
    });
    let range: f64 = problem.joint_range_limit.map_or(0.0, |r| {
        samples
            .iter()
            .zip(phi)
            .filter(|(s, _)| s.torque.is_some())
            .map(|(_, p)| r.penalty(p))
            .sum()
    });
    let joint_motion = motion + range;
    Ok(Cost {
        j: torque + velocity + joint_motion,
        torque,
        velocity,
        joint_motion,
        peak_ankle_speed_m_s: peak_speed,
        tau_rms_nm: if swing > 0 {
            (sum_sq / swing as f64).sqrt()
        } else {
            0.0
        },
        tau_peak_nm: peak_tau,
        swing_samples: swing,
    })
}
