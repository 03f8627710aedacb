//! A pilot losing balance (0x0701 forward, 0x0702 back), seen at the
//! ankles and the crutches: the device cannot actuate the ankles, so the
//! stance shank follows its plan only while the pilot balances it through
//! the crutches. A pilot who balances corrects an error (it shrinks again)
//! and pushes on the crutches to do it; one who has stopped, or leans past
//! what the crutches can hold, lets the body turn about the foot, and the
//! error grows ever faster, as an inverted pendulum's does.
//!
//! The check follows each planned ankle's error e = φ1 − plan and its
//! low-passed rate ė, and counts the accepted frames on which the error is
//! beyond a bound and still growing away from the plan (e·ė > 0, |ė| above
//! its own bound). The bound is tighter while the crutches carry no more
//! than the least they have carried lately (a minimum that forgets at
//! 20 N/s, so it follows the pilot's resting lean, not the push of a
//! step): nobody is pushing the shank back, so a small error already
//! means nobody is balancing (the swing's 0.05 rad finds a pilot who has
//! stopped before a stair ascent's first swing 0.65–0.75 s into it,
//! early enough to set the foot down). A rejected frame neither counts
//! nor resets; a tick without a plan (NaN), or whose plan steps by more
//! than [`PLAN_STEP_RAD`] (a swing's table taking over, the stance
//! swapping at a landing), restarts the count and the rate.

/// The most a plan moves in one tick and is still the same motion, rad (a
/// table turns the shank at up to about 1 rad/s: 0.001 a tick).
pub(super) const PLAN_STEP_RAD: f32 = 0.01;

/// |φ1 − plan| beyond which a frame can count, rad, with both feet down
/// and in a swing.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorBounds {
    /// Both feet down.
    pub feet_down_rad: f32,
    /// In a swing, for the stance shank.
    pub swing_rad: f32,
}

/// Settings of the balance check.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BalanceCheck {
    /// The bounds while the crutches carry no more than the least they
    /// have carried lately (`crutch_rise_n` more at most):
    /// the shank is off its plan and nobody pushes to bring it back,
    /// which a balancing pilot always does.
    pub idle: ErrorBounds,
    /// The bounds while the pilot pushes: a stance shank lags a plan that
    /// turns it fast, by up to 0.13 rad late in a healthy walk's swing,
    /// and overshoots a transfer's aim by up to 0.12 rad at a fast
    /// clinical pace (`exogait tables`, 1.90 m, 0.35 m/s).
    pub pushed: ErrorBounds,
    /// The rise of the crutches' sum over that least value that shows a
    /// pilot pushing, N.
    pub crutch_rise_n: f32,
    /// How fast the least value forgets, N/s: it follows a pilot's
    /// resting load as it changes over many steps, not the push of one.
    pub crutch_forget_n_per_s: f32,
    /// |ė| (growing away from the plan) beyond which a frame can count,
    /// rad/s.
    pub rate_rad_s: f32,
    /// The rate's first-order filter gain per frame (0–1].
    pub rate_filter: f32,
    /// Consecutive counting frames that make the fault.
    pub ticks: u32,
}

impl BalanceCheck {
    /// With the crutches idle 0.1 rad (5.7°) off the plan, 0.05 rad in a
    /// swing; pushing 0.2 and 0.25 rad; moving away at 0.25 rad/s for
    /// 30 ms: beyond the healthy runs' tracking of the stance shank
    /// (the campaign's and the clinical families'), and reached within a
    /// few hundred milliseconds of a pilot who stops balancing
    /// (`docs/safety.md`, `docs/campaign.md`).
    pub const DEFAULT: Self = Self {
        idle: ErrorBounds {
            feet_down_rad: 0.1,
            swing_rad: 0.05,
        },
        pushed: ErrorBounds {
            feet_down_rad: 0.2,
            swing_rad: 0.25,
        },
        crutch_rise_n: 40.0,
        crutch_forget_n_per_s: 20.0,
        rate_rad_s: 0.25,
        rate_filter: 0.05,
        ticks: 30,
    };

    /// Whether every value is finite and in range.
    pub(super) fn is_valid(&self) -> bool {
        [
            self.idle.feet_down_rad,
            self.idle.swing_rad,
            self.pushed.feet_down_rad,
            self.pushed.swing_rad,
            self.crutch_rise_n,
            self.crutch_forget_n_per_s,
            self.rate_rad_s,
        ]
        .iter()
        .all(|v| v.is_finite() && *v > 0.0)
            && self.rate_filter > 0.0
            && self.rate_filter <= 1.0
            && self.ticks > 0
    }
}

/// One accepted ankle frame, as the balance check takes it.
#[derive(Debug, Clone, Copy)]
pub(super) struct BalanceSample {
    /// The frame's angle, rad.
    pub(super) angle_rad: f32,
    /// The plan, rad (finite).
    pub(super) plan_rad: f32,
    /// A swing is under way.
    pub(super) swing: bool,
    /// Both crutches' load, N (NaN when a crutch sensor cannot tell).
    pub(super) crutches_n: f32,
    /// Ticks since the previous accepted frame; `None` for a frame that
    /// seeds the track (the first, or one after a long gap).
    pub(super) elapsed_ticks: Option<u32>,
}

/// One ankle's error and its rate.
#[derive(Debug, Clone, Copy)]
pub(super) struct BalanceTrack {
    /// The last accepted frame's error, rad (NaN: none since the plan
    /// began or the track was seeded).
    error_rad: f32,
    /// Its plan, rad.
    plan_rad: f32,
    /// The error's filtered rate, rad/s.
    rate_rad_s: f32,
    /// The least crutches' sum lately, N, rising at the forgetting rate
    /// (NaN: none read yet). Kept across restarts: a swing's plan begins
    /// with the pilot already pushing.
    crutches_least_n: f32,
    /// |error| on the counting frame [`growth_from`] of the count, rad.
    grown_from_rad: f32,
    /// Consecutive counting frames.
    ticks: u32,
}

impl Default for BalanceTrack {
    fn default() -> Self {
        Self {
            error_rad: f32::NAN,
            plan_rad: f32::NAN,
            rate_rad_s: 0.0,
            crutches_least_n: f32::NAN,
            grown_from_rad: 0.0,
            ticks: 0,
        }
    }
}

impl BalanceTrack {
    /// No plan this tick: start again (the crutches' least value kept).
    pub(super) fn restart(&mut self) {
        *self = Self {
            crutches_least_n: self.crutches_least_n,
            ..Self::default()
        };
    }

    /// An accepted frame, `dt_s` a tick; returns the error once the
    /// fault's condition has held for `cfg.ticks` frames and the error
    /// has grown over the last two thirds of them by at least half what
    /// the rate bound implies (a filtered rate remembers a quick change
    /// for tens of frames: an error that jumped and then stood still does
    /// not count; the growth, 0.0025 rad by default, is above a few
    /// counts of noise).
    pub(super) fn update(
        &mut self,
        cfg: &BalanceCheck,
        sample: &BalanceSample,
        dt_s: f32,
    ) -> Option<f32> {
        // A step in the plan, or the first plan (NaN): start again.
        let same_motion = (sample.plan_rad - self.plan_rad).abs() <= PLAN_STEP_RAD;
        if !same_motion {
            self.restart();
        }
        // Unknown crutches (NaN) neither move the least value nor lower
        // the bound.
        let crutches_n = sample.crutches_n;
        let forgotten = self.crutches_least_n + cfg.crutch_forget_n_per_s * dt_s;
        if crutches_n.is_finite() {
            self.crutches_least_n = if forgotten < crutches_n {
                forgotten
            } else {
                crutches_n
            };
        }
        self.plan_rad = sample.plan_rad;
        let e = sample.angle_rad - sample.plan_rad;
        match sample.elapsed_ticks {
            // A seed after a gap: no rate across it.
            None => {
                self.rate_rad_s = 0.0;
                self.ticks = 0;
            }
            Some(n) if self.error_rad.is_finite() => {
                let raw = (e - self.error_rad) / (n.max(1) as f32 * dt_s);
                self.rate_rad_s += cfg.rate_filter * (raw - self.rate_rad_s);
            }
            Some(_) => {}
        }
        self.error_rad = e;
        let growing = e * self.rate_rad_s > 0.0 && self.rate_rad_s.abs() > cfg.rate_rad_s;
        let idle = crutches_n < self.crutches_least_n + cfg.crutch_rise_n;
        let bounds = if idle { &cfg.idle } else { &cfg.pushed };
        let bound = if sample.swing {
            bounds.swing_rad
        } else {
            bounds.feet_down_rad
        };
        let from = growth_from(cfg.ticks);
        if e.abs() > bound && growing {
            self.ticks = self.ticks.saturating_add(1);
            if self.ticks == from {
                self.grown_from_rad = e.abs();
            }
        } else {
            self.ticks = 0;
        }
        let least_growth = 0.5 * cfg.rate_rad_s * cfg.ticks.saturating_sub(from) as f32 * dt_s;
        let grown = e.abs() - self.grown_from_rad >= least_growth;
        (self.ticks >= cfg.ticks && grown).then_some(e)
    }
}

/// The counting frame from which the error must have grown: a third of
/// the way into the count (at least the first).
const fn growth_from(ticks: u32) -> u32 {
    let third = ticks / 3;
    if third == 0 { 1 } else { third }
}
