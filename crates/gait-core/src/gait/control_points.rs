//! The paper's control-point matrix P and the names of its rows: which
//! rows hold which curve, and within a curve which control point a bound or
//! a pin applies to. Kept apart so that every use of a row goes through a
//! name.

/// Rows of the control-point matrix P.
pub const CONTROL_ROWS: usize = 19;

/// The paper's control-point matrix P (19 rows of two columns), SI units.
pub type ControlPoints<T> = [[T; 2]; CONTROL_ROWS];

/// Where one curve's control points sit in P: `count` consecutive rows from
/// `first`. The rows' names ([`CurveRows::start`], [`CurveRows::second`],
/// [`CurveRows::second_last`], [`CurveRows::end`]) say which control point
/// a bound or a pin applies to, instead of a bare row number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CurveRows {
    first: usize,
    count: usize,
}

impl CurveRows {
    /// The first control point's row (the curve's value at its start).
    pub const fn start(self) -> usize {
        self.first
    }

    /// The second control point's row (with the first, it sets the rate at
    /// the start).
    pub const fn second(self) -> usize {
        self.first.saturating_add(1)
    }

    /// The second-to-last control point's row (with the last, it sets the
    /// rate at the end).
    pub const fn second_last(self) -> usize {
        self.first.saturating_add(self.count).saturating_sub(2)
    }

    /// The last control point's row (the curve's value at its end).
    pub const fn end(self) -> usize {
        self.first.saturating_add(self.count).saturating_sub(1)
    }

    /// The rows as `[first, end)`, end exclusive.
    pub const fn span(self) -> [usize; 2] {
        [self.first, self.first.saturating_add(self.count)]
    }

    /// Number of control points.
    pub const fn count(self) -> usize {
        self.count
    }
}

/// (t, r2): rows 0–4.
pub const R2_ROWS: CurveRows = CurveRows { first: 0, count: 5 };
/// (t, φ3): rows 5–9.
pub const PHI3_ROWS: CurveRows = CurveRows { first: 5, count: 5 };
/// (x5, y5), the swing-ankle path as a curve of z: rows 10–14.
pub const PATH_ROWS: CurveRows = CurveRows {
    first: 10,
    count: 5,
};
/// (t, z), the pace: rows 15–18.
pub const PACE_ROWS: CurveRows = CurveRows {
    first: 15,
    count: 4,
};
