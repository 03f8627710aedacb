//! Clinical mode: gait tables for the device we ship, optimised for what the
//! pilot feels — the crutch load — within what the drives and the
//! supervisor allow (paper mode, in [`crate::solver`], stays the paper's
//! problem and is the record).
//!
//! - The step is a [`ClinicalStep`] (gait-core): double support first, the
//!   stance shank a decision variable, smooth curves, the IK's continuous
//!   knee range, periodic.
//! - The cost is the predicted **balance part of the crutch impulse**,
//!   Σ |τ_pilot| Δt / lever over the step and the weight transfer after it,
//!   from gait-core's [`playback`] (the same sharing of the load between
//!   the feet and the same passive ankle spring the controller's
//!   feed-forward and the simulator use; the pilot's constant lean on the
//!   crutches is not in it: no gait changes it).
//! - Soft limits (quadratic penalties, heavy enough that the optimum sits
//!   inside them): every hip and knee torque within a share of what the
//!   drive can give at that speed; the drives' I²t over two steps (each
//!   joint is a stance joint one step and a swing joint the next) below the
//!   continuous rating; joint speed and acceleration; joint range inside
//!   Table I; the swing foot's clearance over the floor or the nosing; the
//!   pilot's and the stance ankle's peak no higher than the human gait's;
//!   enough weight on the stance foot at the start for the readiness gate.
//!
//! Evaluations are deterministic; the search ([`optimize_clinical`]) is
//! seeded and budgeted by evaluation count, so a table regenerates byte for
//! byte. `docs/optimiser.md` ("Clinical mode") gives each choice and its
//! reason.

pub mod closed_loop;
mod evaluate;
mod search;

pub use evaluate::{EvalError, Evaluation, evaluate_phi, step_phi};
pub use search::{
    ClinicalConfig, ClinicalResult, ClinicalSearchError, DIM, decode, initial_point,
    optimize_clinical,
};

use exogait_device::DeviceConfig;
use exogait_device::drive::DriveSpec;
use gait_core::BodyModel;
use gait_core::foot::StanceFoot;
use gait_core::ik::{IkOptions, KneeRange};
use gait_core::tables::GaitKind;

/// Sample period of the tables, s (the paper's Δt).
pub const TABLE_PERIOD_S: f64 = 0.01;

/// What the device and the pilot allow, for one gait.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClinicalLimits {
    /// The hip and knee drive.
    pub drive: DriveSpec,
    /// Share of the torque the drive can give (at the joint's speed) that
    /// the table's feed-forward may use: the rest is for the position loop
    /// (tracking, model error, the landing).
    pub torque_share: f64,
    /// Share of the continuous current² the two-step mean of I² may use.
    pub i2t_share: f64,
    /// Largest hip and knee speed, rad/s.
    pub joint_speed_rad_s: f64,
    /// Largest hip and knee acceleration, rad/s².
    pub joint_accel_rad_s2: f64,
    /// The supervisor's envelope, (lowest, highest) anatomical angle, rad:
    /// hip, knee, and the stance ankle's dorsiflexion.
    pub envelope_rad: [(f64, f64); 3],
    /// How far inside the envelope the table stays, rad.
    pub range_margin_rad: f64,
    /// The exoskeleton ankle's passive spring, N·m/rad.
    pub ankle_spring_nm_per_rad: f64,
    /// Weight transfer after the landing (both feet down, the table's last
    /// posture held), s.
    pub transfer_s: f64,
    /// Largest share of the body's weight the trailing foot may carry at
    /// the start (the stance foot must carry the readiness gate's load and
    /// the crutches some too).
    pub start_trailing_share: f64,
    /// Swing-foot clearance over the floor (level) or over the nosing it
    /// crosses (stairs), m: (lowest, highest).
    pub clearance_m: (f64, f64),
}

/// Caps from the human-data gait at the same geometry and timing: the
/// table may not ask more of the pilot or of the stance ankle at any
/// instant than replayed human gait does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HumanCaps {
    /// Peak |pilot torque|, N·m.
    pub pilot_peak_nm: f64,
    /// Peak |stance-ankle torque| (T_θ1 after sharing), N·m.
    pub ankle_peak_nm: f64,
}

/// One gait's clinical problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClinicalCase {
    /// Which gait.
    pub gait: GaitKind,
    /// Front ankle relative to the back one in double support, m.
    pub spacing_m: [f64; 2],
    /// Step time, s.
    pub step_time_s: f64,
    /// Pilot plus exoskeleton.
    pub model: BodyModel<f64>,
    /// The feet's toe rocker.
    pub foot: StanceFoot<f64>,
    /// The IK's options (continuous human knee range).
    pub ik: IkOptions<f64>,
    /// The device's limits.
    pub limits: ClinicalLimits,
    /// The human gait's peaks (infinite where none is given).
    pub caps: HumanCaps,
    /// Lever that turns the pilot's torque into crutch force, m (the
    /// simulated pilot's; only scales the reported impulse).
    pub crutch_lever_m: f64,
}

/// The pilot's crutch lever used to report impulses in newton-seconds, m
/// (sim's `PilotConfig::default`; the optimum does not depend on it).
pub const CRUTCH_LEVER_M: f64 = 0.45;

impl ClinicalCase {
    /// The case of `gait` on `device`: walking 0.3 m steps in 2.24 s, stairs
    /// (tread 0.275 m, rise 0.0935 m, the paper's) up or down in 2.28 s —
    /// the paper's geometry and timing.
    pub fn for_gait(gait: GaitKind, device: &DeviceConfig) -> Self {
        let (spacing_m, step_time_s, knee_cap_deg) = match gait {
            GaitKind::Walk => ([0.3, 0.0], 2.24, 60.0),
            GaitKind::StairUp => ([0.275, 0.0935], 2.28, 70.0),
            GaitKind::StairDown => ([0.275, -0.0935], 2.28, 90.0),
        };
        let model = device.body;
        let drive = device.drives[1];
        let seq = device.controller.sequencer;
        Self {
            gait,
            spacing_m,
            step_time_s,
            model,
            foot: StanceFoot::for_model(&model),
            ik: IkOptions {
                stance_knee_max_rad: f64::to_radians(knee_cap_deg),
                knee_range: KneeRange::Human,
            },
            limits: ClinicalLimits {
                drive,
                torque_share: 0.75,
                i2t_share: 0.85,
                joint_speed_rad_s: 1.8,
                joint_accel_rad_s2: 20.0,
                envelope_rad: {
                    let sv = &device.supervisor;
                    let r = |a: gait_control::supervisor::AngleRange| {
                        (f64::from(a.min_rad), f64::from(a.max_rad))
                    };
                    [
                        r(sv.joint_range[0]),
                        r(sv.joint_range[1]),
                        r(sv.ankle_range[0]),
                    ]
                },
                range_margin_rad: 5f64.to_radians(),
                ankle_spring_nm_per_rad: device.ankle_spring_nm_per_rad,
                transfer_s: f64::from(seq.transfer_s),
                // The stance foot carries at least a fifth of the body at
                // the start: the step begins from a stable double support.
                start_trailing_share: 0.8,
                // The clinical band is 3–8 cm; the table aims inside it so
                // that tracking lag does not take the foot out.
                clearance_m: (0.04, 0.07),
            },
            caps: HumanCaps {
                pilot_peak_nm: f64::INFINITY,
                ankle_peak_nm: f64::INFINITY,
            },
            crutch_lever_m: CRUTCH_LEVER_M,
        }
    }
}

impl ClinicalCase {
    /// The case on another body model: its mass properties, and its joint
    /// limits as the envelope (the supervisor's construction from them).
    pub fn with_model(mut self, model: BodyModel<f64>) -> Self {
        let m32: BodyModel<f32> = model.cast();
        let sv = gait_control::supervisor::SupervisorConfig::default_for(m32.limits());
        let r =
            |a: gait_control::supervisor::AngleRange| (f64::from(a.min_rad), f64::from(a.max_rad));
        self.limits.envelope_rad = [
            r(sv.joint_range[0]),
            r(sv.joint_range[1]),
            r(sv.ankle_range[0]),
        ];
        self.foot = StanceFoot::for_model(&model);
        self.model = model;
        self
    }
}
