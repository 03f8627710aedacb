//! A pilot who has stopped balancing (0x0703), seen at the crutches alone.
//!
//! The ankles are passive: in a swing, whatever torque the stance ankle
//! needs beyond its spring comes from the pilot pushing on the crutches,
//! and the push comes and goes with the step. A pilot who balances never
//! leaves the crutches at their resting load for long in a swing: only
//! while the torque the step needs of the ankle passes slowly through zero
//! (332 ticks at most in the built-in gaits without sensor noise, 76 with
//! the device's; 600–800 in some fitted families' stair descents). One who
//! has stopped leaves them there for good. A descent's stance heel is on
//! its stop for most of the swing, so the ankle's error (0x0701, 0x0702)
//! does not see such a pilot until the body has sunk back for a second or
//! more. The window is set by the healthy rests, not by the falls it could
//! save: the torque the plan needs of the ankle, which would tell a rest
//! the step asks for from one it does not, is not among the check's facts.
//!
//! The resting load is the least sum the crutches carried lately, a
//! minimum that forgets at a fixed rate (as the balance check's: it follows
//! a pilot's resting lean, not the push of a step). A tick counts while a
//! swing is under way and the sum stays within [`CrutchIdleCheck::rise_n`]
//! of it; a tick a sensor cannot tell (NaN) neither counts, nor restarts
//! the count, nor moves the least value (a sensor that fails now and then,
//! below its own debounce, must not hide a pilot who has stopped). The end
//! of a swing restarts it. A push that rises slower than the least value
//! forgets (20 N/s) counts as rest: a pilot's push comes and goes within a
//! step.

/// Settings of the idle-crutches check (0x0703).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CrutchIdleCheck {
    /// The crutches are idle while their sum is within this of the least
    /// they carried lately, N.
    pub rise_n: f32,
    /// How fast that least value forgets, N/s.
    pub forget_n_per_s: f32,
    /// Consecutive idle ticks of a swing that make the fault.
    pub ticks: u32,
}

impl CrutchIdleCheck {
    /// Within 10 N of the resting load for 800 ms of a swing: above the
    /// longest rest of a healthy swing, the built-in gaits' (332 ticks
    /// without sensor noise) and the stair descents of fitted families
    /// (600 ticks trips two of nine patients' families, 800 none);
    /// `docs/campaign.md` has the window's trade-off.
    pub const DEFAULT: Self = Self {
        rise_n: 10.0,
        forget_n_per_s: 20.0,
        ticks: 800,
    };

    /// Whether every value is finite and in range.
    pub(super) fn is_valid(&self) -> bool {
        self.rise_n.is_finite()
            && self.rise_n > 0.0
            && self.forget_n_per_s.is_finite()
            && self.forget_n_per_s > 0.0
            && self.ticks > 0
    }
}

/// The crutches' resting load and the idle stretch of the present swing.
#[derive(Debug, Clone, Copy)]
pub(super) struct CrutchIdleTrack {
    /// The least sum lately, N (NaN: none read yet).
    least_n: f32,
    /// Consecutive idle ticks of a swing.
    idle_ticks: u32,
}

impl Default for CrutchIdleTrack {
    fn default() -> Self {
        Self {
            least_n: f32::NAN,
            idle_ticks: 0,
        }
    }
}

impl CrutchIdleTrack {
    /// One tick: the crutches' sum `crutches_n` (NaN when a sensor cannot
    /// tell), whether a swing is under way, `dt_s` a tick. The sum above
    /// the resting load once the crutches have been idle for `cfg.ticks`
    /// ticks of a swing.
    pub(super) fn update(
        &mut self,
        cfg: &CrutchIdleCheck,
        crutches_n: f32,
        swinging: bool,
        dt_s: f32,
    ) -> Option<f32> {
        if !crutches_n.is_finite() {
            return None;
        }
        let forgotten = self.least_n + cfg.forget_n_per_s * dt_s;
        // NaN (none yet) compares false: the first sum is the least.
        self.least_n = if forgotten < crutches_n {
            forgotten
        } else {
            crutches_n
        };
        let above = crutches_n - self.least_n;
        self.idle_ticks = if swinging && above < cfg.rise_n {
            self.idle_ticks.saturating_add(1)
        } else {
            0
        };
        (self.idle_ticks >= cfg.ticks).then_some(above)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f32 = 0.001;

    #[test]
    fn idle_crutches_trip_only_after_the_whole_stretch_of_a_swing() {
        let cfg = CrutchIdleCheck::DEFAULT;
        let mut t = CrutchIdleTrack::default();
        // Standing on a resting load of 100 N: never counts.
        for _ in 0..2000 {
            assert_eq!(t.update(&cfg, 100.0, false, DT), None);
        }
        // A swing with the crutches idle: the fault on the last tick of the
        // window.
        for k in 1..=cfg.ticks {
            let found = t.update(&cfg, 104.0, true, DT);
            assert_eq!(found.is_some(), k == cfg.ticks, "tick {k}");
        }
    }

    #[test]
    fn the_device_s_window_is_800_ms_within_10_n() {
        assert_eq!(
            CrutchIdleCheck::DEFAULT,
            CrutchIdleCheck {
                rise_n: 10.0,
                forget_n_per_s: 20.0,
                ticks: 800,
            }
        );
    }

    #[test]
    fn a_push_or_the_end_of_the_swing_restarts_the_count() {
        let cfg = CrutchIdleCheck::DEFAULT;
        let mut t = CrutchIdleTrack::default();
        t.update(&cfg, 100.0, false, DT);
        for _ in 0..cfg.ticks - 1 {
            assert_eq!(t.update(&cfg, 100.0, true, DT), None);
        }
        // A push of 20 N over the resting load: the pilot balances.
        assert_eq!(t.update(&cfg, 120.0, true, DT), None);
        for _ in 0..cfg.ticks - 1 {
            assert_eq!(t.update(&cfg, 100.0, true, DT), None);
        }
        // One tick out of a swing (a landing): the next swing starts anew.
        assert_eq!(t.update(&cfg, 100.0, false, DT), None);
        for _ in 0..cfg.ticks - 1 {
            assert_eq!(t.update(&cfg, 100.0, true, DT), None);
        }
        assert!(t.update(&cfg, 100.0, true, DT).is_some());
    }

    #[test]
    fn a_tick_a_sensor_cannot_tell_neither_counts_nor_restarts() {
        let cfg = CrutchIdleCheck::DEFAULT;
        let mut t = CrutchIdleTrack::default();
        t.update(&cfg, 100.0, false, DT);
        // A sensor failing one tick in 100 (under its own debounce): the
        // stopped pilot is still found, on the window's last idle tick.
        let mut idle = 0;
        let mut found = None;
        for k in 0..2 * cfg.ticks {
            let sum = if k % 100 == 50 { f32::NAN } else { 100.0 };
            idle += u32::from(sum.is_finite());
            if t.update(&cfg, sum, true, DT).is_some() {
                found = Some(idle);
                break;
            }
        }
        assert_eq!(found, Some(cfg.ticks));
    }

    #[test]
    fn the_resting_load_forgets_so_a_pilot_who_leans_harder_is_not_idle() {
        let cfg = CrutchIdleCheck::DEFAULT;
        let mut t = CrutchIdleTrack::default();
        t.update(&cfg, 50.0, false, DT);
        // A pilot who leans 60 N more and keeps it: idle again once the
        // least value has risen to within 10 N of it (50 N at 20 N/s:
        // 2.5 s), then the window.
        for _ in 0..2000 {
            assert_eq!(t.update(&cfg, 110.0, true, DT), None);
        }
        let mut tripped = None;
        for k in 0..4000 {
            if t.update(&cfg, 110.0, true, DT).is_some() {
                tripped = Some(k);
                break;
            }
        }
        // 2,000 ticks before the loop, so about 2,500 − 2,000 + 800.
        assert!(
            tripped.is_some_and(|k| (1290..=1310).contains(&k)),
            "{tripped:?}"
        );
    }
}
