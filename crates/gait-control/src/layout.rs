//! The device's channel layout, declared once: which joint, ankle, encoder
//! and force sensor sits at which index of the arrays every crate passes
//! around (controller, supervisor, drivers, simulator, logs).
//!
//! Joints: anatomical angles, flexion positive (rad), torques on those
//! coordinates (N·m). Ankles: dorsiflexion positive (rad).

/// Actuated joints: 0 left hip, 1 left knee, 2 right hip, 3 right knee.
pub const JOINTS: usize = 4;
/// Semi-passive ankles: 0 left, 1 right.
pub const ANKLES: usize = 2;
/// Encoders: the four joints (joint order), then left and right ankle.
pub const ENCODERS: usize = JOINTS + ANKLES;
/// Force sensors: 0 left foot, 1 right foot, 2 left crutch, 3 right
/// crutch (N).
pub const FORCES: usize = 4;

/// Index of each joint in the joint order.
pub mod joint {
    /// Left hip.
    pub const LEFT_HIP: usize = 0;
    /// Left knee.
    pub const LEFT_KNEE: usize = 1;
    /// Right hip.
    pub const RIGHT_HIP: usize = 2;
    /// Right knee.
    pub const RIGHT_KNEE: usize = 3;
}

/// Index of each encoder.
pub mod encoder {
    use super::{ANKLES, JOINTS};

    /// The joints' encoders, in joint order.
    pub const OF_JOINTS: [usize; JOINTS] = [0, 1, 2, 3];
    /// The ankles' encoders, left and right.
    pub const OF_ANKLES: [usize; ANKLES] = [JOINTS, JOINTS + 1];
}

/// Index of each force sensor.
pub mod force {
    /// Left foot.
    pub const LEFT_FOOT: usize = 0;
    /// Right foot.
    pub const RIGHT_FOOT: usize = 1;
    /// Left crutch.
    pub const LEFT_CRUTCH: usize = 2;
    /// Right crutch.
    pub const RIGHT_CRUTCH: usize = 3;
    /// The feet's sensors, left and right.
    pub const FEET: [usize; 2] = [LEFT_FOOT, RIGHT_FOOT];
    /// The crutches' sensors, left and right.
    pub const CRUTCHES: [usize; 2] = [LEFT_CRUTCH, RIGHT_CRUTCH];
}

/// A leg (also: which leg carries the body during a step).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Side {
    /// Left leg.
    Left,
    /// Right leg.
    Right,
}

impl Side {
    /// The other leg.
    pub fn other(self) -> Self {
        match self {
            Self::Left => Self::Right,
            Self::Right => Self::Left,
        }
    }

    /// Index in per-side arrays (ankles, feet, crutches): left 0, right 1.
    pub fn index(self) -> usize {
        match self {
            Self::Left => 0,
            Self::Right => 1,
        }
    }

    /// Index of this side's hip in the joint order (its knee is +1).
    pub fn hip(self) -> usize {
        match self {
            Self::Left => joint::LEFT_HIP,
            Self::Right => joint::RIGHT_HIP,
        }
    }

    /// Whether joint `j` (joint order) is on this leg.
    pub fn has_joint(self, j: usize) -> bool {
        j == self.hip() || j == self.hip() + 1
    }

    /// Index of this side's ankle.
    pub fn ankle(self) -> usize {
        self.index()
    }

    /// Index of this side's foot force sensor.
    pub fn foot(self) -> usize {
        match self {
            Self::Left => force::LEFT_FOOT,
            Self::Right => force::RIGHT_FOOT,
        }
    }
}
