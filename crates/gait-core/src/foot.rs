//! The stance foot's geometry: the toe rocker. Once the stance shank leans
//! past the ankle's dorsiflexion stop, the heel lifts and the chain pivots
//! about the ball of the foot instead of the ankle.
//!
//! Why: the paper's model pins the stance ankle with the foot flat, which
//! cannot describe stair descent. In a descent the trailing leg stands on
//! the upper tread while the other foot lands on the lower one; with both
//! feet flat the trailing ankle would need 29–35° of dorsiflexion, past
//! Table I's 20° (test `paper_stair_descent_needs_more_ankle_than_table_i_allows`).
//! People (and passive exoskeleton ankles at their stop) lift the heel.
//!
//! Model (documented in `docs/model.md`, "Toe rocker"):
//! - the foot is massless and rigid; the ankle is free below the stop
//!   `heel_off_rad` and locked at it above (the stop carries the torque);
//! - for φ1 ≤ heel_off the ankle is fixed at the origin (the paper's model);
//!   for φ1 > heel_off the foot pitches by ψ = φ1 − heel_off about the toe
//!   pivot, which stays on the ground, so the ankle moves on a circle:
//!   a(φ1) = toe + R(−ψ)(a₀ − toe). φ1 stays the coordinate: it is still
//!   the stance shank's absolute angle.
//!
//! The chain's dynamics on this foot take it as a contact,
//! [`crate::dynamics::Contact::ToeRocker`].

use crate::kinematics::{Phi, Point, Posture, forward_kinematics, forward_kinematics_at, link_com};
use crate::model::{BodyModel, LINKS};
use crate::scalar::Real;

/// Ankle to the ball of the foot (the toe pivot), m: about 0.53 of a
/// 0.266 m foot (Winter's foot length 0.152 H for H = 1.75 m, the ankle
/// 0.05 m ahead of the heel, the metatarsal heads at 0.73 of the length).
pub const TOE_M: f64 = 0.14;
/// Ankle joint above the sole, m (Winter: 0.039 H).
pub const ANKLE_HEIGHT_M: f64 = 0.07;

/// Geometry and stop of the stance foot.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StanceFoot<T> {
    /// Horizontal distance from the ankle to the toe pivot (ball of the
    /// foot), m.
    pub toe_m: T,
    /// Height of the ankle above the sole, m.
    pub ankle_height_m: T,
    /// Dorsiflexion (stance-shank angle φ1) at which the heel lifts: the
    /// ankle's stop, rad.
    pub heel_off_rad: T,
}

/// Why a [`StanceFoot`]'s geometry is refused ([`StanceFoot::new`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FootError {
    /// The toe pivot is not a finite distance > 0 m ahead of the ankle.
    Toe,
    /// The ankle height is not finite and ≥ 0 m.
    AnkleHeight,
    /// The heel-off angle is not finite and within (−π/2, π/2) rad.
    HeelOff,
}

impl core::fmt::Display for FootError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Toe => "the toe must lie a finite distance > 0 m ahead of the ankle",
            Self::AnkleHeight => "the ankle height must be finite and >= 0 m",
            Self::HeelOff => "the heel-off angle must be finite and in (-pi/2, pi/2) rad",
        })
    }
}

/// The stance ankle's position as a function of φ1 and its first two
/// derivatives, relative to where it is with the foot flat, m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnklePlacement<T> {
    /// a(φ1), m.
    pub position_m: Point<T>,
    /// ∂a/∂φ1, m/rad.
    pub d1: Point<T>,
    /// ∂²a/∂φ1², m/rad².
    pub d2: Point<T>,
}

impl<T: Real> StanceFoot<T> {
    /// A foot of the given geometry, checked: the toe a finite distance
    /// ahead of the ankle (> 0 m), the ankle height finite and ≥ 0 m, the
    /// heel-off angle finite and within (−π/2, π/2) rad.
    pub fn new(toe_m: T, ankle_height_m: T, heel_off_rad: T) -> Result<Self, FootError> {
        if !(toe_m.finite() && toe_m > T::zero()) {
            return Err(FootError::Toe);
        }
        if !(ankle_height_m.finite() && ankle_height_m >= T::zero()) {
            return Err(FootError::AnkleHeight);
        }
        if !(heel_off_rad.finite() && heel_off_rad.abs() < T::lit(core::f64::consts::FRAC_PI_2)) {
            return Err(FootError::HeelOff);
        }
        Ok(Self {
            toe_m,
            ankle_height_m,
            heel_off_rad,
        })
    }

    /// The device's foot ([`TOE_M`], [`ANKLE_HEIGHT_M`]) with the heel
    /// lifting at `heel_off_rad`.
    pub fn device(heel_off_rad: T) -> Self {
        Self {
            toe_m: T::lit(TOE_M),
            ankle_height_m: T::lit(ANKLE_HEIGHT_M),
            heel_off_rad,
        }
    }

    /// The device's foot with heel-off at the model's dorsiflexion limit
    /// (Table I: 20°).
    pub fn for_model(model: &BodyModel<T>) -> Self {
        Self::device(model.limits().ankle_dorsiflexion_rad)
    }

    /// The device's foot with heel-off at Table I's 20°.
    pub fn table_i() -> Self {
        Self::device(crate::model::JointLimits::<T>::paper_table_i().ankle_dorsiflexion_rad)
    }

    /// The foot's pitch (heel up, rad): max(φ1 − heel_off, 0).
    pub fn pitch(&self, phi1: T) -> T {
        (phi1 - self.heel_off_rad).max(T::zero())
    }

    /// Whether the heel is off the ground at φ1.
    pub fn on_toe(&self, phi1: T) -> bool {
        phi1 > self.heel_off_rad
    }

    /// What the ankle's encoder reads: φ1, or the stop once on the toe.
    pub fn dorsiflexion(&self, phi1: T) -> T {
        phi1.min(self.heel_off_rad)
    }

    /// The toe pivot, in the flat foot's frame (ankle at the origin), m.
    pub fn toe(&self) -> Point<T> {
        [self.toe_m, -self.ankle_height_m]
    }

    /// The point the stance leg pivots about at φ1: the ankle while flat,
    /// the toe once the heel is up.
    pub fn pivot(&self, phi1: T) -> Point<T> {
        if self.on_toe(phi1) {
            self.toe()
        } else {
            [T::zero(); 2]
        }
    }

    /// The ankle's position and its φ1-derivatives.
    pub fn ankle(&self, phi1: T) -> AnklePlacement<T> {
        let zero = [T::zero(); 2];
        if !self.on_toe(phi1) {
            return AnklePlacement {
                position_m: zero,
                d1: zero,
                d2: zero,
            };
        }
        let (s, c) = self.pitch(phi1).sin_cos_fast();
        // r0 = a₀ − toe; the heel rising is a clockwise turn by ψ.
        let (rx, ry) = (-self.toe_m, self.ankle_height_m);
        let rot = [rx * c + ry * s, -rx * s + ry * c];
        let [tx, ty] = self.toe();
        AnklePlacement {
            position_m: [tx + rot[0], ty + rot[1]],
            d1: [-rx * s + ry * c, -rx * c - ry * s],
            d2: [-rot[0], -rot[1]],
        }
    }

    /// Forward kinematics with this foot: [`forward_kinematics`]'s points
    /// shifted by the ankle's position (the flat foot's frame: ankle at the
    /// origin while the foot is flat).
    pub fn points(&self, model: &BodyModel<T>, phi: &Phi<T>) -> [Point<T>; LINKS] {
        let a = self.ankle(first(phi)).position_m;
        forward_kinematics(model, phi).map(|p| [p[0] + a[0], p[1] + a[1]])
    }

    /// [`StanceFoot::points`] at a posture whose sines are known.
    pub fn points_at(&self, model: &BodyModel<T>, posture: &Posture<T>) -> [Point<T>; LINKS] {
        let a = self.ankle(first(&posture.phi)).position_m;
        forward_kinematics_at(model, posture).map(|p| [p[0] + a[0], p[1] + a[1]])
    }

    /// Link centres of mass with this foot, flat foot's frame, m.
    pub fn link_com(&self, model: &BodyModel<T>, phi: &Phi<T>) -> [Point<T>; LINKS] {
        let a = self.ankle(first(phi)).position_m;
        link_com(model, phi).map(|p| [p[0] + a[0], p[1] + a[1]])
    }
}

/// φ1 of an angle array.
fn first<T: Real>(a: &Phi<T>) -> T {
    let [x, ..] = *a;
    x
}
