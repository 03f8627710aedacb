//! The chain's dynamics, one API with the stance foot's contact as an
//! argument (as pinocchio takes contacts): [`Contact::FixedAnkle`] is the
//! paper's foot, the stance ankle pinned to the ground; a
//! [`Contact::ToeRocker`] is the device's, whose heel lifts past the
//! ankle's stop so that the chain rolls on the toe (equal to the paper's
//! while the foot is flat). The optimiser, the playback model, the
//! controller's feed-forward and the simulator's plant call these, so none
//! of them picks between two families of functions itself.
//!
//! The implementations are private: `pinned` (paper section III-A) and
//! `rocker` (`docs/model.md`, "Toe rocker"). The dispatchers below are
//! `#[inline]`: a caller whose contact is a constant (the control tick's
//! toe rocker) then pays no runtime match.

use nalgebra::{SMatrix, SVector};

use crate::foot::StanceFoot;
use crate::kinematics::{Phi, Posture, joint_torques};
use crate::model::{BodyModel, LINKS};
use crate::scalar::Real;

mod pinned;
mod rocker;

pub use rocker::contact_switch_velocities;

/// Generalised forces conjugate to the absolute angles, N·m.
pub type TPhi<T> = [T; LINKS];

/// How the stance foot meets the ground: what the chain turns about.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Contact<T> {
    /// The paper's: the stance ankle a fixed pivot, the foot flat.
    FixedAnkle,
    /// The device's: the ankle pivots until its stop, then the heel lifts
    /// and the chain turns about the toe.
    ToeRocker(StanceFoot<T>),
}

impl<T> Contact<T> {
    /// The toe rocker's foot, if this is one.
    pub fn stance_foot(&self) -> Option<&StanceFoot<T>> {
        match self {
            Self::FixedAnkle => None,
            Self::ToeRocker(foot) => Some(foot),
        }
    }
}

/// `None` (no foot configured) is the fixed ankle.
impl<T> From<Option<StanceFoot<T>>> for Contact<T> {
    fn from(foot: Option<StanceFoot<T>>) -> Self {
        foot.map_or(Self::FixedAnkle, Self::ToeRocker)
    }
}

impl<T> From<StanceFoot<T>> for Contact<T> {
    fn from(foot: StanceFoot<T>) -> Self {
        Self::ToeRocker(foot)
    }
}

/// Why forward dynamics could not produce accelerations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DynamicsError {
    /// An input was NaN or infinite.
    NonFinite,
    /// The mass matrix was not positive definite (cannot happen for a valid
    /// model and finite angles; reported rather than assumed).
    SingularMassMatrix,
}

/// The terms of the equation of motion at one state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DynamicsTerms<T: Real> {
    /// Mass matrix D(Φ).
    pub d: SMatrix<T, LINKS, LINKS>,
    /// Velocity product H(Φ, Φ̇) Φ̇.
    pub h_dphi: SVector<T, LINKS>,
    /// Gravity vector G(Φ).
    pub g: SVector<T, LINKS>,
}

/// Holding a posture with both feet on the ground: the ground force on the
/// swing foot and the joint torques that go with it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DoubleSupportStatics<T> {
    /// Ground reaction on the swing (second) foot, (x, y), N.
    pub reaction_n: [T; 2],
    /// Joint torques T_Θ (ankle first), N·m.
    pub torques: [T; LINKS],
    /// The joint torques one newton on the second foot takes, along x and
    /// along y ([`second_foot_torques`]), N·m/N: what a controller pushing
    /// that foot harder needs, without computing them again.
    pub per_newton: ([T; LINKS], [T; LINKS]),
}

/// Friction coefficient assumed between a foot and the ground when sharing
/// the load in double support (a conservative value for a rubber sole).
pub const FOOT_FRICTION: f64 = 0.5;

/// How much more a newton-metre at the stance ankle counts than one at a
/// motor when the load is shared between the feet: the ankle torque is the
/// pilot's, carried by the shoulders through the crutches, while the hip and
/// knee drives are built for it. With 25 (a factor 5 on the torque) the
/// sharing leaves the pilot a fifth of what an even weighting would where
/// the drives can take it; the drives' own limits are the table
/// generator's business (docs/model.md, "Load sharing").
pub const ANKLE_EFFORT_WEIGHT: f64 = 25.0;

/// D(Φ), H(Φ, Φ̇)Φ̇ and G(Φ) on `contact` (eq. (sol1) for the fixed ankle).
#[inline]
pub fn terms<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
) -> DynamicsTerms<T> {
    match contact {
        Contact::FixedAnkle => pinned::terms(model, phi, dphi),
        Contact::ToeRocker(foot) => rocker::terms(model, foot, phi, dphi),
    }
}

/// Eq. (solution): the generalised forces T_Φ = D Φ̈ + H Φ̇ + G that
/// produce Φ̈ at (Φ, Φ̇) on `contact`. The control loop's feed-forward, so
/// it skips the matrices (five sine/cosine pairs); cross-checked against
/// [`terms`] and an independent Lagrangian derivation in the tests.
#[inline]
pub fn inverse_dynamics<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    ddphi: &Phi<T>,
) -> TPhi<T> {
    inverse_dynamics_at(model, contact, &Posture::new(phi), dphi, ddphi)
}

/// [`inverse_dynamics`] at a posture whose sines are known (the control
/// tick shares them with the load sharing and the swing foot's position).
#[inline]
pub fn inverse_dynamics_at<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    posture: &Posture<T>,
    dphi: &Phi<T>,
    ddphi: &Phi<T>,
) -> TPhi<T> {
    match contact {
        Contact::FixedAnkle => pinned::inverse_dynamics_at(model, posture, dphi, ddphi),
        Contact::ToeRocker(foot) => rocker::inverse_dynamics_at(model, foot, posture, dphi, ddphi),
    }
}

/// [`inverse_dynamics_at`] at rest (Φ̇ = Φ̈ = 0): what holding a posture
/// takes, with a tenth of the work (the same numbers, up to the sign of a
/// zero).
pub fn static_torques_at<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    posture: &Posture<T>,
) -> TPhi<T> {
    match contact {
        Contact::FixedAnkle => pinned::static_torques_at(model, posture),
        Contact::ToeRocker(foot) => rocker::static_torques_at(model, foot, posture),
    }
}

/// Eq. (solution) then eq. (hehe): joint torques T_Θ = Aᵀ T_Φ.
pub fn inverse_dynamics_joint<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    ddphi: &Phi<T>,
) -> [T; LINKS] {
    joint_torques(&inverse_dynamics(model, contact, phi, dphi, ddphi))
}

/// The torque about the stance pivot T_θ1 = −Σ_i T_φi (the stance ankle's,
/// or the toe's once the heel is up): the quantity the paper minimises.
pub fn ankle_torque<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    ddphi: &Phi<T>,
) -> T {
    let t = inverse_dynamics(model, contact, phi, dphi, ddphi);
    -t.iter().fold(T::zero(), |acc, &x| acc + x)
}

/// Φ̈ = D⁻¹ (T_Φ − H Φ̇ − G) under the generalised forces `t_phi` at
/// (Φ, Φ̇) on `contact`, by Cholesky (D is symmetric positive definite for
/// any valid model). NaN or infinite inputs are an error.
#[inline]
pub fn forward_dynamics<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    t_phi: &TPhi<T>,
) -> Result<Phi<T>, DynamicsError> {
    match contact {
        Contact::FixedAnkle => pinned::forward_dynamics(model, phi, dphi, t_phi),
        Contact::ToeRocker(foot) => rocker::forward_dynamics(model, foot, phi, dphi, t_phi),
    }
}

/// Kinetic plus gravitational energy on `contact` (heights from the flat
/// foot's ankle), J. Used to check that the free dynamics conserve it.
#[inline]
pub fn energy<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
) -> T {
    match contact {
        Contact::FixedAnkle => pinned::energy(model, phi, dphi),
        Contact::ToeRocker(foot) => rocker::energy(model, foot, phi, dphi),
    }
}

/// Statics of a double-support posture Φ at rest: the chain is held by the
/// stance foot and by a ground force F on the second foot, so the joint
/// torques are T_Θ(F) = Aᵀ (G_req(Φ) − Jᵀ F). One posture, many F:
/// [`share_load`] picks the least-effort one.
///
/// Why: with the single-stance model the whole body hangs on the stance
/// knee; at the stair-ascent start posture (stance knee 43°) that is
/// 208 N·m, more than the drives have, while the straight trailing leg
/// could carry most of it.
pub fn double_support_statics<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    phi: &Phi<T>,
    max_load_n: T,
) -> DoubleSupportStatics<T> {
    let zero = [T::zero(); LINKS];
    let single = joint_torques(&inverse_dynamics(model, contact, phi, &zero, &zero));
    share_load(model, contact, phi, &single, max_load_n)
}

/// Given the joint torques `single` that a motion needs with the stance
/// foot alone (T_Θ from [`inverse_dynamics`]), the ground force F on the
/// second foot (at most `max_load_n` upwards) that minimises the effort
/// w T_θ1² + Σ_{i≥2} T_θi² (w = [`ANKLE_EFFORT_WEIGHT`]: the pilot's ankle
/// torque counts more than the motors'), and the joint torques with it,
/// T_Θ(F) = single − Aᵀ Jᵀ F.
///
/// F is kept physical: pushing (F_y ≥ 0), at most `max_load_n`, inside the
/// friction cone |F_x| ≤ μ F_y. When a bound is active the other component
/// is re-optimised on it (the box/cone minimum of a convex quadratic in two
/// unknowns, found exactly: interior, then each active edge). On the toe
/// rocker the force also acts through the stance ankle's motion about its
/// toe, and at the second foot's toe when that foot stands on it.
#[inline]
pub fn share_load<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    phi: &Phi<T>,
    single: &[T; LINKS],
    max_load_n: T,
) -> DoubleSupportStatics<T> {
    share_load_at(model, contact, &Posture::new(phi), single, max_load_n)
}

/// [`share_load`] at a posture whose sines are known.
#[inline]
pub fn share_load_at<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    posture: &Posture<T>,
    single: &[T; LINKS],
    max_load_n: T,
) -> DoubleSupportStatics<T> {
    match contact {
        Contact::FixedAnkle => {
            let zero = [T::zero(); 2];
            pinned::share_load_with_base_at(model, posture, single, max_load_n, zero, zero)
        }
        Contact::ToeRocker(foot) => rocker::share_load_at(model, foot, posture, single, max_load_n),
    }
}

/// The joint torques T_Θ that a unit ground force on the second foot takes
/// away, for a force along x and along y: Aᵀ Jᵀ e_x and Aᵀ Jᵀ e_y, with J
/// the Jacobian of the second foot's contact point. A force F there changes
/// the joint torques a motion needs by −(Fx·mx + Fy·my).
#[inline]
pub fn second_foot_torques<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    phi: &Phi<T>,
) -> ([T; LINKS], [T; LINKS]) {
    second_foot_torques_at(model, contact, &Posture::new(phi))
}

/// [`second_foot_torques`] at a posture whose sines are known.
#[inline]
pub fn second_foot_torques_at<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    posture: &Posture<T>,
) -> ([T; LINKS], [T; LINKS]) {
    match contact {
        Contact::FixedAnkle => {
            let zero = [T::zero(); 2];
            pinned::second_foot_torques_at(model, posture, zero, zero)
        }
        Contact::ToeRocker(foot) => rocker::second_foot_torques_at(model, foot, posture),
    }
}

/// One classical Runge–Kutta (RK4) step of the chain on `contact` under
/// constant generalised forces `t_phi` over `h` seconds; returns the new
/// (Φ, Φ̇). On the toe rocker a step that crosses heel-off applies
/// [`contact_switch_velocities`] at its end. Used by the energy checks; the
/// simulator's plant steps with [`rk4_integrate`] itself, its forces
/// changing with the state.
pub fn rk4_step<T: Real>(
    model: &BodyModel<T>,
    contact: &Contact<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    t_phi: &TPhi<T>,
    h: T,
) -> Result<(Phi<T>, Phi<T>), DynamicsError> {
    match contact {
        Contact::FixedAnkle => pinned::rk4_step(model, phi, dphi, t_phi, h),
        Contact::ToeRocker(foot) => rocker::rk4_step(model, foot, phi, dphi, t_phi, h),
    }
}

/// One RK4 step of Φ̈ = `accel`(Φ, Φ̇) over `h` seconds (the contacts'
/// [`rk4_step`]s).
fn rk4_with<T: Real>(
    phi: &Phi<T>,
    dphi: &Phi<T>,
    h: T,
    accel: impl Fn(&Phi<T>, &Phi<T>) -> Result<Phi<T>, DynamicsError>,
) -> Result<(Phi<T>, Phi<T>), DynamicsError> {
    rk4_integrate(phi, dphi, T::zero(), h, |q, w, _| accel(q, w))
}

/// The chain's integrator: one classical RK4 step of Φ̈ = `accel`(Φ, Φ̇, t)
/// from time `t0` over `h` seconds; returns the new (Φ, Φ̇). The forces
/// behind `accel` may change with the state and the time (the simulator's
/// plant evaluates its pilot, ankle spring and contacts at every stage).
pub fn rk4_integrate<T: Real, E>(
    phi: &Phi<T>,
    dphi: &Phi<T>,
    t0: T,
    h: T,
    mut accel: impl FnMut(&Phi<T>, &Phi<T>, T) -> Result<Phi<T>, E>,
) -> Result<(Phi<T>, Phi<T>), E> {
    let half = h * T::lit(0.5);
    let k1w = accel(phi, dphi, t0)?;
    let k1q = *dphi;
    let k2q = axpy(dphi, &k1w, half);
    let k2w = accel(&axpy(phi, &k1q, half), &k2q, t0 + half)?;
    let k3q = axpy(dphi, &k2w, half);
    let k3w = accel(&axpy(phi, &k2q, half), &k3q, t0 + half)?;
    let k4q = axpy(dphi, &k3w, h);
    let k4w = accel(&axpy(phi, &k3q, h), &k4q, t0 + h)?;
    let sixth = h / T::lit(6.0);
    let two = T::lit(2.0);
    let mut q = *phi;
    let mut w = *dphi;
    for i in 0..LINKS {
        // `i < LINKS` for every array here, so `get` never misses.
        let pick = |a: &Phi<T>| a.get(i).copied().unwrap_or(T::zero());
        if let Some(qi) = q.get_mut(i) {
            *qi += sixth * (pick(&k1q) + two * pick(&k2q) + two * pick(&k3q) + pick(&k4q));
        }
        if let Some(wi) = w.get_mut(i) {
            *wi += sixth * (pick(&k1w) + two * pick(&k2w) + two * pick(&k3w) + pick(&k4w));
        }
    }
    Ok((q, w))
}

/// `a + s·b`, element-wise.
fn axpy<T: Real>(a: &Phi<T>, b: &Phi<T>, s: T) -> Phi<T> {
    let mut o = *a;
    for (oi, &bi) in o.iter_mut().zip(b) {
        *oi += s * bi;
    }
    o
}
