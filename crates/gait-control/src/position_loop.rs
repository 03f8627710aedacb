//! One joint's position loop: PID on the anatomical angle plus the model's
//! inverse-dynamics feed-forward, with anti-windup and torque and slew
//! limits. Pure arithmetic, constant time, no state beyond two numbers.
//!
//! The motor driver limits again (its own torque, slew and thermal limits):
//! this loop's limits shape the controller's behaviour, the driver's protect
//! the hardware whatever the controller does.

use gait_core::scalar::clamp_f32;

/// Gains and limits of one joint.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct JointGains {
    /// Proportional gain, N·m/rad.
    pub kp_nm_per_rad: f32,
    /// Integral gain, N·m/(rad·s).
    pub ki_nm_per_rad_s: f32,
    /// Derivative gain, N·m·s/rad.
    pub kd_nm_s_per_rad: f32,
    /// Largest magnitude of the integral term, N·m.
    pub integral_limit_nm: f32,
    /// Largest magnitude of the command, N·m.
    pub torque_limit_nm: f32,
    /// Largest change of the command per tick, N·m.
    pub slew_nm_per_tick: f32,
}

impl JointGains {
    /// The gains with no feedback at all (the loop then passes its
    /// feed-forward through its limits and slew): for a joint whose
    /// encoder is lost, which must not be driven by PID on a stale angle.
    #[must_use]
    pub fn without_feedback(&self) -> Self {
        Self {
            kp_nm_per_rad: 0.0,
            ki_nm_per_rad_s: 0.0,
            kd_nm_s_per_rad: 0.0,
            integral_limit_nm: 0.0,
            ..*self
        }
    }

    /// The gains with the position feedback (proportional, integral and the
    /// integral's clamp) scaled by `k` in [0, 1]; damping and limits kept.
    #[must_use]
    pub fn with_stiffness(&self, k: f32) -> Self {
        let k = if k.is_finite() {
            k.clamp(0.0, 1.0)
        } else {
            1.0
        };
        Self {
            kp_nm_per_rad: self.kp_nm_per_rad * k,
            ki_nm_per_rad_s: self.ki_nm_per_rad_s * k,
            integral_limit_nm: self.integral_limit_nm * k,
            ..*self
        }
    }

    /// `true` when every value is finite and non-negative and the limits
    /// are positive.
    pub fn is_valid(&self) -> bool {
        let all = [
            self.kp_nm_per_rad,
            self.ki_nm_per_rad_s,
            self.kd_nm_s_per_rad,
            self.integral_limit_nm,
            self.torque_limit_nm,
            self.slew_nm_per_tick,
        ];
        all.iter().all(|v| v.is_finite() && *v >= 0.0)
            && self.torque_limit_nm > 0.0
            && self.slew_nm_per_tick > 0.0
    }
}

/// What the loop wants the joint to do this tick.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Setpoint {
    /// Reference angle, rad.
    pub angle_rad: f32,
    /// Reference rate, rad/s.
    pub rate_rad_s: f32,
    /// Feed-forward torque from the model, N·m.
    pub feedforward_nm: f32,
}

/// The loop's output.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LoopOutput {
    /// Torque command, N·m (within the limits, always finite).
    pub command_nm: f32,
    /// The PID + feed-forward sum hit the torque limit.
    pub saturated: bool,
    /// An input was NaN or infinite: the command is zero.
    pub rejected: bool,
}

/// State of one joint's loop.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointLoop {
    integral_nm: f32,
    last_command_nm: f32,
}

impl JointLoop {
    /// Forgets the integral and the last command (after a hold or a reset,
    /// so no stale integral kicks the joint).
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// The last command, N·m.
    pub fn last_command_nm(&self) -> f32 {
        self.last_command_nm
    }

    /// One tick. `measured_rate_rad_s` is the controller's filtered rate.
    pub fn update(
        &mut self,
        gains: &JointGains,
        sp: &Setpoint,
        measured_rad: f32,
        measured_rate_rad_s: f32,
        dt_s: f32,
    ) -> LoopOutput {
        // One finiteness test of the sum instead of six: a NaN or an
        // infinity in any input makes it non-finite (∞ − ∞ is NaN). So would
        // finite inputs summing past f32::MAX (3.4e38), which no angle, rate
        // or torque reaches; rejected, they would be safe too. Six tests
        // cost 40 instructions a joint on the M4 (`cargo xtask profile`).
        let sum = sp.angle_rad
            + sp.rate_rad_s
            + sp.feedforward_nm
            + measured_rad
            + measured_rate_rad_s
            + dt_s;
        if !sum.is_finite() {
            // Ramp towards zero at the slew limit rather than jump.
            let cmd = step_towards(self.last_command_nm, 0.0, gains.slew_nm_per_tick);
            self.last_command_nm = cmd;
            return LoopOutput {
                command_nm: cmd,
                saturated: false,
                rejected: true,
            };
        }
        let error = sp.angle_rad - measured_rad;
        let rate_error = sp.rate_rad_s - measured_rate_rad_s;
        let pd = gains.kp_nm_per_rad * error + gains.kd_nm_s_per_rad * rate_error;
        let candidate_integral = clamp_f32(
            self.integral_nm + gains.ki_nm_per_rad_s * error * dt_s,
            -gains.integral_limit_nm,
            gains.integral_limit_nm,
        );
        let limit = gains.torque_limit_nm;
        let unclamped = sp.feedforward_nm + pd + candidate_integral;
        let saturated = unclamped.abs() > limit;
        // Anti-windup by conditional integration: while saturated, the
        // integral may only move in the direction that leaves saturation.
        let grows_into_limit =
            saturated && (candidate_integral - self.integral_nm).signum() == unclamped.signum();
        if !grows_into_limit {
            self.integral_nm = candidate_integral;
        }
        let wanted = clamp_f32(sp.feedforward_nm + pd + self.integral_nm, -limit, limit);
        let cmd = step_towards(self.last_command_nm, wanted, gains.slew_nm_per_tick);
        self.last_command_nm = cmd;
        LoopOutput {
            command_nm: cmd,
            saturated,
            rejected: false,
        }
    }
}

/// Moves `from` towards `to` by at most `max_step`.
fn step_towards(from: f32, to: f32, max_step: f32) -> f32 {
    from + clamp_f32(to - from, -max_step, max_step)
}

#[cfg(test)]
mod tests {

    #[test]
    fn without_feedback_passes_the_feed_forward_through_limits_and_slew() {
        let g = G.without_feedback();
        let mut l = JointLoop::default();
        let sp = Setpoint {
            angle_rad: 0.3,
            rate_rad_s: 0.0,
            feedforward_nm: 5.0,
        };
        // Far from the reference, no feedback: only the feed-forward.
        let mut last = 0.0;
        for _ in 0..1000 {
            last = l.update(&g, &sp, -1.0, 2.0, 0.001).command_nm;
        }
        assert!((last - 5.0).abs() < 1e-6, "{last}");
    }

    use super::*;

    const G: JointGains = JointGains {
        kp_nm_per_rad: 300.0,
        ki_nm_per_rad_s: 200.0,
        kd_nm_s_per_rad: 10.0,
        integral_limit_nm: 20.0,
        torque_limit_nm: 80.0,
        slew_nm_per_tick: 5.0,
    };

    fn sp(angle: f32) -> Setpoint {
        Setpoint {
            angle_rad: angle,
            rate_rad_s: 0.0,
            feedforward_nm: 0.0,
        }
    }

    #[test]
    fn proportional_action_with_slew() {
        let mut l = JointLoop::default();
        let o = l.update(&G, &sp(0.1), 0.0, 0.0, 0.001);
        assert!((o.command_nm - 5.0).abs() < 1e-6, "slew-limited first step");
        let mut last = o.command_nm;
        for _ in 0..20 {
            last = l.update(&G, &sp(0.1), 0.0, 0.0, 0.001).command_nm;
        }
        assert!(last > 30.0 && last <= 80.0);
    }

    #[test]
    fn saturates_and_does_not_wind_up() {
        let mut l = JointLoop::default();
        for _ in 0..5000 {
            let o = l.update(&G, &sp(1.0), 0.0, 0.0, 0.001);
            assert!(o.command_nm.abs() <= 80.0 + 1e-4);
        }
        assert!(
            l.integral_nm.abs() < 1e-3,
            "integral wound up to {}",
            l.integral_nm
        );
        // Once the error reverses, the command reverses without delay.
        let mut cmd = 0.0;
        for _ in 0..40 {
            cmd = l.update(&G, &sp(-1.0), 0.0, 0.0, 0.001).command_nm;
        }
        assert!(cmd < -70.0);
    }

    #[test]
    fn integral_removes_steady_error_under_load() {
        // Inertia 0.5 kg·m², damping 20 N·m·s/rad, spring 50 N·m/rad and a
        // constant 10 N·m load; semi-implicit Euler at 1 kHz.
        let run = |gains: &JointGains| {
            let mut l = JointLoop::default();
            let (mut q, mut w) = (0.0f32, 0.0f32);
            for _ in 0..20_000 {
                let o = l.update(gains, &sp(0.1), q, w, 0.001);
                let acc = (o.command_nm - 10.0 - 50.0 * q - 20.0 * w) / 0.5;
                w += acc * 0.001;
                q += w * 0.001;
            }
            0.1 - q
        };
        let without = run(&JointGains {
            ki_nm_per_rad_s: 0.0,
            ..G
        });
        let with = run(&G);
        assert!(without.abs() > 0.03, "P-only steady error {without}");
        assert!(with.abs() < 1e-4, "PI steady error {with}");
    }

    #[test]
    fn any_non_finite_input_is_rejected() {
        // Each of the six inputs NaN, +∞ or −∞ (the sum test must see each),
        // and +∞ with −∞ elsewhere (their sum is NaN, not finite).
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for at in 0..6 {
                let mut v = [0.1f32, 0.2, 3.0, 0.05, -0.1, 0.001];
                v[at] = bad;
                let setpoint = Setpoint {
                    angle_rad: v[0],
                    rate_rad_s: v[1],
                    feedforward_nm: v[2],
                };
                let o = JointLoop::default().update(&G, &setpoint, v[3], v[4], v[5]);
                assert!(o.rejected, "{bad} at {at}");
                assert!(o.command_nm.is_finite());
            }
        }
        let setpoint = Setpoint {
            angle_rad: f32::INFINITY,
            rate_rad_s: 0.0,
            feedforward_nm: 0.0,
        };
        let o = JointLoop::default().update(&G, &setpoint, f32::INFINITY, 0.0, 0.001);
        assert!(o.rejected);
        // Large but finite inputs are taken.
        let big = Setpoint {
            angle_rad: 1e6,
            rate_rad_s: -1e6,
            feedforward_nm: 1e4,
        };
        assert!(
            !JointLoop::default()
                .update(&G, &big, 1e6, 1e6, 0.001)
                .rejected
        );
    }

    #[test]
    fn non_finite_inputs_ramp_to_zero() {
        let mut l = JointLoop::default();
        for _ in 0..30 {
            l.update(&G, &sp(0.5), 0.0, 0.0, 0.001);
        }
        let before = l.last_command_nm();
        let o = l.update(&G, &sp(f32::NAN), 0.0, 0.0, 0.001);
        assert!(o.rejected);
        assert!((before - o.command_nm - 5.0).abs() < 1e-4);
        for _ in 0..100 {
            l.update(&G, &sp(0.0), f32::INFINITY, 0.0, 0.001);
        }
        assert_eq!(l.last_command_nm(), 0.0);
    }
}
