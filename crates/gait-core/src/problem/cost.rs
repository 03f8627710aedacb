//! Eq. (cost): J and its parts from a step's samples, computed in one
//! place ([`CostAccumulator`]) whichever way the samples are made: from
//! control points through the IK ([`PaperProblem::cost`]) or from a
//! sequence of angles (gait-opt's `cost_from_phi`, for human-data
//! baselines). Both feed the accumulator every sample's swing-ankle
//! position and every dynamics sample's posture, rates and ankle torque.

use super::{Infeasible, JointMotionLimit, JointRangeLimit, PaperProblem};
use crate::gait::{
    CONTACT_THRESHOLD_M, ControlPoints, Differences, GaitError, StepEvent, contact_weight,
    evaluate_step,
};
use crate::kinematics::Phi;
use crate::scalar::Real;

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

pub use crate::gait::MAX_SAMPLES;

/// One dynamics sample as J sees it (k ≥ 2 with eq. (ee2)'s backward
/// differences).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostSample<'a, T> {
    /// Swing-ankle position p5, m.
    pub p5: [T; 2],
    /// Absolute angles Φ, rad.
    pub phi: &'a Phi<T>,
    /// Φ̇, rad/s.
    pub dphi: &'a Phi<T>,
    /// Φ̈, rad/s².
    pub ddphi: &'a Phi<T>,
    /// τ = T_θ1, the stance pivot's joint torque, N·m.
    pub ankle_torque_nm: T,
}

/// Eq. (cost) accumulated sample by sample: the one place J and its parts
/// are computed.
///
/// Feed [`CostAccumulator::position`] the swing-ankle position of every
/// sample k = 0…N in order, and [`CostAccumulator::dynamics`] every sample
/// whose derivatives exist, in order; then [`CostAccumulator::finish`].
/// The (p5, τ) pairs are kept (no heap: at most [`MAX_SAMPLES`]) until
/// p5(N) is known for c_k.
#[derive(Clone, Debug)]
pub struct CostAccumulator<T> {
    dt: T,
    intervals: usize,
    velocity_weight: T,
    count_every_sample: bool,
    motion_limit: Option<JointMotionLimit<T>>,
    range_limit: Option<JointRangeLimit<T>>,
    first: Option<[T; 2]>,
    prev: Option<[T; 2]>,
    peak_speed: T,
    taus: heapless::Vec<([T; 2], T), MAX_SAMPLES>,
    joint_motion: T,
}

impl<T: Real> CostAccumulator<T> {
    /// An empty accumulator for `problem`'s sampling, weights and limits;
    /// refuses a step of more than [`MAX_SAMPLES`] samples.
    pub fn new(problem: &PaperProblem<T>) -> Result<Self, Infeasible> {
        let n = problem.sampling.intervals;
        if n.saturating_add(1) > MAX_SAMPLES {
            return Err(Infeasible::Gait(GaitError::BadSampling));
        }
        Ok(Self {
            dt: problem.sampling.dt_s,
            intervals: n,
            velocity_weight: problem.velocity_weight,
            count_every_sample: problem.count_every_sample,
            motion_limit: problem.joint_motion_limit,
            range_limit: problem.joint_range_limit,
            first: None,
            prev: None,
            peak_speed: T::zero(),
            taus: heapless::Vec::new(),
            joint_motion: T::zero(),
        })
    }

    /// The swing-ankle position p5 of the next sample (k = 0…N in order):
    /// the path's peak speed, and p5(0) and p5(N) for c_k.
    pub fn position(&mut self, p5: [T; 2]) {
        if self.first.is_none() {
            self.first = Some(p5);
        }
        if let Some(q) = self.prev {
            let dx = p5[0] - q[0];
            let dy = p5[1] - q[1];
            self.peak_speed = self.peak_speed.max((dx * dx + dy * dy).sqrt() / self.dt);
        }
        self.prev = Some(p5);
    }

    /// The next dynamics sample: its τ, and its joint-range and
    /// joint-motion terms. `first_rate` is Φ̇ of the interval before the
    /// first dynamics sample (which no dynamics sample holds); it is asked
    /// for once, on the first call, and only when a [`JointMotionLimit`]
    /// counts it.
    pub fn dynamics(&mut self, s: &CostSample<'_, T>, first_rate: impl FnOnce() -> Option<Phi<T>>) {
        if let Some(r) = &self.range_limit {
            self.joint_motion += r.penalty(s.phi);
        }
        if let Some(l) = &self.motion_limit {
            self.joint_motion += l.penalty(s.dphi, Some(s.ddphi));
            if self.taus.is_empty() {
                if let Some(rate) = first_rate() {
                    self.joint_motion += l.penalty(&rate, None);
                }
            }
        }
        // Capacity was checked against N in `new`.
        let _ = self.taus.push((s.p5, s.ankle_torque_nm));
    }

    /// J and its parts from the samples fed so far.
    pub fn finish(&self) -> Result<Cost<T>, Infeasible> {
        let (Some(start), Some(landing)) = (self.first, self.prev) else {
            return Err(Infeasible::Gait(GaitError::BadSampling));
        };
        let threshold = T::lit(CONTACT_THRESHOLD_M);
        let mut sum_sq = T::zero();
        let mut peak_tau = T::zero();
        let mut swing = 0usize;
        for &(p5, tau) in &self.taus {
            if self.count_every_sample || contact_weight(p5, start, landing, threshold) > T::zero()
            {
                sum_sq += tau * tau;
                peak_tau = peak_tau.max(tau.abs());
                swing += 1;
            }
        }
        let denom = T::lit(self.intervals.saturating_sub(1).max(1) as f64);
        let torque = sum_sq / denom;
        let velocity = self.velocity_weight * self.peak_speed;
        let tau_rms = if swing > 0 {
            (sum_sq / T::lit(swing as f64)).sqrt()
        } else {
            T::zero()
        };
        let joint_motion = self.joint_motion;
        Ok(Cost {
            j: torque + velocity + joint_motion,
            torque,
            velocity,
            joint_motion,
            peak_ankle_speed_m_s: self.peak_speed,
            tau_rms_nm: tau_rms,
            tau_peak_nm: peak_tau,
            swing_samples: swing,
        })
    }
}

impl<T: Real> PaperProblem<T> {
    /// Eq. (cost): J(P) and its parts, after checking feasibility.
    pub fn cost(&self, p: &ControlPoints<T>) -> Result<Cost<T>, Infeasible> {
        self.check_feasible(p)?;
        self.cost_unchecked(p)
    }

    /// J(P) without the bound checks (sampling and IK are still checked).
    /// For evaluating human-data baselines, which need not respect eq. (cons).
    pub fn cost_unchecked(&self, p: &ControlPoints<T>) -> Result<Cost<T>, Infeasible> {
        let step = self.step(p);
        let mut acc = CostAccumulator::new(self)?;
        let dt = self.sampling.dt_s;
        let backward = self.differences == Differences::Backward;
        evaluate_step::<T, Infeasible>(&self.model, &step, self.differences, |ev| {
            match ev {
                StepEvent::Sample(s) => acc.position(s.p5),
                StepEvent::Dynamics(d) => {
                    let sample = CostSample {
                        p5: d.gait.p5,
                        phi: &d.phi,
                        dphi: &d.dphi,
                        ddphi: &d.ddphi,
                        ankle_torque_nm: d.torque[0],
                    };
                    // The first interval's rate is in no dynamics sample;
                    // with backward differences it is
                    // Φ̇(k−1) = Φ̇(k) − Φ̈(k)·Δt at the first one.
                    acc.dynamics(&sample, || {
                        backward.then(|| {
                            let mut rate = d.dphi;
                            for (r, &a) in rate.iter_mut().zip(&d.ddphi) {
                                *r -= a * dt;
                            }
                            rate
                        })
                    });
                }
            }
            Ok(())
        })?;
        acc.finish()
    }
}
