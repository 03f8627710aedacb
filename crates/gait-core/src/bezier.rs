//! Bézier curves in the standard Bernstein form (paper eq. (Brcurve),
//! (Brcurve2)).
//!
//! The paper prints the quartic and cubic basis matrices with their rows in
//! reverse order: multiplied out as printed, [1 u u² u³ u⁴]·M·P does not pass
//! through P0 at u = 0 (it evaluates to P4). The standard form
//! B(u) = Σ C(n,i) uⁱ (1−u)ⁿ⁻ⁱ P_i is what the text describes ("the curve
//! will always go through the first control point and last control point"),
//! and is what is used here.
//!
//! Curves are kept in power-basis coefficients (converted once from the
//! control points) so that each evaluation is a Horner scheme: the gait
//! sampler evaluates every curve on a grid of at least 2,001 points.

use crate::scalar::Real;

/// A planar Bézier curve of `N` control points (degree `N − 1`), stored as
/// power-basis coefficients for fast evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bezier<T, const N: usize> {
    control: [[T; 2]; N],
    coeffs: [[T; 2]; N],
}

impl<T: Real, const N: usize> Bezier<T, N> {
    /// A curve through these control points (rows `[a, b]`, e.g. `[t, r2]`).
    pub fn new(control: [[T; 2]; N]) -> Self {
        // Power-basis coefficient k = C(n,k) Σ_{i≤k} (−1)^{k−i} C(k,i) P_i.
        let n = N.saturating_sub(1);
        let mut coeffs = [[T::zero(); 2]; N];
        for (k, ck) in coeffs.iter_mut().enumerate() {
            let outer = T::lit(binomial(n, k));
            for (i, p) in control.iter().enumerate().take(k + 1) {
                let sign = if (k - i) % 2 == 0 {
                    T::one()
                } else {
                    -T::one()
                };
                let w = outer * sign * T::lit(binomial(k, i));
                ck[0] += w * p[0];
                ck[1] += w * p[1];
            }
        }
        Self { control, coeffs }
    }

    /// The control points.
    pub fn control(&self) -> &[[T; 2]; N] {
        &self.control
    }

    /// Evaluates both coordinates at parameter `u` (Horner in power basis).
    #[inline]
    pub fn eval(&self, u: T) -> [T; 2] {
        let mut a = T::zero();
        let mut b = T::zero();
        for c in self.coeffs.iter().rev() {
            a = a * u + c[0];
            b = b * u + c[1];
        }
        [a, b]
    }

    /// Reference evaluation by de Casteljau's algorithm (numerically the most
    /// robust form; used to cross-check [`Bezier::eval`]).
    pub fn eval_de_casteljau(&self, u: T) -> [T; 2] {
        let mut pts = self.control;
        let one_minus = T::one() - u;
        for level in (1..N).rev() {
            for i in 0..level {
                let next = pts.get(i + 1).copied();
                if let (Some(q), Some(p)) = (next, pts.get_mut(i)) {
                    p[0] = one_minus * p[0] + u * q[0];
                    p[1] = one_minus * p[1] + u * q[1];
                }
            }
        }
        pts.first().copied().unwrap_or([T::zero(); 2])
    }
}

/// Binomial coefficient C(n, k) for the small degrees used here.
fn binomial(n: usize, k: usize) -> f64 {
    if k > n {
        return 0.0;
    }
    let mut r = 1.0;
    for i in 0..k {
        r = r * (n - i) as f64 / (i + 1) as f64;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quartic() -> Bezier<f64, 5> {
        Bezier::new([[0.0, 0.94], [0.3, 0.2], [1.1, 0.9], [1.9, 0.1], [2.24, 0.5]])
    }

    #[test]
    fn passes_through_end_points() {
        let c = quartic();
        assert_eq!(c.eval(0.0), [0.0, 0.94]);
        let e = c.eval(1.0);
        assert!((e[0] - 2.24).abs() < 1e-14 && (e[1] - 0.5).abs() < 1e-14);
    }

    #[test]
    fn paper_matrix_as_printed_is_reversed() {
        // Row 0 of the printed quartic matrix is [1 −4 6 −4 1]: at u = 0 the
        // printed form gives P0 − 4P1 + 6P2 − 4P3 + P4, the 4th forward
        // difference, not P0. Reversing the rows gives the Bernstein form.
        let m: [[f64; 5]; 5] = [
            [1.0, -4.0, 6.0, -4.0, 1.0],
            [-4.0, 12.0, -12.0, 4.0, 0.0],
            [6.0, -12.0, 6.0, 0.0, 0.0],
            [-4.0, 4.0, 0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0, 0.0, 0.0],
        ];
        let c = quartic();
        let p = c.control();
        let printed_at = |u: f64, rows_reversed: bool| {
            let pw = [1.0, u, u * u, u * u * u, u * u * u * u];
            let mut out = 0.0;
            for (i, w) in pw.iter().enumerate() {
                let row = if rows_reversed { m[4 - i] } else { m[i] };
                for (j, mij) in row.iter().enumerate() {
                    out += w * mij * p[j][1];
                }
            }
            out
        };
        assert!((printed_at(0.0, false) - p[0][1]).abs() > 0.1);
        for k in 0..=10 {
            let u = k as f64 / 10.0;
            assert!((printed_at(u, true) - c.eval(u)[1]).abs() < 1e-12);
        }
    }

    #[test]
    fn horner_matches_de_casteljau() {
        let c = quartic();
        for k in 0..=100 {
            let u = k as f64 / 100.0;
            let a = c.eval(u);
            let b = c.eval_de_casteljau(u);
            assert!((a[0] - b[0]).abs() < 1e-13 && (a[1] - b[1]).abs() < 1e-13);
        }
        let cubic = Bezier::new([[0.0, 0.0], [0.5, 0.9], [1.0, 0.1], [2.0, 1.0]]);
        for k in 0..=100 {
            let u = k as f64 / 100.0;
            let a = cubic.eval(u);
            let b = cubic.eval_de_casteljau(u);
            assert!((a[0] - b[0]).abs() < 1e-13 && (a[1] - b[1]).abs() < 1e-13);
        }
    }
}
