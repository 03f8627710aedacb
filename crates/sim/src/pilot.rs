//! The pilot balancing through the crutches, seen from the stance ankle.
//!
//! The paper's premise: the exoskeleton cannot actuate the stance ankle, so
//! whatever ankle torque the motion needs beyond the ankle's passive spring
//! is supplied by the pilot pushing on the crutches. We model the pilot as a
//! torque-limited PD controller on the stance-shank angle φ1 (which, with the
//! foot flat, is the ankle dorsiflexion) tracking a desired profile, and the
//! crutches as a lever: vertical crutch force = |ankle torque| / lever arm.
//! The force is split evenly between the two crutches (no lateral model in a
//! sagittal plant), and a baseline load is always added: pilots of
//! exoskeletons never stand without leaning on their crutches.

use gait_core::gait::StanceAnkleProfile;

/// What the pilot tries to do with the stance shank.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PilotTarget {
    /// The pilot does not balance at all (zero torque, baseline load only).
    Off,
    /// Hold φ1 at a fixed angle, rad.
    Hold {
        /// Desired stance-shank angle, rad (clockwise from vertical-up).
        phi1_rad: f64,
    },
    /// Track the paper's logistic stance-ankle profile, its time measured
    /// from the simulation time `t0_s`.
    Profile {
        /// The profile φ1(t).
        profile: StanceAnkleProfile<f64>,
        /// Simulation time at which the profile's t = 0, s.
        t0_s: f64,
    },
    /// Track a moving target set each control tick: φ1 at `t0_s` and its
    /// rate (extrapolated linearly within the tick).
    Track {
        /// φ1 at `t0_s`, rad.
        phi1_rad: f64,
        /// dφ1/dt, rad/s.
        rate_rad_s: f64,
        /// Simulation time of `phi1_rad`, s.
        t0_s: f64,
    },
    /// Track the profile with its time measured from the last leg swap (or
    /// from the start): each new stance restarts it.
    ProfileFromLanding {
        /// The profile φ1(t).
        profile: StanceAnkleProfile<f64>,
    },
}

/// Pilot and crutch parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PilotConfig {
    /// Proportional gain on the φ1 error, N·m/rad.
    pub kp_nm_per_rad: f64,
    /// Derivative gain, N·m·s/rad.
    pub kd_nm_s_per_rad: f64,
    /// Share (0–1) of the static ankle torque of the present posture the
    /// pilot supplies without waiting for an error: a pilot who has learnt
    /// the gait knows how hard to lean (0: a pure PD, which lags a body
    /// that tips forward and settles short of its target by the gravity
    /// moment over kp).
    pub gravity_compensation: f64,
    /// Largest ankle torque the pilot can supply through the crutches, N·m.
    pub torque_limit_nm: f64,
    /// Horizontal lever between the stance ankle and the crutch tips, m:
    /// crutch force = |pilot torque| / lever.
    pub crutch_lever_m: f64,
    /// Load the pilot always leans on the crutches with (both together), N.
    pub baseline_crutch_load_n: f64,
    /// The time the pilot takes to act on a safe hold the controller
    /// started, s: until then the pilot goes on with the shank's motion
    /// as it was (a hold comes unannounced). 0: at once.
    pub hold_reaction_s: f64,
    /// Then the time the pilot takes to bring the shank from where it is
    /// to the hold's aim, s (eased in and out). 0: a step of the aim.
    pub hold_recovery_s: f64,
    /// The pilot's own lean over the plan's stance shank, rad (positive
    /// forward): a habit kept through every step, standing and swinging …
    pub habit_lean_rad: f64,
    /// … except when the device keeps the pilot waiting for a step: after
    /// this long, s, …
    pub patience_s: f64,
    /// … the pilot brings the shank towards the plan at this rate, rad/s,
    /// for that step (the habit returns with the next weight transfer).
    pub correction_rad_s: f64,
}

impl Default for PilotConfig {
    /// Stiff enough to hold the 93 kg inverted pendulum (needs more than
    /// m·g·h ≈ 900 N·m/rad), damped near critically, 120 N·m at most
    /// (≈ 270 N on the crutches at 0.45 m), 100 N baseline.
    fn default() -> Self {
        Self {
            kp_nm_per_rad: 2500.0,
            kd_nm_s_per_rad: 400.0,
            gravity_compensation: 0.0,
            torque_limit_nm: 120.0,
            crutch_lever_m: 0.45,
            baseline_crutch_load_n: 100.0,
            hold_reaction_s: 0.0,
            hold_recovery_s: 0.0,
            habit_lean_rad: 0.0,
            patience_s: 0.5,
            correction_rad_s: 0.05,
        }
    }
}

impl PilotTarget {
    /// Desired (φ1, φ̇1) at simulation time `t_s`, `since_swap_s` after the
    /// last leg swap; `None` when the pilot is off.
    pub fn desired(&self, t_s: f64, since_swap_s: f64) -> Option<(f64, f64)> {
        let eval = |p: &StanceAnkleProfile<f64>, t: f64| {
            let e = (-p.k_per_s * (t - p.t_c_s)).exp();
            let rate = (p.b_rad - p.a_rad) * p.k_per_s * e / ((1.0 + e) * (1.0 + e));
            (p.at(t), if rate.is_finite() { rate } else { 0.0 })
        };
        match self {
            Self::Off => None,
            Self::Hold { phi1_rad } => Some((*phi1_rad, 0.0)),
            Self::Profile { profile, t0_s } => Some(eval(profile, t_s - t0_s)),
            Self::Track {
                phi1_rad,
                rate_rad_s,
                t0_s,
            } => Some((phi1_rad + rate_rad_s * (t_s - t0_s), *rate_rad_s)),
            Self::ProfileFromLanding { profile } => Some(eval(profile, since_swap_s)),
        }
    }
}

impl PilotConfig {
    /// The pilot's torque on the ankle-dorsiflexion coordinate (N·m, positive
    /// tips the shank forward), limited. `static_nm`: the torque on that
    /// coordinate that would hold the present posture still (scaled by
    /// [`PilotConfig::gravity_compensation`]).
    pub fn torque_nm(
        &self,
        desired: Option<(f64, f64)>,
        phi1: f64,
        dphi1: f64,
        static_nm: f64,
    ) -> f64 {
        match desired {
            None => 0.0,
            Some((q, dq)) => {
                let ff = if static_nm.is_finite() {
                    self.gravity_compensation * static_nm
                } else {
                    0.0
                };
                let t = self.kp_nm_per_rad * (q - phi1) + self.kd_nm_s_per_rad * (dq - dphi1) + ff;
                t.clamp(-self.torque_limit_nm, self.torque_limit_nm)
            }
        }
    }

    /// Vertical force on each crutch (left, right), N, for a pilot torque.
    pub fn crutch_forces_n(&self, pilot_torque_nm: f64) -> [f64; 2] {
        let total = pilot_torque_nm.abs() / self.crutch_lever_m + self.baseline_crutch_load_n;
        [0.5 * total, 0.5 * total]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gravity_compensation_adds_the_static_torque_within_the_limit() {
        let target = Some((0.1, 0.0));
        let pd = PilotConfig {
            torque_limit_nm: 300.0,
            ..PilotConfig::default()
        };
        // On target and still: a pure PD gives nothing, whatever gravity
        // asks; a compensating pilot supplies the static torque.
        assert_eq!(pd.torque_nm(target, 0.1, 0.0, 150.0), 0.0);
        let learnt = PilotConfig {
            gravity_compensation: 1.0,
            ..pd
        };
        assert!((learnt.torque_nm(target, 0.1, 0.0, 150.0) - 150.0).abs() < 1e-12);
        // Still limited, NaN ignored, nothing when the pilot is off.
        assert_eq!(learnt.torque_nm(target, 0.1, 0.0, 1e4), 300.0);
        assert_eq!(learnt.torque_nm(target, 0.1, 0.0, f64::NAN), 0.0);
        assert_eq!(learnt.torque_nm(None, 0.1, 0.0, 150.0), 0.0);
    }
}
