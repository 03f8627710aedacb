//! The facts the supervisor receives each tick ([`SupervisorInput`]),
//! plain data the controller fills after sensing and computing, before it
//! writes.

use super::{ANKLES, DriveCurrentSense, FORCES, JOINTS, Side};

/// Outcome of one encoder read: the driver's own error kind.
pub use crate::drivers::as5048a::ReadStatus as EncoderStatus;

/// One encoder sample. When `status` is not `Ok` the other fields are
/// ignored (the controller may fill them with anything, NaN included).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EncoderSense {
    /// What the driver reported.
    pub status: EncoderStatus,
    /// Raw 14-bit counts from the ANGLE register.
    pub raw_counts: u16,
    /// Calibrated angle, rad, in (−π, π].
    pub angle_rad: f32,
}

/// Outcome of one force conversion: the driver's own error kind.
pub use crate::drivers::mcp3208::ReadStatus as ForceStatus;

/// One force sample. `newtons` is ignored unless `status` is `Ok`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ForceSense {
    /// What the driver reported.
    pub status: ForceStatus,
    /// Calibrated force, N.
    pub newtons: f32,
}

/// One motor output, as computed this tick and reported by the driver.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MotorSense {
    /// Torque the controller computed this tick, before any limiting, N·m.
    pub commanded_nm: f32,
    /// Torque the driver applied at the last tick, N·m.
    pub applied_nm: f32,
    /// Current magnitude limit, N·m: `Motor::thermal_limit_nm()` (the
    /// I²t-derated limit, not scaled by the soft start); must be > 0.
    pub limit_nm: f32,
    /// The driver has latched a thermal (I²t) fault.
    pub thermal_fault: bool,
    /// The driver has latched an output-stage fault (a write failed).
    pub output_fault: bool,
    /// The drive is enabled and past its soft start: it gave the torque
    /// asked for, `applied_nm` (0x0404 checks only then).
    pub enabled: bool,
    /// The feed-forward part of `commanded_nm`: the model's torque for the
    /// reference motion, N·m (0x0404 checks the rest against the motion).
    pub feedforward_nm: f32,
}

/// Everything the supervisor needs for one tick. Plain data, filled by the
/// controller after sensing and computing, before writing.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SupervisorInput {
    /// Tick number, copied into log records.
    pub tick: u32,
    /// Actuated joint encoders.
    pub joints: [EncoderSense; JOINTS],
    /// Reference angle of each actuated joint this tick, rad. While the
    /// motors are disabled it must follow the measured angle.
    pub joint_reference_rad: [f32; JOINTS],
    /// Ankle encoders.
    pub ankles: [EncoderSense; ANKLES],
    /// Foot and crutch force sensors.
    pub forces: [ForceSense; FORCES],
    /// Motor outputs, one per actuated joint.
    pub motors: [MotorSense; JOINTS],
    /// The emergency-stop input reads pressed.
    pub e_stop_pressed: bool,
    /// The emergency-stop input could not be read.
    pub e_stop_read_error: bool,
    /// The previous tick overran its 1 ms budget.
    pub deadline_missed: bool,
    /// A step is being taken (for the record; the reaction is the
    /// controller's to apply).
    pub step_in_progress: bool,
    /// The button driver reports a wiring or read fault.
    pub button_input_fault: bool,
    /// The dorsiflexion the gait plans for each ankle this tick, rad: the
    /// stance ankle's φ1 during a swing; NaN where nothing is planned (the
    /// swing ankle, standing). For the unplanned heel-off rule (0x0105)
    /// and the pilot's balance (0x0701, 0x0702).
    pub ankle_plan_rad: [f32; ANKLES],
    /// The leg in the air (`None` while both feet are down): its joints
    /// move only their own links (0x0404's swing inertias), and the
    /// crutches are judged through its swing (0x0703).
    pub swing_leg: Option<Side>,
    /// The torque-residual limit the playing gait sets for the stance hip
    /// of its swings, N·m (NaN or 0: the device's; 0x0404,
    /// [`super::ResponseCheck::stance_hip_limit_nm`]).
    pub stance_hip_residual_nm: f32,
    /// The swing leg once its foot is surely in the air (the table's
    /// landing window, no contact yet; `Sequencer::airborne_leg`): an
    /// ankle its spring must have taken off the dorsiflexion stop.
    pub airborne_leg: Option<Side>,
    /// Joints whose angle control takes this tick from the closed chain of
    /// double support, not from their own encoder
    /// ([`crate::posture::joint_through_closed_chain`]): a joint whose
    /// encoder is lost ([`FaultCode::loses_angle`]) is then held by its
    /// drive, not braked.
    pub chain_closed: [bool; JOINTS],
    /// The drive whose current monitor was sampled this tick, if any (one
    /// drive a tick, in turn).
    pub drive_current: Option<DriveCurrentSense>,
}
