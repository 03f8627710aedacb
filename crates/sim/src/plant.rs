//! The exoskeleton-plus-pilot plant: the paper's 5-link chain with its
//! stance foot pinned at the origin of a per-step frame, and the world
//! bookkeeping around it (which leg stands, where the feet are, terrain,
//! landing and leg swap, foot and crutch forces).
//!
//! # Conventions
//!
//! - Motor torques are **anatomical**, in the order left hip, left knee,
//!   right hip, right knee, flexion positive, N·m. They map to the model's
//!   relative-joint torques with the signs of
//!   [`gait_core::kinematics::anatomical_angles`] (a torque on a coordinate
//!   q = s·θ is s·T_θ): stance hip −T_θ3, stance knee +T_θ2, swing hip +T_θ4,
//!   swing knee −T_θ5; then T_Φ solves T_Θ = Aᵀ T_Φ
//!   (T_φ5 = −T_θ5, T_φi = −T_θi + T_θ(i+1)).
//! - The stance ankle (θ1) carries a rotational spring and the pilot's
//!   balancing torque ([`crate::pilot`]); ankle dorsiflexion = φ1 (foot flat).
//! - World frame: x forward, y up, the first stance foot at the origin.
//!
//! # Approximations (documented, not hidden)
//!
//! - The swing leg is free: nothing stops it from entering the ground before
//!   it has been lifted (double support is not a constraint). A landing is
//!   only registered after the swing ankle has risen above
//!   `lift_clearance_m`, then comes back within `landing_tolerance_m` of the
//!   ground at its x while moving down, at least 5 cm along the ground from
//!   where it was at the last leg swap (a trailing foot settling back onto
//!   its own tread is no step).
//! - Leg swap: the posture is mirrored exactly (old swing leg → links 1–2,
//!   old stance leg → links 4–5), so every point keeps its world position.
//!   Velocities follow a rigid plastic impact that conserves the angular
//!   momenta the impulses cannot change ([`crate::impact`]); the old stance
//!   foot is assumed to lift off (its vertical speed is in [`Landing`]).
//! - The model's mass properties belong to roles (Table III gives the
//!   stance and swing legs different masses), so a swap changes the mass of
//!   each physical leg, as in the paper's model.
//! - Foot forces: the total vertical support M(g + ÿ_com) minus the crutch
//!   load; while the swing foot touches the ground it takes a share by the
//!   lever rule on the centre of mass's x between the two ankles.

use gait_core::dynamics::{self, Contact, DynamicsError};
use gait_core::foot::{self, StanceFoot};
use gait_core::kinematics::{
    Phi, anatomical_angles, forward_kinematics, joint_torques, link_com, link_com_accelerations,
    theta_from_phi,
};
use gait_core::model::{BodyModel, GRAVITY_M_S2, LINKS};

use crate::pilot::{PilotConfig, PilotTarget};
use crate::terrain::Terrain;

use std::f64::consts::PI;

pub use gait_control::layout::{Side, joint};

mod config;
mod forces;
mod landing;
mod state;

use config::check_config;
pub use config::{GroundContact, JointStops, PlantConfig};
use forces::role_angles;
pub use landing::Landing;
pub use state::TrueState;

/// Why the plant refused a configuration or a step. After an error from
/// [`Plant::step`] the state is the one before the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SimError {
    /// A configuration value is unusable (the field is named).
    Config(&'static str),
    /// An input torque, or the integrated state, is NaN or infinite.
    NonFinite,
    /// gait-core's forward dynamics failed.
    Dynamics(DynamicsError),
    /// A link turned faster than `max_speed_rad_s`.
    Runaway {
        /// Link (1-based, the paper's numbering).
        link: usize,
        /// Its angular speed, rad/s.
        speed_rad_s: f64,
    },
    /// The hip came down below `min_hip_height_m` above the stance foot.
    Fell {
        /// Hip height above the stance foot, m.
        hip_height_m: f64,
    },
}

impl core::fmt::Display for SimError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Config(field) => write!(f, "unusable plant configuration: {field}"),
            Self::NonFinite => f.write_str("non-finite torque or state"),
            Self::Dynamics(e) => write!(f, "forward dynamics failed: {e:?}"),
            Self::Runaway { link, speed_rad_s } => {
                write!(f, "link {link} turns at {speed_rad_s:.1} rad/s")
            }
            Self::Fell { hip_height_m } => write!(f, "fell: hip {hip_height_m:.3} m high"),
        }
    }
}

impl std::error::Error for SimError {}

impl From<DynamicsError> for SimError {
    fn from(e: DynamicsError) -> Self {
        match e {
            DynamicsError::NonFinite => Self::NonFinite,
            other => Self::Dynamics(other),
        }
    }
}

/// The plant. See the module documentation.
#[derive(Clone, Debug)]
pub struct Plant {
    cfg: PlantConfig,
    phi: Phi<f64>,
    dphi: Phi<f64>,
    ddphi: Phi<f64>,
    stance: Side,
    stance_foot_m: [f64; 2],
    time_s: f64,
    last_swap_s: f64,
    pilot_target: PilotTarget,
    lifted: bool,
    /// World x of the swing ankle at the last leg swap (or the start), m.
    swing_start_x_m: f64,
    /// World x where the swing foot's current ground contact began, and
    /// whether that contact is on the toe (the anchor restarts when the
    /// contact point moves between the ankle and the toe).
    contact_anchor_x: Option<(f64, bool)>,
    /// The swing foot's ground force at the present state (x, y), N.
    contact_n: [f64; 2],
    motor_nm: [f64; 4],
    /// The joints' dynamic-brake damping, N·m·s/rad (order of [`joint`]).
    brakes: [f64; 4],
    /// The brakes' torques at the present state, N·m.
    brake_nm: [f64; 4],
    pilot_nm: f64,
    spring_nm: f64,
    stops_nm: [f64; 4],
    landings: Vec<Landing>,
}

/// Standing upright, feet together: Φ = (0, 0, 0, π, π).
pub const STANDING: Phi<f64> = [0.0, 0.0, 0.0, PI, PI];

impl Plant {
    /// Standing upright at the origin on the left leg, at rest, the pilot
    /// holding φ1 = 0.
    pub fn new(cfg: PlantConfig) -> Result<Self, SimError> {
        Self::with_posture(cfg, STANDING, [0.0; LINKS], Side::Left, [0.0, 0.0])
    }

    /// Any posture: Φ, Φ̇ in the stance frame, the stance leg and its ankle's
    /// world position.
    pub fn with_posture(
        cfg: PlantConfig,
        phi: Phi<f64>,
        dphi: Phi<f64>,
        stance: Side,
        stance_foot_m: [f64; 2],
    ) -> Result<Self, SimError> {
        check_config(&cfg)?;
        if !phi
            .iter()
            .chain(&dphi)
            .chain(&stance_foot_m)
            .all(|x| x.is_finite())
        {
            return Err(SimError::NonFinite);
        }
        let mut plant = Self {
            cfg,
            phi,
            dphi,
            ddphi: [0.0; LINKS],
            stance,
            stance_foot_m,
            time_s: 0.0,
            last_swap_s: 0.0,
            pilot_target: PilotTarget::Hold { phi1_rad: phi[0] },
            lifted: false,
            swing_start_x_m: 0.0,
            contact_anchor_x: None,
            contact_n: [0.0; 2],
            motor_nm: [0.0; 4],
            brakes: [0.0; 4],
            brake_nm: [0.0; 4],
            pilot_nm: 0.0,
            spring_nm: 0.0,
            stops_nm: [0.0; 4],
            landings: Vec::new(),
        };
        plant.lifted = plant.swing_height_above_ground_m() > cfg.lift_clearance_m;
        plant.swing_start_x_m = plant.swing_foot_world()[0];
        plant.update_contact_anchor();
        plant.refresh_outputs()?;
        Ok(plant)
    }

    /// The configuration.
    pub fn config(&self) -> &PlantConfig {
        &self.cfg
    }

    /// Simulation time, s.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// The stance leg.
    pub fn stance(&self) -> Side {
        self.stance
    }

    /// Every landing so far.
    pub fn landings(&self) -> &[Landing] {
        &self.landings
    }

    /// What the pilot does from now on.
    pub fn set_pilot(&mut self, target: PilotTarget) {
        self.pilot_target = target;
    }

    /// The pilot's current target.
    pub fn pilot(&self) -> PilotTarget {
        self.pilot_target
    }

    /// Sets each joint's brake damping, N·m·s/rad (order of [`joint`]; 0
    /// for none): a torque −b·ω the plant evaluates at every stage of its
    /// integration, as a shorted winding brakes continuously (a torque held
    /// over the step would be unstable at a drive brake's b; negative or
    /// non-finite values are taken as 0).
    pub fn set_brakes(&mut self, damping_nm_s_per_rad: [f64; 4]) {
        self.brakes = damping_nm_s_per_rad.map(|b| if b.is_finite() { b.max(0.0) } else { 0.0 });
    }

    /// Advances one control period under the four motor torques (anatomical,
    /// flexion positive, N·m, order of [`joint`]). Returns the landing if the
    /// swing foot touched down in this period (the legs are then swapped).
    /// On error the state is left as it was.
    pub fn step(&mut self, motor_torques_nm: [f64; 4]) -> Result<Option<Landing>, SimError> {
        if !motor_torques_nm.iter().all(|t| t.is_finite()) {
            return Err(SimError::NonFinite);
        }
        let saved = self.clone();
        let result = self.advance(motor_torques_nm);
        if result.is_err() {
            *self = saved;
        }
        result
    }

    fn advance(&mut self, motor_torques_nm: [f64; 4]) -> Result<Option<Landing>, SimError> {
        self.motor_nm = motor_torques_nm;
        let h = self.cfg.dt_s / f64::from(self.cfg.substeps);
        for _ in 0..self.cfg.substeps {
            self.rk4(h)?;
            self.update_contact_anchor();
        }
        self.check_sane()?;
        self.refresh_outputs()?;
        Ok(self.detect_landing())
    }

    /// One classical RK4 step of `h` seconds. The ankle spring and the
    /// pilot and the brakes are evaluated at every stage (they depend on the
    /// state, so holding them over the step would cost RK4 its accuracy);
    /// the motor torques are held.
    fn rk4(&mut self, h: f64) -> Result<(), SimError> {
        let t0 = self.time_s;
        let q0 = self.phi;
        let (q, w) =
            dynamics::rk4_integrate(&self.phi, &self.dphi, t0, h, |q, w, t| self.accel(q, w, t))?;
        self.phi = q;
        self.dphi = w;
        self.time_s = t0 + h;
        // The heel lifted or landed in this substep: a plastic contact
        // switch ([`dynamics::contact_switch_velocities`]), applied at its end.
        if let Some(f) = &self.cfg.foot {
            let (was, is) = (f.on_toe(q0[0]), f.on_toe(self.phi[0]));
            if was != is {
                self.dphi = dynamics::contact_switch_velocities(
                    &self.cfg.model,
                    f,
                    &self.phi,
                    &self.dphi,
                    is,
                )?;
            }
        }
        Ok(())
    }

    /// Φ̈ at a state and time, with the held motor torques.
    fn accel(&self, phi: &Phi<f64>, dphi: &Phi<f64>, t_s: f64) -> Result<Phi<f64>, SimError> {
        let f = self.forces(phi, dphi, t_s);
        self.forward(phi, dphi, &f.t_phi)
    }

    /// Recomputes the reported torques and Φ̈ at the present state.
    fn refresh_outputs(&mut self) -> Result<(), SimError> {
        let f = self.forces(&self.phi, &self.dphi, self.time_s);
        self.pilot_nm = f.pilot_nm;
        self.contact_n = f.contact_n;
        self.spring_nm = f.spring_nm;
        self.stops_nm = f.stops_nm;
        self.brake_nm = f.brake_nm;
        self.ddphi = self.forward(&self.phi, &self.dphi, &f.t_phi)?;
        Ok(())
    }

    /// The stance foot's contact: the configured toe rocker, or the fixed
    /// ankle without one.
    fn contact(&self) -> Contact<f64> {
        Contact::from(self.cfg.foot)
    }

    /// Forward dynamics on the configured foot.
    fn forward(
        &self,
        phi: &Phi<f64>,
        dphi: &Phi<f64>,
        t_phi: &[f64; LINKS],
    ) -> Result<Phi<f64>, SimError> {
        Ok(dynamics::forward_dynamics(
            &self.cfg.model,
            &self.contact(),
            phi,
            dphi,
            t_phi,
        )?)
    }

    fn check_sane(&self) -> Result<(), SimError> {
        if !self.phi.iter().chain(&self.dphi).all(|x| x.is_finite()) {
            return Err(SimError::NonFinite);
        }
        for (i, w) in self.dphi.iter().enumerate() {
            if w.abs() > self.cfg.max_speed_rad_s {
                return Err(SimError::Runaway {
                    link: i + 1,
                    speed_rad_s: w.abs(),
                });
            }
        }
        let hip = forward_kinematics(&self.cfg.model, &self.phi)[1][1]
            + self.ankle_at(self.phi[0]).position_m[1];
        if hip < self.cfg.min_hip_height_m {
            return Err(SimError::Fell { hip_height_m: hip });
        }
        Ok(())
    }
}

/// Solves T_Θ = Aᵀ T_Φ for T_Φ (the inverse of
/// [`gait_core::kinematics::joint_torques`]): T_φ5 = −T_θ5,
/// T_φi = −T_θi + T_θ(i+1).
pub fn t_phi_from_t_theta(t_theta: &[f64; LINKS]) -> [f64; LINKS] {
    core::array::from_fn(|i| {
        let next = t_theta.get(i + 1).copied().unwrap_or(0.0);
        -t_theta[i] + next
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use gait_core::kinematics::joint_torques;

    #[test]
    fn t_phi_inverts_joint_torques() {
        let t_theta = [1.5, -2.0, 0.3, 4.0, -7.0];
        let back = joint_torques(&t_phi_from_t_theta(&t_theta));
        for i in 0..LINKS {
            assert!((back[i] - t_theta[i]).abs() < 1e-12);
        }
    }
}
