//! Measurement noise for the simulated converters: uniform integer noise of
//! a set amplitude (in counts), from a seeded xorshift generator so that a
//! scenario is reproducible. Written here rather than taken from `rand`: a
//! dozen lines, one distribution, and a fixed sequence per seed across
//! library versions.

use std::cell::Cell;

/// Uniform noise in [−amplitude, +amplitude] counts.
#[derive(Clone, Debug)]
pub struct Noise {
    amplitude: u16,
    state: Cell<u64>,
}

impl Noise {
    /// Noise of `amplitude` counts (0: none), seeded.
    pub fn new(amplitude: u16, seed: u64) -> Self {
        Self {
            amplitude,
            // xorshift must not start at 0.
            state: Cell::new(seed | 1),
        }
    }

    /// No noise.
    pub fn none() -> Self {
        Self::new(0, 1)
    }

    /// The next sample, counts.
    pub fn sample(&self) -> i64 {
        if self.amplitude == 0 {
            return 0;
        }
        let mut x = self.state.get();
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.state.set(x);
        let span = 2 * u64::from(self.amplitude) + 1;
        (x % span) as i64 - i64::from(self.amplitude)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stays_in_range_covers_it_and_repeats_per_seed() {
        let n = Noise::new(3, 42);
        let samples: Vec<i64> = (0..10_000).map(|_| n.sample()).collect();
        assert!(samples.iter().all(|s| (-3..=3).contains(s)));
        for v in -3..=3 {
            let share = samples.iter().filter(|&&s| s == v).count() as f64 / 10_000.0;
            assert!((share - 1.0 / 7.0).abs() < 0.02, "{v}: {share}");
        }
        let again = Noise::new(3, 42);
        assert!(samples.iter().take(100).all(|&s| s == again.sample()));
        assert_eq!(Noise::none().sample(), 0);
    }
}
