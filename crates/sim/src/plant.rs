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
//!   ground at its x while moving down.
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

use gait_core::dynamics::{self, DynamicsError};
use gait_core::foot::{self, StanceFoot};
use gait_core::kinematics::{
    Phi, anatomical_angles, forward_kinematics, joint_torques, link_com, link_com_accelerations,
    theta_from_phi,
};
use gait_core::mechanics;
use gait_core::model::{BodyModel, GRAVITY_M_S2, LINKS};

use crate::pilot::{PilotConfig, PilotTarget};
use crate::terrain::Terrain;

use std::f64::consts::PI;

pub use gait_control::layout::{Side, joint};

/// Plant parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantConfig {
    /// The body model (default: the paper's Table III).
    pub model: BodyModel<f64>,
    /// The ground.
    pub terrain: Terrain,
    /// Control period: one [`Plant::step`], s.
    pub dt_s: f64,
    /// RK4 substeps per control period (spring and pilot re-evaluated at
    /// each, motor torques held: a PWM holds its duty for the period).
    pub substeps: u32,
    /// Stance-ankle spring stiffness, N·m/rad (0: free ankle).
    pub ankle_stiffness_nm_per_rad: f64,
    /// Ankle angle (dorsiflexion) at which the spring is relaxed, rad.
    pub ankle_rest_rad: f64,
    /// Pilot and crutch parameters.
    pub pilot: PilotConfig,
    /// The device's mechanical stops at the model's joint limits (Table I),
    /// or `None` for a chain without stops.
    pub stops: Option<JointStops>,
    /// Swing-ankle height above ground counted as touching down, m.
    pub landing_tolerance_m: f64,
    /// Height the swing ankle must rise above the ground before a landing
    /// can be registered, m (default 1 cm; the closed-loop rigs use 3 cm,
    /// see `scenario::gait_rig`).
    pub lift_clearance_m: f64,
    /// The swing foot carries load while within this height of the ground, m.
    pub contact_tolerance_m: f64,
    /// Any link faster than this is a blow-up, rad/s.
    pub max_speed_rad_s: f64,
    /// A hip lower than this above the stance foot is a fall, m.
    pub min_hip_height_m: f64,
    /// Ground contact of the swing foot (double support before lift-off, a
    /// scuff during the swing): a penalty spring-damper with friction, or
    /// `None` for the bare chain (no double support).
    pub contact: Option<GroundContact>,
    /// The feet's toe rocker ([`gait_core::foot`]): past the ankle's
    /// dorsiflexion stop the stance heel lifts and the chain turns about
    /// the toe. `None`: the paper's pinned, flat foot.
    pub foot: Option<StanceFoot<f64>>,
}

/// Penalty contact between the swing ankle and the ground: vertical
/// spring-damper that only pushes, horizontal spring to the point where
/// contact began (sticking) limited by Coulomb friction.
///
/// Without it the 5-link chain has no double support at all: the trailing
/// foot of a step would carry nothing and the whole body would hang on the
/// stance ankle and the pilot's crutches, which is not how a pilot stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundContact {
    /// Vertical stiffness, N/m.
    pub stiffness_n_per_m: f64,
    /// Vertical damping, N·s/m.
    pub damping_n_s_per_m: f64,
    /// Horizontal (sticking) stiffness, N/m.
    pub tangential_stiffness_n_per_m: f64,
    /// Horizontal damping, N·s/m.
    pub tangential_damping_n_s_per_m: f64,
    /// Coulomb friction coefficient.
    pub friction: f64,
}

impl Default for GroundContact {
    /// 200 kN/m (2 mm under half the body weight), damped at about a third
    /// of critical for the whole body, friction 0.8.
    fn default() -> Self {
        Self {
            stiffness_n_per_m: 2.0e5,
            damping_n_s_per_m: 3.0e3,
            tangential_stiffness_n_per_m: 2.0e5,
            tangential_damping_n_s_per_m: 3.0e3,
            friction: 0.8,
        }
    }
}

impl Default for PlantConfig {
    fn default() -> Self {
        Self {
            model: BodyModel::paper_table_iii(),
            terrain: Terrain::Level,
            dt_s: 0.001,
            substeps: 4,
            ankle_stiffness_nm_per_rad: 30.0,
            ankle_rest_rad: 0.0,
            pilot: PilotConfig::default(),
            stops: Some(JointStops::default()),
            landing_tolerance_m: 0.002,
            lift_clearance_m: 0.01,
            contact_tolerance_m: 0.005,
            max_speed_rad_s: 60.0,
            min_hip_height_m: 0.4,
            contact: Some(GroundContact::default()),
            foot: Some(StanceFoot::table_i()),
        }
    }
}

/// Mechanical joint stops: beyond a limit of `BodyModel::limits` a joint
/// meets a stiff spring-damper that only pushes back (the exoskeleton's hard
/// stops, e.g. the knee's at full extension). Stiff, but slow enough for
/// RK4 at the default 0.25 ms substep (ω·h ≈ 0.06 and damping rate × h ≈ 0.13
/// for a swing shank; RK4 is stable below 2.8).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointStops {
    /// Stiffness beyond the limit, N·m/rad.
    pub stiffness_nm_per_rad: f64,
    /// Damping beyond the limit, N·m·s/rad.
    pub damping_nm_s_per_rad: f64,
}

impl Default for JointStops {
    fn default() -> Self {
        Self {
            stiffness_nm_per_rad: 20000.0,
            damping_nm_s_per_rad: 200.0,
        }
    }
}

impl JointStops {
    /// The stop torque on a coordinate `q` (rate `dq`) allowed in
    /// `[-below, above]`: zero inside, pushing back only outside.
    pub fn torque_nm(&self, q: f64, dq: f64, below: f64, above: f64) -> f64 {
        if q > above {
            (-self.stiffness_nm_per_rad * (q - above) - self.damping_nm_s_per_rad * dq).min(0.0)
        } else if q < -below {
            (-self.stiffness_nm_per_rad * (q + below) - self.damping_nm_s_per_rad * dq).max(0.0)
        } else {
            0.0
        }
    }
}

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

/// A registered landing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Landing {
    /// Simulation time, s.
    pub time_s: f64,
    /// The leg that landed (the new stance leg).
    pub side: Side,
    /// Where its ankle landed, world frame, m.
    pub position_m: [f64; 2],
    /// Ground height there, m (the ankle may be up to the tolerance above,
    /// or below it by what it travelled in the last step).
    pub ground_m: f64,
    /// Downward ankle speed at touch-down, m/s (positive).
    pub descent_speed_m_s: f64,
    /// Horizontal distance from the previous stance foot, m.
    pub step_length_m: f64,
    /// Vertical speed of the trailing (old stance) foot just after the
    /// impact, m/s, positive up; negative means the impact model's lift-off
    /// assumption did not hold.
    pub trailing_foot_speed_up_m_s: f64,
}

/// The true state, for metrics, plots and the peripherals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrueState {
    /// Simulation time, s.
    pub time_s: f64,
    /// The stance leg.
    pub stance: Side,
    /// Absolute link angles Φ in the stance frame, rad.
    pub phi: Phi<f64>,
    /// Φ̇, rad/s.
    pub dphi: Phi<f64>,
    /// Anatomical joint angles, flexion positive, rad: left hip, left knee,
    /// right hip, right knee (the order of [`joint`]).
    pub joint_angles_rad: [f64; 4],
    /// Their rates, rad/s.
    pub joint_rates_rad_s: [f64; 4],
    /// Ankle dorsiflexion per side (left, right), rad: the stance ankle's is
    /// φ1; the swing ankle is not modelled (`None`).
    pub ankle_dorsiflexion_rad: [Option<f64>; 2],
    /// Ankle positions per side (left, right), world frame, m.
    pub feet_m: [[f64; 2]; 2],
    /// Stance ankle p0 then p1…p5 (stance knee, hip, torso top, swing knee,
    /// swing ankle), world frame, m.
    pub points_m: [[f64; 2]; 6],
    /// Centre of mass, world frame, m.
    pub com_m: [f64; 2],
    /// Vertical ground force under each foot (left, right), N.
    pub foot_forces_n: [f64; 2],
    /// Vertical force on each crutch (left, right), N.
    pub crutch_forces_n: [f64; 2],
    /// The pilot's balancing torque on the stance ankle (dorsiflexion
    /// positive), N·m.
    pub pilot_torque_nm: f64,
    /// The ankle spring's torque plus the ankle stop's (dorsiflexion
    /// positive), N·m.
    pub spring_torque_nm: f64,
    /// The joint stops' torques (order of [`joint`], flexion positive), N·m.
    pub stop_torques_nm: [f64; 4],
    /// The motor torques applied in the last step, N·m (order of [`joint`]).
    pub motor_torques_nm: [f64; 4],
    /// Mechanical energy: kinetic + gravity (world heights) + ankle spring, J.
    pub energy_j: f64,
    /// Whether the swing ankle has been lifted since the last swap.
    pub swing_lifted: bool,
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
    pilot_nm: f64,
    spring_nm: f64,
    stops_nm: [f64; 4],
    landings: Vec<Landing>,
}

/// The swing foot's ground contact point ([`Plant::swing_sole`]).
struct SwingSole {
    /// The contact point, world x, and the sole's height in the terrain's
    /// ankle-level convention, m.
    point_m: [f64; 2],
    /// Its velocity, m/s.
    velocity_m_s: [f64; 2],
    /// ∂(contact point)/∂φ5 beyond the ankle's own (the toe turning with
    /// the shank), m/rad; zero while flat.
    d5: [f64; 2],
    /// Whether the foot stands on its toe.
    on_toe: bool,
}

/// The generalised forces at one state.
struct Forces {
    t_phi: [f64; LINKS],
    contact_n: [f64; 2],
    pilot_nm: f64,
    /// Ankle spring plus the ankle's stop.
    spring_nm: f64,
    stops_nm: [f64; 4],
}

/// Anatomical angles and rates by role: ankle dorsiflexion, stance knee
/// flexion, stance hip flexion, swing hip flexion, swing knee flexion.
fn role_angles(phi: &Phi<f64>, dphi: &Phi<f64>) -> ([f64; LINKS], [f64; LINKS]) {
    let q = anatomical_angles(&theta_from_phi(phi));
    // Θ̇ = A⁻¹Φ̇ = theta_from_phi(Φ̇) − theta_from_phi(0) (b drops out).
    let t = theta_from_phi(dphi);
    let t0 = theta_from_phi(&[0.0; LINKS]);
    let dt: [f64; LINKS] = core::array::from_fn(|i| t[i] - t0[i]);
    (q, [dphi[0], dt[1], -dt[2], dt[3], -dt[4]])
}

/// A swing foot that has moved this far along the ground from where it was
/// at the last leg swap has been lifted, m.
const MIN_STEP_TRAVEL_M: f64 = 0.2;

/// A lifted swing foot whose ground contact carries this much has landed,
/// N (well below the controller's 80 N landing threshold, so the plant's
/// leg swap never lags the controller's).
const LANDED_LOAD_N: f64 = 30.0;

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
    /// pilot are evaluated at every stage (they depend on the state, so
    /// holding them over the step would cost RK4 its accuracy); the motor
    /// torques are held.
    fn rk4(&mut self, h: f64) -> Result<(), SimError> {
        let t0 = self.time_s;
        let q0 = self.phi;
        let (q, w) =
            dynamics::rk4_integrate(&self.phi, &self.dphi, t0, h, |q, w, t| self.accel(q, w, t))?;
        self.phi = q;
        self.dphi = w;
        self.time_s = t0 + h;
        // The heel lifted or landed in this substep: a plastic contact
        // switch ([`foot::contact_switch_velocities`]), applied at its end.
        if let Some(f) = &self.cfg.foot {
            let (was, is) = (f.on_toe(q0[0]), f.on_toe(self.phi[0]));
            if was != is {
                self.dphi =
                    foot::contact_switch_velocities(&self.cfg.model, f, &self.phi, &self.dphi, is)?;
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
        self.ddphi = self.forward(&self.phi, &self.dphi, &f.t_phi)?;
        Ok(())
    }

    /// Forward dynamics on the configured foot.
    fn forward(
        &self,
        phi: &Phi<f64>,
        dphi: &Phi<f64>,
        t_phi: &[f64; LINKS],
    ) -> Result<Phi<f64>, SimError> {
        Ok(mechanics::forward_dynamics(
            &self.cfg.model,
            self.cfg.foot.as_ref(),
            phi,
            dphi,
            t_phi,
        )?)
    }

    /// The stance ankle's offset from the flat foot's ankle, its
    /// φ1-derivatives (zero while flat).
    fn ankle_at(&self, phi1: f64) -> foot::AnklePlacement<f64> {
        match &self.cfg.foot {
            Some(f) => f.ankle(phi1),
            None => foot::AnklePlacement {
                position_m: [0.0; 2],
                d1: [0.0; 2],
                d2: [0.0; 2],
            },
        }
    }

    /// Whether the stance heel is up at φ1.
    fn on_toe(&self, phi1: f64) -> bool {
        self.cfg.foot.is_some_and(|f| f.on_toe(phi1))
    }

    /// Where the swing foot meets the ground: under the ankle while flat;
    /// at the toe while it still stands on it, before lift-off (a
    /// descent's trailing foot, its shank leaning past the stop: the foot
    /// turns with the shank, held on its stop, so a ground force there also
    /// turns the swing shank, [`SwingSole::d5`]). Once lifted the foot hangs
    /// free, its angle not modelled, and is a point at the ankle again, as in
    /// the paper (a toe held at the stop in the air caught the stair nosing
    /// in stair ascent).
    fn swing_sole(&self, phi: &Phi<f64>, dphi: &Phi<f64>) -> SwingSole {
        let (ankle, v) = self.swing_foot_at(phi, dphi);
        let lean = gait_core::kinematics::wrap_pi(phi[4] - PI);
        match self.cfg.foot.filter(|f| !self.lifted && f.on_toe(lean)) {
            Some(f) => {
                let a = f.ankle(lean);
                let toe = f.toe();
                // Toe − ankle in the world, and its φ5-derivative.
                let r = [toe[0] - a.position_m[0], toe[1] - a.position_m[1]];
                let d5 = [-a.d1[0], -a.d1[1]];
                SwingSole {
                    // Heights in the ankle-level convention of the terrain:
                    // the sole is `rise` below the raised ankle.
                    point_m: [ankle[0] + r[0], ankle[1] - a.position_m[1]],
                    velocity_m_s: [v[0] + d5[0] * dphi[4], v[1] + d5[1] * dphi[4]],
                    d5,
                    on_toe: true,
                }
            }
            None => SwingSole {
                point_m: ankle,
                velocity_m_s: v,
                d5: [0.0; 2],
                on_toe: false,
            },
        }
    }

    /// Every generalised force at a state: motors (held), ankle spring,
    /// pilot, joint stops; mapped to T_Φ.
    fn forces(&self, phi: &Phi<f64>, dphi: &Phi<f64>, t_s: f64) -> Forces {
        let (q, dq) = role_angles(phi, dphi);
        let contact_n = self.contact_force(phi, dphi);
        let (pilot, spring) = self.ankle_torques_at(t_s, phi, dphi[0], contact_n);
        // On the toe the ankle rests on its stop: spring and stop torques
        // act between the (massless) foot and the shank, and the toe, not
        // the ankle, meets the ground: nothing of them reaches the chain.
        let toe = self.on_toe(phi[0]);
        let spring = if toe { 0.0 } else { spring };
        let lim = self.cfg.model.limits();
        let bounds = [
            (lim.ankle_plantarflexion_rad, lim.ankle_dorsiflexion_rad),
            (lim.knee_extension_rad, lim.knee_flexion_rad),
            (lim.hip_extension_rad, lim.hip_flexion_rad),
            (lim.hip_extension_rad, lim.hip_flexion_rad),
            (lim.knee_extension_rad, lim.knee_flexion_rad),
        ];
        let mut stops: [f64; LINKS] = match &self.cfg.stops {
            Some(st) => {
                core::array::from_fn(|i| st.torque_nm(q[i], dq[i], bounds[i].0, bounds[i].1))
            }
            None => [0.0; LINKS],
        };
        if self.cfg.foot.is_some() && q[0] > 0.0 {
            // The dorsiflexion stop is the toe rocker's heel-off.
            stops[0] = stops[0].max(0.0);
        }
        let m = self.motor_nm;
        let (st_hip, st_knee, sw_hip, sw_knee) = match self.stance {
            Side::Left => (m[0], m[1], m[2], m[3]),
            Side::Right => (m[2], m[3], m[0], m[1]),
        };
        // Torques on the role coordinates [ankle dorsiflexion, stance knee
        // flexion, stance hip flexion, swing hip flexion, swing knee flexion]
        // = s·θ with s = (−1, +1, −1, +1, −1), so T_θ = s·τ.
        let role = [
            pilot + spring + stops[0],
            st_knee + stops[1],
            st_hip + stops[2],
            sw_hip + stops[3],
            sw_knee + stops[4],
        ];
        let t_theta = [-role[0], role[1], -role[2], role[3], -role[4]];
        let mut stops_nm = [0.0; 4];
        let (hip_s, knee_s, hip_w, knee_w) = match self.stance {
            Side::Left => (0, 1, 2, 3),
            Side::Right => (2, 3, 0, 1),
        };
        stops_nm[hip_s] = stops[2];
        stops_nm[knee_s] = stops[1];
        stops_nm[hip_w] = stops[3];
        stops_nm[knee_w] = stops[4];
        let mut t_phi = t_phi_from_t_theta(&t_theta);
        // Generalised forces of a force F at the swing ankle: Jᵀ F with
        // ∂p5/∂φ_i = l_i (cos φ_i, −sin φ_i) for links 1, 2, 4, 5.
        let l = self.cfg.model.lengths();
        for i in [0, 1, 3, 4] {
            t_phi[i] += l[i] * (phi[i].cos() * contact_n[0] - phi[i].sin() * contact_n[1]);
        }
        // The moving stance ankle carries the swing foot with it; a force
        // on the swing foot's toe also turns its shank.
        let d1 = self.ankle_at(phi[0]).d1;
        t_phi[0] += d1[0] * contact_n[0] + d1[1] * contact_n[1];
        let d5 = self.swing_sole(phi, dphi).d5;
        t_phi[4] += d5[0] * contact_n[0] + d5[1] * contact_n[1];
        Forces {
            t_phi,
            contact_n,
            pilot_nm: pilot,
            spring_nm: spring + stops[0],
            stops_nm,
        }
    }

    /// (pilot, spring) torques on the ankle-dorsiflexion coordinate at `t_s`.
    fn ankle_torques_at(
        &self,
        t_s: f64,
        phi: &Phi<f64>,
        dphi1: f64,
        contact_n: [f64; 2],
    ) -> (f64, f64) {
        let phi1 = phi[0];
        let desired = self.pilot_target.desired(t_s, t_s - self.last_swap_s);
        let spring = -self.cfg.ankle_stiffness_nm_per_rad * (phi1 - self.cfg.ankle_rest_rad);
        // What would hold this posture still on the dorsiflexion coordinate
        // (T_θ1 = −that), less what the spring already gives and what the
        // ground under the other foot takes (its generalised forces Jᵀ F).
        let static_nm = if self.cfg.pilot.gravity_compensation != 0.0 {
            let zero = [0.0; LINKS];
            let mut required = mechanics::inverse_dynamics(
                &self.cfg.model,
                self.cfg.foot.as_ref(),
                phi,
                &zero,
                &zero,
            );
            let l = self.cfg.model.lengths();
            for i in [0, 1, 3, 4] {
                required[i] -= l[i] * (phi[i].cos() * contact_n[0] - phi[i].sin() * contact_n[1]);
            }
            let d1 = self.ankle_at(phi1).d1;
            required[0] -= d1[0] * contact_n[0] + d1[1] * contact_n[1];
            let d5 = self.swing_sole(phi, &[0.0; LINKS]).d5;
            required[4] -= d5[0] * contact_n[0] + d5[1] * contact_n[1];
            let spring_now = if self.on_toe(phi1) { 0.0 } else { spring };
            -joint_torques(&required)[0] - spring_now
        } else {
            0.0
        };
        let pilot = self.cfg.pilot.torque_nm(desired, phi1, dphi1, static_nm);
        (pilot, spring)
    }

    /// Swing-ankle world position and velocity at a state.
    fn swing_foot_at(&self, phi: &Phi<f64>, dphi: &Phi<f64>) -> ([f64; 2], [f64; 2]) {
        let p5 = forward_kinematics(&self.cfg.model, phi)[4];
        let a = self.ankle_at(phi[0]);
        let l = self.cfg.model.lengths();
        let mut v = [a.d1[0] * dphi[0], a.d1[1] * dphi[0]];
        for i in [0, 1, 3, 4] {
            v[0] += l[i] * dphi[i] * phi[i].cos();
            v[1] -= l[i] * dphi[i] * phi[i].sin();
        }
        let o = self.stance_foot_m;
        (
            [
                o[0] + a.position_m[0] + p5[0],
                o[1] + a.position_m[1] + p5[1],
            ],
            v,
        )
    }

    /// The ground's force on the swing ankle at a state (world x, y), N.
    fn contact_force(&self, phi: &Phi<f64>, dphi: &Phi<f64>) -> [f64; 2] {
        let Some(c) = &self.cfg.contact else {
            return [0.0; 2];
        };
        let sole = self.swing_sole(phi, dphi);
        let (p, v) = (sole.point_m, sole.velocity_m_s);
        let depth = self.cfg.terrain.height_m(p[0]) - p[1];
        if depth <= 0.0 {
            return [0.0; 2];
        }
        let fy = (c.stiffness_n_per_m * depth - c.damping_n_s_per_m * v[1]).max(0.0);
        let stick = self
            .contact_anchor_x
            .filter(|&(_, toe)| toe == sole.on_toe)
            .map_or(0.0, |(ax, _)| -c.tangential_stiffness_n_per_m * (p[0] - ax));
        let limit = c.friction * fy;
        let fx = (stick - c.tangential_damping_n_s_per_m * v[0]).clamp(-limit, limit);
        [fx, fy]
    }

    /// Remembers where the swing foot's contact began; forgets it once the
    /// foot is clear of the ground.
    fn update_contact_anchor(&mut self) {
        let sole = self.swing_sole(&self.phi, &self.dphi);
        let p = sole.point_m;
        let depth = self.cfg.terrain.height_m(p[0]) - p[1];
        let same = self
            .contact_anchor_x
            .is_some_and(|(_, toe)| toe == sole.on_toe);
        if depth >= 0.0 {
            if !same {
                self.contact_anchor_x = Some((p[0], sole.on_toe));
            }
        } else if depth < -0.001 {
            self.contact_anchor_x = None;
        }
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

    /// Swing-ankle position in the world, m.
    fn swing_foot_world(&self) -> [f64; 2] {
        self.swing_foot_at(&self.phi, &self.dphi).0
    }

    /// The swing foot's sole above the ground (the toe, for a foot whose
    /// heel is up), m.
    fn swing_height_above_ground_m(&self) -> f64 {
        let p = self.swing_sole(&self.phi, &self.dphi).point_m;
        p[1] - self.cfg.terrain.height_m(p[0])
    }

    /// Swing-ankle velocity, m/s: Σ l_i φ̇_i (cos φ_i, −sin φ_i) over links
    /// 1, 2, 4, 5.
    fn swing_foot_velocity(&self) -> [f64; 2] {
        self.swing_foot_at(&self.phi, &self.dphi).1
    }

    fn detect_landing(&mut self) -> Option<Landing> {
        let above = self.swing_height_above_ground_m();
        if !self.lifted {
            // Lifted: clear of the ground by the clearance, or carried
            // forward (or back) a good part of a step — a low swing whose
            // foot, still leaning on its toe's geometry, never shows the
            // clearance; a foot hovering after an impact does neither.
            let travel = (self.swing_foot_world()[0] - self.swing_start_x_m).abs();
            if above > self.cfg.lift_clearance_m || travel >= MIN_STEP_TRAVEL_M {
                self.lifted = true;
            }
            return None;
        }
        let v = self.swing_foot_velocity();
        // Touching down, or already standing on it: a foot set down at rest
        // (a table that lands with zero speed) may settle into the ground
        // without ever moving down through the tolerance band.
        let touching = above <= self.cfg.landing_tolerance_m && v[1] < 0.0;
        let loaded = self.contact_n[1] >= LANDED_LOAD_N;
        if !(touching || loaded) {
            return None;
        }
        let foot = self.swing_foot_world();
        let mut landing = Landing {
            time_s: self.time_s,
            side: self.stance.other(),
            position_m: foot,
            ground_m: self.cfg.terrain.height_m(foot[0]),
            descent_speed_m_s: -v[1],
            step_length_m: foot[0] - self.stance_foot_m[0],
            trailing_foot_speed_up_m_s: 0.0,
        };
        self.swap(foot);
        landing.trailing_foot_speed_up_m_s = self.swing_foot_velocity()[1];
        self.landings.push(landing);
        Some(landing)
    }

    /// Mirrors the posture onto the other leg and applies the impact map
    /// ([`crate::impact`]); see the module docs.
    fn swap(&mut self, new_stance_foot: [f64; 2]) {
        let a = self.ankle_at(self.phi[0]);
        let old_ankle = [
            self.stance_foot_m[0] + a.position_m[0],
            self.stance_foot_m[1] + a.position_m[1],
        ];
        let old_ankle_vel = [a.d1[0] * self.dphi[0], a.d1[1] * self.dphi[0]];
        let [p1, p2, p3, p4, p5] = self.phi;
        let [_, _, w3, w4, w5] = self.dphi;
        let near_zero = gait_core::kinematics::wrap_pi::<f64>;
        let near_pi = |x: f64| PI + near_zero(x - PI);
        let phi_new = [
            near_zero(p5 - PI),
            near_zero(p4 - PI),
            near_zero(p3),
            near_pi(p2 + PI),
            near_pi(p1 + PI),
        ];
        self.dphi = crate::impact::post_impact_velocities(
            &self.cfg.model,
            &self.phi,
            &self.dphi,
            old_ankle,
            old_ankle_vel,
            &phi_new,
            new_stance_foot,
        )
        // Fallback (never needed for a physical posture): keep the new stance
        // leg's and the torso's angular velocities, stop the new swing leg.
        .unwrap_or([w5, w4, w3, 0.0, 0.0]);
        self.phi = phi_new;
        // The pilot's target was the old stance shank's: until the harness
        // gives one for the new stance shank, the pilot holds it where it is
        // (a target of the other shank would read as a 0.2 rad error).
        self.pilot_target = PilotTarget::Hold {
            phi1_rad: phi_new[0],
        };
        self.stance = self.stance.other();
        self.stance_foot_m = new_stance_foot;
        self.last_swap_s = self.time_s;
        self.lifted = false;
        self.swing_start_x_m = self.swing_foot_world()[0];
        self.contact_anchor_x = None;
        self.update_contact_anchor();
        // A failure here would repeat at the next step's first stage and be
        // reported there; the outputs keep their pre-swap values meanwhile.
        let _ = self.refresh_outputs();
    }

    /// The true state now.
    pub fn state(&self) -> TrueState {
        let model = &self.cfg.model;
        let pts = forward_kinematics(model, &self.phi);
        let a = self.ankle_at(self.phi[0]).position_m;
        let o = [self.stance_foot_m[0] + a[0], self.stance_foot_m[1] + a[1]];
        let world = |p: [f64; 2]| [o[0] + p[0], o[1] + p[1]];
        let points_m = [
            o,
            world(pts[0]),
            world(pts[1]),
            world(pts[2]),
            world(pts[3]),
            world(pts[4]),
        ];
        let (anat, rates) = role_angles(&self.phi, &self.dphi);
        let (angles, rates_out) = match self.stance {
            Side::Left => (
                [anat[2], anat[1], anat[3], anat[4]],
                [rates[2], rates[1], rates[3], rates[4]],
            ),
            Side::Right => (
                [anat[3], anat[4], anat[2], anat[1]],
                [rates[3], rates[4], rates[2], rates[1]],
            ),
        };
        let mut ankle = [None; 2];
        // The encoder reads the shank–foot angle: φ1, or the stop once the
        // heel is up.
        ankle[self.stance.index()] = Some(
            self.cfg
                .foot
                .map_or(self.phi[0], |f| f.dorsiflexion(self.phi[0])),
        );
        let mut feet_m = [[0.0; 2]; 2];
        feet_m[self.stance.index()] = o;
        feet_m[self.stance.other().index()] = points_m[5];

        let coms = link_com(model, &self.phi);
        let total_m = model.total_mass_kg();
        let mut com = [0.0; 2];
        for (c, l) in coms.iter().zip(model.links()) {
            com[0] += l.mass_kg * c[0] / total_m;
            com[1] += l.mass_kg * c[1] / total_m;
        }
        let com_m = world(com);

        let crutch_forces_n = self.cfg.pilot.crutch_forces_n(self.pilot_nm);
        let support = total_m * (GRAVITY_M_S2 + self.com_accel_y());
        let feet_total = (support - crutch_forces_n[0] - crutch_forces_n[1]).max(0.0);
        // The swing foot carries what the ground contact pushes; the stance
        // foot the rest of the support the crutches do not take.
        let swing_load = self.contact_n[1].max(0.0);
        let mut foot_forces_n = [0.0; 2];
        foot_forces_n[self.stance.index()] = (feet_total - swing_load).max(0.0);
        foot_forces_n[self.stance.other().index()] = swing_load;

        let spring_angle = self
            .cfg
            .foot
            .map_or(self.phi[0], |f| f.dorsiflexion(self.phi[0]));
        let spring_pe = 0.5
            * self.cfg.ankle_stiffness_nm_per_rad
            * (spring_angle - self.cfg.ankle_rest_rad).powi(2);
        let chain = mechanics::energy(model, self.cfg.foot.as_ref(), &self.phi, &self.dphi);
        let energy_j = chain + total_m * GRAVITY_M_S2 * self.stance_foot_m[1] + spring_pe;
        TrueState {
            time_s: self.time_s,
            stance: self.stance,
            phi: self.phi,
            dphi: self.dphi,
            joint_angles_rad: angles,
            joint_rates_rad_s: rates_out,
            ankle_dorsiflexion_rad: ankle,
            feet_m,
            points_m,
            com_m,
            foot_forces_n,
            crutch_forces_n,
            pilot_torque_nm: self.pilot_nm,
            spring_torque_nm: self.spring_nm,
            stop_torques_nm: self.stops_nm,
            motor_torques_nm: self.motor_nm,
            energy_j,
            swing_lifted: self.lifted,
        }
    }

    /// Vertical acceleration of the centre of mass, m/s²: the stance
    /// ankle's own (on its circle about the toe) plus the links' relative
    /// to it ([`gait_core::kinematics::link_com_accelerations`]).
    fn com_accel_y(&self) -> f64 {
        let model = &self.cfg.model;
        let a = self.ankle_at(self.phi[0]);
        let base = a.d1[1] * self.ddphi[0] + a.d2[1] * self.dphi[0].powi(2);
        let relative = link_com_accelerations(model, &self.phi, &self.dphi, &self.ddphi);
        let mut total = model.total_mass_kg() * base;
        for (link, [_, y]) in model.links().iter().zip(relative) {
            total += link.mass_kg * y;
        }
        total / model.total_mass_kg()
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

fn check_config(cfg: &PlantConfig) -> Result<(), SimError> {
    let positive = |v: f64| v.is_finite() && v > 0.0;
    let non_negative = |v: f64| v.is_finite() && v >= 0.0;
    if !positive(cfg.dt_s) {
        return Err(SimError::Config("dt_s"));
    }
    if cfg.substeps == 0 {
        return Err(SimError::Config("substeps"));
    }
    if !non_negative(cfg.ankle_stiffness_nm_per_rad) || !cfg.ankle_rest_rad.is_finite() {
        return Err(SimError::Config("ankle spring"));
    }
    let p = &cfg.pilot;
    if !non_negative(p.kp_nm_per_rad)
        || !non_negative(p.kd_nm_s_per_rad)
        || !non_negative(p.torque_limit_nm)
        || !positive(p.crutch_lever_m)
        || !non_negative(p.baseline_crutch_load_n)
    {
        return Err(SimError::Config("pilot"));
    }
    if !cfg.terrain.is_valid() {
        return Err(SimError::Config("terrain"));
    }
    if !non_negative(cfg.landing_tolerance_m)
        || !positive(cfg.lift_clearance_m)
        || cfg.lift_clearance_m <= cfg.landing_tolerance_m
        || !non_negative(cfg.contact_tolerance_m)
    {
        return Err(SimError::Config("contact tolerances"));
    }
    if !positive(cfg.max_speed_rad_s) || !cfg.min_hip_height_m.is_finite() {
        return Err(SimError::Config("blow-up guards"));
    }
    Ok(())
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
