//! Eq. (cons): the box B ≼ P ≼ U each control point must lie in, the time
//! order of each curve's control points, and a simple feasible starting
//! point. Kept apart from the cost so that the feasible set can be read (and
//! checked against a report's stored copy) on its own.

use super::PaperProblem;
use crate::gait::{ControlPoints, GaitError, PACE_ROWS, PHI3_ROWS, R2_ROWS};
use crate::scalar::Real;

/// Why P is outside the feasible set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Infeasible {
    /// Entry (row, column) of P violates B ≼ P ≼ U.
    Bound {
        /// Row of P.
        row: usize,
        /// Column of P (0 = time or x, 1 = value or y).
        col: usize,
    },
    /// The interior time control points of a curve decrease (row of the
    /// second point of the offending pair).
    TimeOrder {
        /// Row of P.
        row: usize,
    },
    /// Sampling or IK failed (see [`GaitError`]).
    Gait(GaitError),
}

impl From<GaitError> for Infeasible {
    fn from(e: GaitError) -> Self {
        Self::Gait(e)
    }
}

impl core::fmt::Display for Infeasible {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Bound { row, col } => write!(f, "P[{row}][{col}] is outside its bounds"),
            Self::TimeOrder { row } => write!(f, "time control points decrease at row {row}"),
            Self::Gait(e) => write!(f, "{e}"),
        }
    }
}

/// Rows of P whose time column must be non-decreasing, per curve, as
/// `[first, end)`: r2 (0–4), φ3 (5–9) and the pace z (15–18); the path
/// (10–14) has no time column.
pub const TIME_ORDERED_ROWS: [[usize; 2]; 3] = [R2_ROWS.span(), PHI3_ROWS.span(), PACE_ROWS.span()];

/// An entry of a stored copy of eq. (cons)'s bounds (e.g. a report's) that
/// does not follow from the problem ([`PaperProblem::check_bounds_copy`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundsMismatch<T> {
    /// The upper bound U (else the lower bound B).
    pub upper: bool,
    /// Row of P.
    pub row: usize,
    /// Column of P.
    pub col: usize,
    /// The stored value.
    pub stored: T,
    /// The value eq. (cons) gives.
    pub derived: T,
}

impl<T: Real> PaperProblem<T> {
    /// Checks a stored copy (B, U) of eq. (cons)'s bounds against
    /// [`PaperProblem::bounds`], entry by entry to a relative 1e-12.
    pub fn check_bounds_copy(
        &self,
        lower: &ControlPoints<T>,
        upper: &ControlPoints<T>,
    ) -> Result<(), BoundsMismatch<T>> {
        let (lo, hi) = self.bounds();
        let tol = T::lit(1e-12);
        for (is_upper, stored, derived) in [(false, lower, &lo), (true, upper, &hi)] {
            for (row, (a, b)) in stored.iter().zip(derived).enumerate() {
                for (col, (&x, &y)) in a.iter().zip(b).enumerate() {
                    if (x - y).abs() > tol * (T::one() + y.abs()) {
                        return Err(BoundsMismatch {
                            upper: is_upper,
                            row,
                            col,
                            stored: x,
                            derived: y,
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// Eq. (cons): the lower and upper bound matrices (B, U), SI units.
    pub fn bounds(&self) -> (ControlPoints<T>, ControlPoints<T>) {
        let c = &self.case;
        let ts = c.step_time_s;
        let (z, one) = (T::zero(), T::one());
        let [x0, y0] = c.start_m;
        let [xs, ys] = c.landing_m;
        let lift = T::lit(0.3);
        let top = T::lit(0.6);
        let tilt = T::lit(core::f64::consts::PI / 12.0);
        let mut lo: ControlPoints<T> = [
            [z, c.r2_start],
            [z, z],
            [z, z],
            [z, z],
            [ts, z],
            [z, c.phi3_start_rad],
            [z, -tilt],
            [z, -tilt],
            [z, -tilt],
            [ts, -tilt],
            [x0, y0],
            [x0, y0 + lift],
            [x0, y0.min(ys)],
            [xs, ys + lift],
            [xs, ys],
            [z, z],
            [z, z],
            [z, z],
            [ts, one],
        ];
        let mut hi: ControlPoints<T> = [
            [z, c.r2_start],
            [ts, one],
            [ts, one],
            [ts, one],
            [ts, one],
            [z, c.phi3_start_rad],
            [ts, tilt],
            [ts, tilt],
            [ts, tilt],
            [ts, tilt],
            [x0, y0],
            [x0, top],
            [xs, top],
            [xs, top],
            [xs, ys],
            [z, z],
            [ts, one],
            [ts, one],
            [ts, one],
        ];
        let mut pin = |row: usize, v: T| {
            for m in [&mut lo, &mut hi] {
                if let Some(cell) = m.get_mut(row).and_then(|r| r.get_mut(1)) {
                    *cell = v;
                }
            }
        };
        if let Some(end) = c.end_posture {
            pin(R2_ROWS.end(), end.r2);
            pin(PHI3_ROWS.end(), end.phi3_rad);
            if c.rest_at_ends {
                pin(R2_ROWS.second_last(), end.r2);
                pin(PHI3_ROWS.second_last(), end.phi3_rad);
            }
        }
        if c.rest_at_ends {
            // Second control value = first: zero rate at t = 0; z's
            // second-to-last = 1: zero pace at the landing.
            pin(R2_ROWS.second(), c.r2_start);
            pin(PHI3_ROWS.second(), c.phi3_start_rad);
            pin(PACE_ROWS.second(), z);
            pin(PACE_ROWS.second_last(), one);
            // The rate is zero at an end only if the neighbouring time
            // control point is away from it (with t1 = t0 the ratio of the
            // two derivatives is 0/0 and its limit is not zero); keep the
            // neighbours a tenth of the step inside.
            let margin = ts * T::lit(0.1);
            for row in [R2_ROWS.second(), PHI3_ROWS.second(), PACE_ROWS.second()] {
                if let Some(cell) = lo.get_mut(row).and_then(|r| r.get_mut(0)) {
                    *cell = margin;
                }
            }
            for row in [
                R2_ROWS.second_last(),
                PHI3_ROWS.second_last(),
                PACE_ROWS.second_last(),
            ] {
                if let Some(cell) = hi.get_mut(row).and_then(|r| r.get_mut(0)) {
                    *cell = ts - margin;
                }
            }
        }
        (lo, hi)
    }

    /// Checks B ≼ P ≼ U (with a relative slack for rounding) and that each
    /// curve's time control points are non-decreasing.
    pub fn check_feasible(&self, p: &ControlPoints<T>) -> Result<(), Infeasible> {
        let (lo, hi) = self.bounds();
        let slack = T::lit(1e-9);
        for (row, ((pr, lr), hr)) in p.iter().zip(&lo).zip(&hi).enumerate() {
            for (col, ((&v, &l), &h)) in pr.iter().zip(lr).zip(hr).enumerate() {
                let tol = slack * (T::one() + l.abs().max(h.abs()));
                if !v.finite() || v < l - tol || v > h + tol {
                    return Err(Infeasible::Bound { row, col });
                }
            }
        }
        for [start, end] in TIME_ORDERED_ROWS {
            for row in start + 1..end {
                let (Some(a), Some(b)) = (p.get(row - 1), p.get(row)) else {
                    continue;
                };
                if b[0] < a[0] {
                    return Err(Infeasible::TimeOrder { row });
                }
            }
        }
        Ok(())
    }
}

impl<T: Real> PaperProblem<T> {
    /// A simple feasible P: evenly spaced times, constant r2 and φ3, a path
    /// lifted by the bounds' minimum clearance and a linear pace. A starting
    /// point for searches and a fixture for tests, not a good gait.
    pub fn initial_guess(&self) -> ControlPoints<T> {
        let c = &self.case;
        let ts = c.step_time_s;
        let q = |i: f64, n: f64| T::lit(i / n) * ts;
        let [x0, y0] = c.start_m;
        let [xs, ys] = c.landing_m;
        let lift = T::lit(0.3);
        let half = T::lit(0.5);
        let r2 = c.r2_start;
        let p3 = c.phi3_start_rad;
        // A fixed landing posture is reached by a linear blend of the
        // values; otherwise they stay constant.
        let (r2e, p3e) = c.end_posture.map_or((r2, p3), |e| (e.r2, e.phi3_rad));
        // Blend weights of the middle control values: linear, or flat at
        // both ends when the step must start and end at rest.
        let w: [f64; 3] = if c.rest_at_ends {
            [0.0, 0.5, 1.0]
        } else {
            [0.25, 0.5, 0.75]
        };
        let mix = |a: T, b: T, i: usize| a + T::lit(w.get(i).copied().unwrap_or(0.5)) * (b - a);
        let (z1, z2) = if c.rest_at_ends {
            (T::zero(), T::one())
        } else {
            (T::lit(1.0 / 3.0), T::lit(2.0 / 3.0))
        };
        [
            [q(0.0, 4.0), r2],
            [q(1.0, 4.0), mix(r2, r2e, 0)],
            [q(2.0, 4.0), mix(r2, r2e, 1)],
            [q(3.0, 4.0), mix(r2, r2e, 2)],
            [ts, r2e],
            [q(0.0, 4.0), p3],
            [q(1.0, 4.0), mix(p3, p3e, 0)],
            [q(2.0, 4.0), mix(p3, p3e, 1)],
            [q(3.0, 4.0), mix(p3, p3e, 2)],
            [ts, p3e],
            [x0, y0],
            [x0, y0 + lift],
            [(x0 + xs) * half, (y0 + ys) * half + lift],
            [xs, ys + lift],
            [xs, ys],
            [T::zero(), T::zero()],
            [q(1.0, 3.0), z1],
            [q(2.0, 3.0), z2],
            [ts, T::one()],
        ]
    }
}
