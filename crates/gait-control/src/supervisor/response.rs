//! The model-based check of each hip and knee drive (0x0404): does the
//! joint move as the torque it was given says it should?
//!
//! About the reference, a joint's error e = θ − θ_ref obeys
//! J ë = (τ − τ_ff) + d: the feed-forward τ_ff is the model's torque for the
//! reference motion, so what the drive gives beyond it (the position loop's
//! correction u = τ − τ_ff) accelerates the error by u / J, and d is the
//! torque the model does not explain. d is small in a healthy joint (model
//! error, the pilot's push, a landing); it is large when the torque reaching
//! the joint is not the one commanded: a drive stuck on an old set value
//! gives d = τ_stuck − τ, a drive giving a share k gives d = −(1 − k) τ.
//!
//! A disturbance observer estimates d without differentiating the encoder
//! twice: e and u pass through the same critically damped second-order
//! low-pass at ω, and d̂ = J (ω² (e − x₁) − 2ω x₂) − z₁, where x₁, x₂ are the
//! filter's states for e (ω² (e − x₁) − 2ω x₂ is the filtered ë) and z₁ the
//! filtered u. J is the joint's effective inertia: its leg's stance or swing
//! figure (a stance knee moves the body, a swing knee a shank).
//!
//! Healthy closed-loop runs with sensor noise keep |d̂| under 50 N·m (stair
//! ascent's stance knee; walking 45); a stuck drive reaches 200–2,000 N·m,
//! a drive at half its torque 80–250 N·m (`docs/safety.md`).

use crate::layout::Side;

/// Settings of the residual check.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ResponseCheck {
    /// Effective inertia of a stance leg's hip and knee, kg·m².
    pub stance_inertia_kgm2: [f32; 2],
    /// Effective inertia of a swing leg's hip (the leg) and knee (shank and
    /// foot), kg·m².
    pub swing_inertia_kgm2: [f32; 2],
    /// The observer's bandwidth, Hz.
    pub bandwidth_hz: f32,
    /// |d̂| above which a tick counts, N·m.
    pub limit_nm: f32,
    /// The lowest limit a gait may set for the stance hip of its swings,
    /// N·m ([`crate::supervisor::SupervisorInput::stance_hip_residual_nm`]):
    /// a gait whose healthy closed loop keeps that hip's |d̂| well under
    /// [`ResponseCheck::limit_nm`] catches a slipping stance hip sooner,
    /// and none is held tighter than this.
    pub stance_hip_min_nm: f32,
    /// Consecutive ticks over the limit that make the fault.
    pub ticks: u32,
    /// A hip whose own ankle reads further forward than the ankle's plan
    /// by more than this, rad …
    pub leaning_ankle_rad: f32,
    /// … has its limit multiplied by this: the pilot leaning on the
    /// crutches drives that shank, and the torso with it, and the hip
    /// that carries the torso feels a torque no drive gave. Braked for
    /// it, the hip let the torso fall; a stuck drive's residual (190–1,930
    /// N·m) still passes the raised limit, and the drive's current
    /// (0x0405) finds a drive that does not deliver at once.
    pub leaning_factor: f32,
}

impl ResponseCheck {
    /// The paper's body (Table III): the swing knee carries shank and foot
    /// (0.35 kg·m² about the knee), the swing hip the leg (1.2); a stance
    /// joint moves the body over the foot, far more than its own links,
    /// of which 8 kg·m² is what the closed loop's responses fit best. 3 Hz,
    /// 100 N·m for 10 ticks: above every healthy run (the shipped gaits
    /// stay under 50 N·m, the human-data stair descent passes 80), below
    /// every stuck drive. A gait may hold the stance hip of its swings to
    /// as little as 70 N·m: the built-in gaits keep it under 52 (a pilot 2° off
    /// the plan included), and a stance hip whose gear slips shows 70–95 (`docs/safety.md`).
    pub const DEFAULT: Self = Self {
        stance_inertia_kgm2: [8.0, 8.0],
        swing_inertia_kgm2: [1.2, 0.35],
        bandwidth_hz: 3.0,
        limit_nm: 100.0,
        stance_hip_min_nm: 70.0,
        ticks: 10,
        leaning_ankle_rad: 0.05,
        leaning_factor: 2.0,
    };

    /// The limit on the stance hip of a swing whose gait asks for
    /// `gait_nm`: the gait's figure held within
    /// [`ResponseCheck::stance_hip_min_nm`] and
    /// [`ResponseCheck::limit_nm`]; the limit itself where the gait gives
    /// none (NaN, zero or negative).
    #[must_use]
    pub fn stance_hip_limit_nm(&self, gait_nm: f32) -> f32 {
        stance_hip_limit(gait_nm, self.stance_hip_min_nm, self.limit_nm)
    }

    /// Whether every value is finite and positive.
    pub(super) fn is_valid(&self) -> bool {
        let all = [
            self.stance_inertia_kgm2[0],
            self.stance_inertia_kgm2[1],
            self.swing_inertia_kgm2[0],
            self.swing_inertia_kgm2[1],
            self.bandwidth_hz,
            self.limit_nm,
            self.stance_hip_min_nm,
        ];
        all.iter().all(|v| v.is_finite() && *v > 0.0)
            && self.stance_hip_min_nm <= self.limit_nm
            && self.ticks > 0
            && self.leaning_ankle_rad.is_finite()
            && self.leaning_ankle_rad >= 0.0
            && self.leaning_factor.is_finite()
            && self.leaning_factor >= 1.0
    }
}

fn stance_hip_limit(gait_nm: f32, min_nm: f32, limit_nm: f32) -> f32 {
    if gait_nm > 0.0 && gait_nm.is_finite() {
        gait_nm.max(min_nm).min(limit_nm)
    } else {
        limit_nm
    }
}

/// The observer's constants, worked out once from [`ResponseCheck`] (the
/// tick only multiplies).
#[derive(Debug, Clone, Copy)]
pub(super) struct Observer {
    /// ω², 1/s².
    w2: f32,
    /// 2ω, 1/s.
    two_w: f32,
    dt_s: f32,
    /// Inertia of each joint (joint order) on a stance leg, then on a swing
    /// leg, kg·m².
    inertia_kgm2: [[f32; super::JOINTS]; 2],
    /// |d̂| limit, N·m.
    pub(super) limit_nm: f32,
    /// The lowest a gait may hold the stance hip of its swings to, N·m.
    stance_hip_min_nm: f32,
    /// Ticks over it that make the fault.
    pub(super) ticks: u32,
    /// A hip's ankle this far ahead of its plan raises its limit, rad …
    leaning_ankle_rad: f32,
    /// … by this factor.
    leaning_factor: f32,
}

impl Observer {
    pub(super) fn new(cfg: &ResponseCheck, dt_s: f32) -> Self {
        let w = 2.0 * core::f32::consts::PI * cfg.bandwidth_hz;
        let [sh, sk] = cfg.stance_inertia_kgm2;
        let [wh, wk] = cfg.swing_inertia_kgm2;
        Self {
            w2: w * w,
            two_w: 2.0 * w,
            dt_s,
            inertia_kgm2: [[sh, sk, sh, sk], [wh, wk, wh, wk]],
            limit_nm: cfg.limit_nm,
            stance_hip_min_nm: cfg.stance_hip_min_nm,
            ticks: cfg.ticks,
            leaning_ankle_rad: cfg.leaning_ankle_rad,
            leaning_factor: cfg.leaning_factor,
        }
    }

    /// Each joint's limit this tick: the gait's `gait_nm` for the hip
    /// that stands while `swing_leg` swings, the device's for the rest;
    /// a hip whose ankle reads `ahead_rad` (left, right: accepted angle
    /// less its plan, NaN where either is unknown) past
    /// [`ResponseCheck::leaning_ankle_rad`] has its limit raised by
    /// [`ResponseCheck::leaning_factor`].
    pub(super) fn limits(
        &self,
        swing_leg: Option<Side>,
        gait_nm: f32,
        ahead_rad: [f32; 2],
    ) -> [f32; super::JOINTS] {
        let mut limits = [self.limit_nm; super::JOINTS];
        if let Some(hip) = swing_leg.and_then(|leg| limits.get_mut(leg.other().hip())) {
            *hip = stance_hip_limit(gait_nm, self.stance_hip_min_nm, self.limit_nm);
        }
        for side in [Side::Left, Side::Right] {
            let ahead = ahead_rad.get(side.ankle()).copied().unwrap_or(f32::NAN);
            if ahead > self.leaning_ankle_rad {
                if let Some(hip) = limits.get_mut(side.hip()) {
                    *hip *= self.leaning_factor;
                }
            }
        }
        limits
    }

    /// Joint `joint`'s inertia, on a swing leg or not.
    pub(super) fn inertia(&self, joint: usize, swing: bool) -> f32 {
        self.inertia_kgm2
            .get(usize::from(swing))
            .and_then(|row| row.get(joint))
            .copied()
            .unwrap_or(f32::NAN)
    }
}

/// One joint's observer.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Residual {
    /// The low-pass of the error: value (rad) and rate (rad/s).
    e: [f32; 2],
    /// The low-pass of the correction: value and rate (N·m, N·m/s).
    u: [f32; 2],
    /// The feed-forward of the previous tick (the drive applied the
    /// previous tick's command against it), N·m.
    last_feedforward_nm: f32,
    /// The states are seeded.
    running: bool,
    /// The inertia the states were run with, kg·m².
    inertia_kgm2: f32,
    /// Consecutive ticks over the limit.
    pub(super) over_ticks: u32,
    /// d̂ of the last tick the observer ran, N·m (0 while stopped).
    pub(super) last_nm: f32,
}

impl Residual {
    /// Stops the observer (drive disabled, frame not taken): it re-seeds
    /// from the next sample.
    pub(super) fn stop(&mut self, feedforward_nm: f32) {
        self.running = false;
        self.over_ticks = 0;
        self.last_feedforward_nm = feedforward_nm;
        self.last_nm = 0.0;
    }

    /// One tick: `error_rad` now, `applied_nm` the torque the drive gave
    /// over the last tick, `feedforward_nm` this tick's. Returns d̂, N·m.
    pub(super) fn update(
        &mut self,
        o: &Observer,
        error_rad: f32,
        applied_nm: f32,
        feedforward_nm: f32,
        inertia_kgm2: f32,
    ) -> f32 {
        let correction = applied_nm - self.last_feedforward_nm;
        self.last_feedforward_nm = feedforward_nm;
        // A leg that lands or lifts changes the joint's inertia several
        // times over: the acceleration filtered so far belongs to the
        // other inertia's motion, and read against this one it is a torque
        // nobody gave. The error's filter starts again as if the joint had
        // always moved at its present rate: filtered acceleration 0, rate
        // the filter's estimate of it (its rate state lags a steady
        // acceleration by 2/ω of it; a moving joint must not read as a
        // jolt), the value lagging that rate as a steady filter's does.
        if self.running && inertia_kgm2 != self.inertia_kgm2 {
            let w = 0.5 * o.two_w;
            let acc = o.w2 * (error_rad - self.e[0]) - o.two_w * self.e[1];
            let rate = self.e[1] + 2.0 * acc / w;
            self.e = [error_rad - 2.0 * rate / w, rate];
            self.over_ticks = 0;
        }
        self.inertia_kgm2 = inertia_kgm2;
        if !self.running {
            self.e = [error_rad, 0.0];
            self.u = [correction, 0.0];
            self.running = true;
        }
        let e_acc = o.w2 * (error_rad - self.e[0]) - o.two_w * self.e[1];
        let residual = inertia_kgm2 * e_acc - self.u[0];
        let u_acc = o.w2 * (correction - self.u[0]) - o.two_w * self.u[1];
        self.e[1] += e_acc * o.dt_s;
        self.e[0] += self.e[1] * o.dt_s;
        self.u[1] += u_acc * o.dt_s;
        self.u[0] += self.u[1] * o.dt_s;
        self.last_nm = residual;
        residual
    }
}
