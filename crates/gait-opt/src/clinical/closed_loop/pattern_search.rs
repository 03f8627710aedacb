//! The closed-loop refinement's search: Hooke–Jeeves pattern search in
//! the unit box (why this method: the parent module's documentation). It
//! only compares objective values, so a rejected point is an infinite one.

use super::RefineConfig;
use crate::clinical::DIM;

/// Hooke–Jeeves pattern search in the unit box from `x0` (value `f0`):
/// exploratory moves ± `step` along each coordinate (the first improving
/// sign kept), then pattern moves along the displacement they made, kept
/// while the exploration around them improves on the base; the step halves
/// after an exploration without improvement. Stops below `min_step` or when
/// the next exploration could exceed the budget. Returns every point that
/// improved on the best so far, in order, with its value, and the
/// evaluations spent (each improvement with the evaluations spent when
/// it was found).
pub(super) fn pattern_search(
    x0: [f64; DIM],
    f0: f64,
    config: &RefineConfig,
    f: impl FnMut(&[f64; DIM]) -> f64,
    progress: &mut dyn FnMut(usize, f64),
) -> (Vec<([f64; DIM], f64, usize)>, usize) {
    let mut s = Search {
        f,
        evals: 0,
        best: f0,
        improvements: Vec::new(),
        progress,
    };
    let mut base = (x0, f0);
    let mut step = config.initial_step;
    while step >= config.min_step && s.evals + 2 * DIM <= config.max_evals {
        let found = s.explore(base, step);
        if found.1 >= base.1 {
            step *= 0.5;
            (s.progress)(s.evals, s.best);
            continue;
        }
        // Pattern moves while they pay.
        let mut prev = base;
        base = found;
        while s.evals + 2 * DIM < config.max_evals {
            let mut p = base.0;
            for (pi, (b, a)) in p.iter_mut().zip(base.0.iter().zip(prev.0.iter())) {
                *pi = (2.0 * b - a).clamp(0.0, 1.0);
            }
            let fp = s.eval(&p);
            let around = s.explore((p, fp), step);
            if around.1 < base.1 {
                prev = base;
                base = around;
            } else {
                break;
            }
        }
    }
    (s.improvements, s.evals)
}

/// The pattern search's state: the objective, the evaluations spent and
/// the improvements on the best so far.
struct Search<'p, F> {
    f: F,
    evals: usize,
    best: f64,
    improvements: Vec<([f64; DIM], f64, usize)>,
    progress: &'p mut dyn FnMut(usize, f64),
}

impl<F: FnMut(&[f64; DIM]) -> f64> Search<'_, F> {
    fn eval(&mut self, x: &[f64; DIM]) -> f64 {
        let v = (self.f)(x);
        self.evals += 1;
        if v < self.best {
            self.best = v;
            self.improvements.push((*x, v, self.evals));
            (self.progress)(self.evals, v);
        }
        v
    }

    /// One exploratory sweep around `from`.
    fn explore(&mut self, from: ([f64; DIM], f64), step: f64) -> ([f64; DIM], f64) {
        let (mut x, mut fx) = from;
        for i in 0..DIM {
            for sign in [1.0, -1.0] {
                let mut y = x;
                y[i] = (y[i] + sign * step).clamp(0.0, 1.0);
                if y[i] == x[i] {
                    continue;
                }
                let fy = self.eval(&y);
                if fy < fx {
                    x = y;
                    fx = fy;
                    break;
                }
            }
        }
        (x, fx)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::{DIM, RefineConfig, pattern_search};

    fn config(max_evals: usize) -> RefineConfig {
        RefineConfig {
            search_steps: 1,
            max_evals,
            initial_step: 0.02,
            min_step: 1e-6,
        }
    }

    #[test]
    fn the_pattern_search_walks_down_a_valley_far_from_its_start() {
        // A narrow valley along (1, 1, …): pattern moves follow it.
        let target = 0.8;
        let f = |x: &[f64; DIM]| {
            let mean = x.iter().sum::<f64>() / DIM as f64;
            let spread: f64 = x.iter().map(|v| (v - mean).powi(2)).sum();
            (mean - target).powi(2) + 10.0 * spread
        };
        let x0 = [0.2; DIM];
        let (improvements, evals) = pattern_search(x0, f(&x0), &config(20_000), f, &mut |_, _| {});
        let (x, v, n) = *improvements.last().unwrap();
        assert!(v < 1e-8, "{v}");
        assert!(x.iter().all(|&xi| (xi - target).abs() < 1e-3), "{x:?}");
        assert!(n <= evals && evals <= 20_000);
        // Improvements are in order and each better than the last.
        assert!(
            improvements
                .windows(2)
                .all(|w| w[1].1 < w[0].1 && w[1].2 > w[0].2)
        );
    }

    #[test]
    fn rejected_points_are_never_kept_and_the_box_is_kept() {
        // Everything with x0 > 0.5 is rejected; the minimum is outside the
        // box in the other coordinates.
        let f = |x: &[f64; DIM]| {
            if x[0] > 0.5 {
                f64::INFINITY
            } else {
                -x.iter().sum::<f64>()
            }
        };
        let x0 = [0.45; DIM];
        let (improvements, _) = pattern_search(x0, f(&x0), &config(5_000), f, &mut |_, _| {});
        let (x, _, _) = *improvements.last().unwrap();
        assert!(x[0] <= 0.5 && x[0] > 0.49, "{}", x[0]);
        assert!(x.iter().skip(1).all(|&v| v == 1.0), "{x:?}");
    }

    #[test]
    fn the_budget_is_kept() {
        let f = |x: &[f64; DIM]| x.iter().map(|v| (v - 0.3).powi(2)).sum::<f64>();
        let x0 = [0.9; DIM];
        let mut seen = 0;
        let (_, evals) = pattern_search(x0, f(&x0), &config(100), f, &mut |n, _| seen = n);
        assert!(evals <= 100 && seen <= evals, "{evals}");
    }
}
