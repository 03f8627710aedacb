//! The ground the feet land on.

/// Ground profile in the sagittal plane (world frame: x forward, y up, the
/// first stance foot at x = 0 on y = 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Terrain {
    /// Flat ground at y = 0.
    Level,
    /// A staircase going up: flat at y = 0 before `start_x_m`, then `steps`
    /// steps of `rise_m` whose treads are `tread_m` deep; the top landing
    /// continues flat at `steps · rise_m`.
    Stairs {
        /// x of the first riser, m.
        start_x_m: f64,
        /// Step height, m (negative: a staircase going down).
        rise_m: f64,
        /// Tread depth, m.
        tread_m: f64,
        /// Number of steps.
        steps: u32,
    },
}

impl Terrain {
    /// Ground height at `x_m`, m.
    pub fn height_m(&self, x_m: f64) -> f64 {
        match *self {
            Self::Level => 0.0,
            Self::Stairs {
                start_x_m,
                rise_m,
                tread_m,
                steps,
            } => {
                if x_m < start_x_m || tread_m <= 0.0 || !x_m.is_finite() {
                    return 0.0;
                }
                let n = ((x_m - start_x_m) / tread_m).floor() + 1.0;
                rise_m * n.min(f64::from(steps))
            }
        }
    }

    /// Whether the parameters make sense (finite, positive tread and rise
    /// of either sign).
    pub fn is_valid(&self) -> bool {
        match *self {
            Self::Level => true,
            Self::Stairs {
                start_x_m,
                rise_m,
                tread_m,
                ..
            } => start_x_m.is_finite() && rise_m.is_finite() && tread_m > 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stairs_profile() {
        let t = Terrain::Stairs {
            start_x_m: 0.2,
            rise_m: 0.15,
            tread_m: 0.3,
            steps: 2,
        };
        assert_eq!(t.height_m(0.0), 0.0);
        assert_eq!(t.height_m(0.19), 0.0);
        assert!((t.height_m(0.21) - 0.15).abs() < 1e-12);
        assert!((t.height_m(0.51) - 0.30).abs() < 1e-12);
        assert!((t.height_m(5.0) - 0.30).abs() < 1e-12);
        assert_eq!(Terrain::Level.height_m(3.0), 0.0);
    }
}
