//! The plant's parameters: the body, the ground contact, the joint stops,
//! the limits that end a run; checked once when the plant is built.

use super::*;

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

pub(super) fn check_config(cfg: &PlantConfig) -> Result<(), SimError> {
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
