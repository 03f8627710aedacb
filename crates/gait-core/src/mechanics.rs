//! The chain's dynamics, one API with the stance foot as an input: `None`
//! is the paper's foot (the ankle pinned to the ground, [`crate::dynamics`]);
//! a [`StanceFoot`] is the device's, whose heel lifts past the ankle's stop
//! so that the chain rolls on the toe ([`crate::foot`]; equal to the
//! paper's while the foot is flat). The optimiser, the playback model and
//! the controller's feed-forward, and the simulator's plant call these, so
//! none of them chooses between the two families itself. The integrator
//! is [`crate::dynamics::rk4_integrate`].

use crate::dynamics::{self, DynamicsError, TPhi};
use crate::foot::{self, StanceFoot};
use crate::kinematics::{Phi, Posture};
use crate::model::BodyModel;
use crate::scalar::Real;

/// Generalised forces T_Φ that produce Φ̈ at (Φ, Φ̇) on `foot`.
pub fn inverse_dynamics<T: Real>(
    model: &BodyModel<T>,
    foot: Option<&StanceFoot<T>>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    ddphi: &Phi<T>,
) -> TPhi<T> {
    match foot {
        Some(f) => foot::inverse_dynamics(model, f, phi, dphi, ddphi),
        None => dynamics::inverse_dynamics(model, phi, dphi, ddphi),
    }
}

/// [`inverse_dynamics`] at a posture whose sines are known (the control
/// tick shares them with the load sharing and the swing foot's position).
pub fn inverse_dynamics_at<T: Real>(
    model: &BodyModel<T>,
    foot: Option<&StanceFoot<T>>,
    posture: &Posture<T>,
    dphi: &Phi<T>,
    ddphi: &Phi<T>,
) -> TPhi<T> {
    match foot {
        Some(f) => foot::inverse_dynamics_at(model, f, posture, dphi, ddphi),
        None => dynamics::inverse_dynamics_at(model, posture, dphi, ddphi),
    }
}

/// Φ̈ under the generalised forces `t_phi` at (Φ, Φ̇) on `foot`.
pub fn forward_dynamics<T: Real>(
    model: &BodyModel<T>,
    foot: Option<&StanceFoot<T>>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    t_phi: &TPhi<T>,
) -> Result<Phi<T>, DynamicsError> {
    match foot {
        Some(f) => foot::forward_dynamics(model, f, phi, dphi, t_phi),
        None => dynamics::forward_dynamics(model, phi, dphi, t_phi),
    }
}

/// Kinetic plus gravitational energy on `foot`, J.
pub fn energy<T: Real>(
    model: &BodyModel<T>,
    foot: Option<&StanceFoot<T>>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
) -> T {
    match foot {
        Some(f) => foot::energy(model, f, phi, dphi),
        None => dynamics::energy(model, phi, dphi),
    }
}
