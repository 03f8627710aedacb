//! The search space: 22 free entries of P, mapped from an unconstrained
//! vector so that every point the optimiser proposes is a P inside
//! eq. (cons) with non-decreasing time control points.
//!
//! Each free entry has a coordinate x_i whose box is [0, 1]:
//! value = lo + clamp(x_i, 0, 1) · (hi − lo), with (lo, hi) from
//! [`PaperProblem::bounds`]. The interior time control points of one curve
//! (three for r2 and φ3, two for the pace z) are clamped the same way and
//! then *sorted*, which maps the cube onto the ordered simplex
//! 0 ≤ t1 ≤ t2 ≤ t3 ≤ ts (continuous, and the identity where already
//! ordered). Outside the box the optimiser pays a quadratic penalty on the
//! distance to it ([`Encoding::box_violation`]), which pulls the search
//! distribution back without making the cost discontinuous at the faces.

use gait_core::gait::ControlPoints;
use gait_core::problem::PaperProblem;

/// Number of free variables.
pub const DIM: usize = 22;

/// (row, col) of P that each coordinate sets.
const SLOTS: [(usize, usize); DIM] = [
    // r2: interior times (sorted group 0), then values of rows 1–4.
    (1, 0),
    (2, 0),
    (3, 0),
    (1, 1),
    (2, 1),
    (3, 1),
    (4, 1),
    // φ3: interior times (sorted group 1), values of rows 6–9.
    (6, 0),
    (7, 0),
    (8, 0),
    (6, 1),
    (7, 1),
    (8, 1),
    (9, 1),
    // Path: y of row 11, (x, y) of row 12, y of row 13.
    (11, 1),
    (12, 0),
    (12, 1),
    (13, 1),
    // Pace: interior times (sorted group 2), then z of rows 16, 17.
    (16, 0),
    (17, 0),
    (16, 1),
    (17, 1),
];

/// Coordinate ranges whose values are sorted after clamping (time
/// control points of one curve).
const SORTED: [(usize, usize); 3] = [(0, 3), (7, 10), (18, 20)];

/// The map between the unconstrained search vector and P.
#[derive(Clone, Copy, Debug)]
pub struct Encoding {
    lo: ControlPoints<f64>,
    hi: ControlPoints<f64>,
}

impl Encoding {
    /// The encoding for a problem's bounds. Every entry of P that is not
    /// free is fixed by the bounds (lower = upper).
    pub fn new(problem: &PaperProblem<f64>) -> Self {
        let (lo, hi) = problem.bounds();
        Self { lo, hi }
    }

    fn range(&self, (r, c): (usize, usize)) -> (f64, f64) {
        let lo = self
            .lo
            .get(r)
            .and_then(|row| row.get(c))
            .copied()
            .unwrap_or(0.0);
        let hi = self
            .hi
            .get(r)
            .and_then(|row| row.get(c))
            .copied()
            .unwrap_or(0.0);
        (lo, hi)
    }

    /// P for a search vector (clamped to the box, time groups sorted).
    pub fn decode(&self, x: &[f64]) -> ControlPoints<f64> {
        let mut p = self.lo;
        let mut u = [0.0; DIM];
        for (ui, &xi) in u.iter_mut().zip(x) {
            *ui = if xi.is_finite() {
                xi.clamp(0.0, 1.0)
            } else {
                0.5
            };
        }
        for (a, b) in SORTED {
            if let Some(group) = u.get_mut(a..b) {
                group.sort_by(f64::total_cmp);
            }
        }
        for (&slot, &ui) in SLOTS.iter().zip(&u) {
            let (lo, hi) = self.range(slot);
            let (r, c) = slot;
            if let Some(v) = p.get_mut(r).and_then(|row| row.get_mut(c)) {
                *v = lo + ui * (hi - lo);
            }
        }
        p
    }

    /// A search vector that decodes to `p` (entries clamped to the box).
    pub fn encode(&self, p: &ControlPoints<f64>) -> [f64; DIM] {
        let mut x = [0.5; DIM];
        for (xi, &slot) in x.iter_mut().zip(&SLOTS) {
            let (lo, hi) = self.range(slot);
            let (r, c) = slot;
            let v = p.get(r).and_then(|row| row.get(c)).copied().unwrap_or(lo);
            *xi = if hi > lo {
                ((v - lo) / (hi - lo)).clamp(0.0, 1.0)
            } else {
                0.5
            };
        }
        x
    }

    /// Squared Euclidean distance from `x` to the box [0, 1]^DIM.
    pub fn box_violation(x: &[f64]) -> f64 {
        x.iter()
            .map(|&v| {
                let d = if v < 0.0 {
                    -v
                } else if v > 1.0 {
                    v - 1.0
                } else {
                    0.0
                };
                d * d
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gait_core::problem::PaperCase;

    #[test]
    fn round_trip_and_feasible_anywhere() {
        for case in [PaperCase::Walk, PaperCase::StairUp] {
            let pr = PaperProblem::<f64>::paper(case);
            let e = Encoding::new(&pr);
            let p0 = pr.initial_guess();
            let back = e.decode(&e.encode(&p0));
            for (a, b) in p0.iter().flatten().zip(back.iter().flatten()) {
                assert!((a - b).abs() < 1e-12, "{a} {b}");
            }
            // Far outside the box and unordered: still inside eq. (cons).
            let mut x = [0.0; DIM];
            for (i, xi) in x.iter_mut().enumerate() {
                *xi = ((i * 37 % 11) as f64 - 5.0) * 0.4;
            }
            pr.check_feasible(&e.decode(&x)).unwrap();
            assert!(Encoding::box_violation(&x) > 0.0);
        }
    }
}
