//! Compass (pattern) search in the unit box: the polish both searches (paper
//! mode and clinical mode) end with after CMA-ES. Derivative-free, so the
//! kinks and jumps of their costs are harmless.

/// From `x` (value `f_x`), tries ± `step` along each coordinate in turn
/// (clamped to [0, 1]) and moves on the first improvement; halves the step
/// after a sweep without one. Stops once the step is below `min_step` or a
/// whole sweep would exceed `budget` evaluations. `eval` scores a point
/// through `state`; `after_sweep` sees `state` and the best value after each
/// sweep. Returns the best point, its value and the evaluations spent.
pub(crate) fn compass_search<S, const N: usize>(
    state: &mut S,
    mut x: [f64; N],
    f_x: f64,
    min_step: f64,
    budget: usize,
    mut eval: impl FnMut(&mut S, &[f64; N]) -> f64,
    mut after_sweep: impl FnMut(&S, f64),
) -> ([f64; N], f64, usize) {
    let mut best = f_x;
    let mut used = 0;
    let mut step = 0.02;
    while step > min_step && used + 2 * N <= budget {
        let mut improved = false;
        for i in 0..N {
            for sign in [1.0, -1.0] {
                let mut y = x;
                if let Some(v) = y.get_mut(i) {
                    *v = (*v + sign * step).clamp(0.0, 1.0);
                }
                let f = eval(state, &y);
                used += 1;
                if f < best {
                    best = f;
                    x = y;
                    improved = true;
                    break;
                }
            }
        }
        if !improved {
            step *= 0.5;
        }
        after_sweep(state, best);
    }
    (x, best, used)
}

#[cfg(test)]
mod tests {
    use super::compass_search;

    #[test]
    fn finds_the_minimum_of_a_bowl_in_the_box_within_its_budget() {
        let target = [0.3, 0.71, 0.05];
        let bowl = |_: &mut (), y: &[f64; 3]| -> f64 {
            y.iter().zip(target).map(|(a, b)| (a - b) * (a - b)).sum()
        };
        let mut sweeps = 0;
        let (x, f, used) = compass_search(
            &mut (),
            [0.5; 3],
            bowl(&mut (), &[0.5; 3]),
            1e-6,
            10_000,
            bowl,
            |_, _| sweeps += 1,
        );
        assert!(f < 1e-10, "{f}");
        for (a, b) in x.iter().zip(target) {
            assert!((a - b).abs() < 1e-5, "{x:?}");
        }
        assert!(used <= 10_000 && sweeps > 0);
        // A budget smaller than one sweep spends nothing.
        let (x, _, used) = compass_search(&mut (), [0.5; 3], 1.0, 1e-6, 5, bowl, |_, _| {});
        assert_eq!((x, used), ([0.5; 3], 0));
    }

    #[test]
    fn stays_inside_the_unit_box() {
        // The minimum is outside the box: the search stops on its face.
        let slope = |_: &mut (), y: &[f64; 2]| y[0] - y[1];
        let (x, _, _) = compass_search(&mut (), [0.5; 2], 0.0, 1e-6, 1_000, slope, |_, _| {});
        assert_eq!(x, [0.0, 1.0]);
    }
}
