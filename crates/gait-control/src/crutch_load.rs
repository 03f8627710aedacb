//! On-board crutch-load measurement: the paper's metric
//! F = T_s Σ (f_l + f_r) and each crutch's peak force, per swing step,
//! kept in a small fixed-size log (the newest steps win).
//!
//! The paper sums 100 Hz samples (T_s = 0.01 s); here every 1 kHz tick is a
//! sample (T_s = the tick period), which is the same integral sampled
//! finer. A step's window runs from the start of its swing to the start of
//! the next swing or until the device stands again, so the load the pilot
//! takes to balance after landing (the paper's observation) is counted.

use crate::ring_log::RingLog;

/// Steps kept in the log.
pub const LOG_STEPS: usize = 12;

/// One step's crutch load.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StepLoad {
    /// Step number since power-up.
    pub step: u32,
    /// F = T_s Σ (f_l + f_r), N·s.
    pub impulse_ns: f32,
    /// Peak left-crutch force, N.
    pub left_peak_n: f32,
    /// Peak right-crutch force, N.
    pub right_peak_n: f32,
    /// Window length, s.
    pub duration_s: f32,
}

/// Accumulates the current step and logs finished ones.
#[derive(Clone, Debug)]
pub struct CrutchLoad {
    current: Option<StepLoad>,
    steps: u32,
    log: RingLog<StepLoad, LOG_STEPS>,
}

impl Default for CrutchLoad {
    fn default() -> Self {
        Self::new()
    }
}

impl CrutchLoad {
    /// An empty log.
    pub fn new() -> Self {
        Self {
            current: None,
            steps: 0,
            log: RingLog::new(),
        }
    }

    /// A swing starts: closes the previous window (if any), opens a new one.
    pub fn begin_step(&mut self) -> Option<StepLoad> {
        let closed = self.end_step();
        self.steps = self.steps.wrapping_add(1);
        self.current = Some(StepLoad {
            step: self.steps,
            impulse_ns: 0.0,
            left_peak_n: 0.0,
            right_peak_n: 0.0,
            duration_s: 0.0,
        });
        closed
    }

    /// The device stands again (or holds): closes the window.
    pub fn end_step(&mut self) -> Option<StepLoad> {
        let done = self.current.take()?;
        self.log.push(done);
        #[cfg(feature = "defmt")]
        defmt::info!(
            "crutch load: step {} F={} N·s peaks L={} N R={} N",
            done.step,
            done.impulse_ns,
            done.left_peak_n,
            done.right_peak_n
        );
        Some(done)
    }

    /// One tick's crutch forces (N; a non-finite reading counts as 0 and is
    /// the supervisor's business).
    pub fn sample(&mut self, left_n: f32, right_n: f32, dt_s: f32) {
        let Some(cur) = self.current.as_mut() else {
            return;
        };
        let clean = |f: f32| if f.is_finite() { f.max(0.0) } else { 0.0 };
        let (l, r) = (clean(left_n), clean(right_n));
        cur.impulse_ns += (l + r) * dt_s;
        cur.left_peak_n = cur.left_peak_n.max(l);
        cur.right_peak_n = cur.right_peak_n.max(r);
        cur.duration_s += dt_s;
    }

    /// The step being measured, if any.
    pub fn current(&self) -> Option<&StepLoad> {
        self.current.as_ref()
    }

    /// Finished steps, oldest first.
    pub fn log(&self) -> impl Iterator<Item = &StepLoad> {
        self.log.iter()
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    #[test]
    fn integrates_forces_and_keeps_peaks() {
        let mut c = CrutchLoad::new();
        c.sample(100.0, 100.0, 0.001); // ignored: no step open
        c.begin_step();
        for k in 0..1000 {
            c.sample(50.0, if k == 500 { 180.0 } else { 30.0 }, 0.001);
        }
        let s = c.end_step();
        assert!(
            s.is_some_and(|s| (s.impulse_ns - (80.0 - 0.03 + 0.18)).abs() < 1e-2),
            "{s:?}"
        );
        assert_eq!(
            s.map(|s| (s.left_peak_n, s.right_peak_n)),
            Some((50.0, 180.0))
        );
        assert!(s.is_some_and(|s| (s.duration_s - 1.0).abs() < 1e-3));
        assert_eq!(c.log().count(), 1);
    }

    #[test]
    fn log_keeps_the_newest_steps() {
        let mut c = CrutchLoad::new();
        for _ in 0..(LOG_STEPS + 5) {
            c.begin_step();
            c.sample(f32::NAN, -3.0, 0.001);
        }
        c.end_step();
        let steps: std::vec::Vec<u32> = c.log().map(|s| s.step).collect();
        assert_eq!(steps.len(), LOG_STEPS);
        assert_eq!(steps.last().copied(), Some((LOG_STEPS + 5) as u32));
        assert!(c.log().all(|s| s.impulse_ns == 0.0));
    }
}
