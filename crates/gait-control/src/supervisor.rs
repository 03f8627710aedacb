//! The safety supervisor: checked once per 1 kHz tick, after the controller
//! has sensed and computed its commands and before any output is written.
//!
//! It only receives facts ([`SupervisorInput`]), decides ([`Verdict`]) and
//! never waits: no allocation, no panics, a fixed amount of work per call
//! (loops only over the fixed-size joint, ankle, sensor and fault arrays).
//! The fault table, the detection bounds, the reactions and the reset rules
//! are in `docs/safety.md`; the tests in `tests/supervisor.rs` check one
//! row each.
//!
//! # Time
//!
//! Every window and debounce counts calls of [`Supervisor::check`] (one per
//! tick), not `input.tick`, which is only copied into the log, so a
//! controller that repeats or skips a tick number cannot stretch a window.
//!
//! # NaN
//!
//! Every comparison is written so that NaN fails it (`!(x <= limit)` rather
//! than `x > limit`): a NaN value can only trip a fault, never pass a check.

use heapless::HistoryBuf;

use crate::drivers::as5048a::{DATA_MASK, wrapped_delta};
use crate::faults::{FaultCode, FaultSet, Reaction};

pub use crate::layout::{ANKLES, FORCES, JOINTS};
/// Records kept in the post-mortem log (the newest ones).
pub const LOG_LEN: usize = 32;
/// Channel of a [`FaultRecord`] for faults that belong to no channel.
pub const NO_CHANNEL: u8 = 0xFF;
/// Longest debounce window for encoder and force samples, ticks.
pub const MAX_SAMPLE_WINDOW_TICKS: u8 = 128;
/// Largest number of deadline misses the deadline rule can count.
pub const MAX_DEADLINE_MISSES: u8 = 8;

/// Largest |angle| an AS5048A reading can give after calibration, rad
/// (the driver's range is (−π, π]; a little slack for rounding).
const MAX_ENCODER_ANGLE_RAD: f32 = core::f32::consts::PI + 1e-3;

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
    /// swing ankle, standing). For the unplanned heel-off rule (0x0105).
    pub ankle_plan_rad: [f32; ANKLES],
}

/// Allowed range of one angle, rad.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AngleRange {
    /// Smallest allowed angle, rad.
    pub min_rad: f32,
    /// Largest allowed angle, rad.
    pub max_rad: f32,
}

impl AngleRange {
    /// Whether `angle_rad` is inside (false for NaN).
    #[must_use]
    pub fn contains(&self, angle_rad: f32) -> bool {
        self.min_rad <= angle_rad && angle_rad <= self.max_rad
    }
}

/// "`count` bad samples within the last `window_ticks` ticks" (the tick
/// being checked included).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Debounce {
    /// Bad samples needed, ≥ 1.
    pub count: u8,
    /// Window, ticks, in `count..=MAX_SAMPLE_WINDOW_TICKS`.
    pub window_ticks: u8,
}

/// How far inside Table I's mechanical stops the envelope lies.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EnvelopeMargins {
    /// Margin inside every hip and knee stop, rad.
    pub joint_margin_rad: f32,
    /// Where a stop is at (or within the margin of) 0°, the knee may read
    /// this far past 0 (encoder calibration, compliance), rad.
    pub knee_hyperextension_tolerance_rad: f32,
    /// How far past the ankle's dorsiflexion stop a reading may go, rad.
    /// The stop itself is where the toe rocker lifts the heel
    /// (`gait_core::foot`): stair descent rests the trailing ankle on it,
    /// so the envelope ends just beyond it (the stop's compliance and the
    /// encoder's calibration), not inside it.
    pub ankle_stop_tolerance_rad: f32,
    /// Margin inside the ankle's plantarflexion stop, where that stop is far
    /// from 0° (the heel rocker's 12°), rad.
    pub ankle_margin_rad: f32,
    /// Like the knee's tolerance, for plantarflexion past 0, rad.
    pub ankle_plantarflexion_tolerance_rad: f32,
}

impl EnvelopeMargins {
    /// 5° inside the hip and knee stops, 3° of knee hyperextension, 2°
    /// past the ankle's dorsiflexion stop, 2° inside its plantarflexion stop
    /// or 3° past it when it is at 0°.
    pub const DEFAULT: Self = Self {
        joint_margin_rad: 5.0 * DEG,
        knee_hyperextension_tolerance_rad: 3.0 * DEG,
        ankle_stop_tolerance_rad: 2.0 * DEG,
        ankle_margin_rad: 2.0 * DEG,
        ankle_plantarflexion_tolerance_rad: 3.0 * DEG,
    };
}

const DEG: f32 = core::f32::consts::PI / 180.0;

/// `|x| ≤ limit`; false for NaN, so `!within(..)` trips on NaN.
fn within(x: f32, limit: f32) -> bool {
    x.abs() <= limit
}

/// Limits and detection bounds. Build it with
/// [`SupervisorConfig::default_for`] (or [`SupervisorConfig::paper`]) and
/// change fields as needed; [`Supervisor::new`] checks it once.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SupervisorConfig {
    /// Tick period, s (0.001 at 1 kHz).
    pub dt_s: f32,
    /// Envelope of each actuated joint.
    pub joint_range: [AngleRange; JOINTS],
    /// Envelope of each ankle.
    pub ankle_range: [AngleRange; ANKLES],
    /// Magnitude limit of each joint's filtered velocity, rad/s.
    pub velocity_limit_rad_s: [f32; JOINTS],
    /// Velocity filter weight α in (0, 1]: `v ← v + α (v_raw − v)` per
    /// accepted sample.
    pub velocity_filter_alpha: f32,
    /// Magnitude limit of |angle − reference|, rad.
    pub tracking_error_limit_rad: f32,
    /// Consecutive ticks over the tracking limit that make a fault.
    pub tracking_error_ticks: u32,
    /// Bad encoder frames (bus, parity, error flag, jump) that make a fault.
    pub encoder_debounce: Debounce,
    /// Largest plausible change of raw counts per tick.
    pub max_jump_counts_per_tick: u16,
    /// Consecutive ticks of unchanged raw counts while driven that make a
    /// frozen-encoder fault.
    pub frozen_ticks: u32,
    /// The joint counts as driven when its reference moves at least this
    /// fast, rad/s …
    pub frozen_reference_speed_rad_s: f32,
    /// … or when |command| ≥ this fraction of the motor's limit. Near the
    /// limit (0.9 by default), not below: a still stance knee holding the
    /// body, or a joint held against its stop, legitimately reads constant
    /// counts under a large command.
    pub frozen_command_fraction: f32,
    /// Bad force samples (bus, open, shorted, out of range) that make a
    /// fault.
    pub force_debounce: Debounce,
    /// Rated range of the force sensors, N.
    pub force_min_n: f32,
    /// Rated range of the force sensors, N.
    pub force_max_n: f32,
    /// Consecutive ticks with |command| ≥ limit that make a fault.
    pub saturation_ticks: u32,
    /// The ankles' dorsiflexion stop, where the heel lifts (the toe
    /// rocker), rad.
    pub heel_off_rad: f32,
    /// A reading within this of the stop counts as resting on it, rad.
    pub heel_off_reading_tolerance_rad: f32,
    /// Resting on the stop is unplanned when the plan is more than this
    /// below it, rad.
    pub heel_off_plan_margin_rad: f32,
    /// Consecutive ticks of unplanned heel-off that make a fault.
    pub heel_off_ticks: u32,
    /// Missed deadlines within the window that make a fault (1 ..=
    /// [`MAX_DEADLINE_MISSES`]).
    pub deadline_miss_count: u8,
    /// Window of the deadline rule, ticks.
    pub deadline_window_ticks: u32,
}

impl SupervisorConfig {
    /// The envelope from `limits` (Table I form) with
    /// [`EnvelopeMargins::DEFAULT`] and the default detection bounds.
    #[must_use]
    pub fn default_for(limits: &gait_core::JointLimits<f32>) -> Self {
        Self::with_margins(limits, &EnvelopeMargins::DEFAULT)
    }

    /// Table I of the paper with the default margins and bounds.
    #[must_use]
    pub fn paper() -> Self {
        Self::default_for(&gait_core::JointLimits::paper_table_i())
    }

    /// The envelope from `limits` with `margins`, and the default detection
    /// bounds.
    ///
    /// Flexion (dorsiflexion) bounds are the stop minus the margin. For the
    /// extension side, where a stop at 0° is the standing posture itself,
    /// the bound is `−max(stop − margin, tolerance)`: inside a stop that is
    /// far from 0, a few degrees past a stop at 0.
    #[must_use]
    pub fn with_margins(limits: &gait_core::JointLimits<f32>, margins: &EnvelopeMargins) -> Self {
        let m = margins;
        let hip = AngleRange {
            min_rad: -(limits.hip_extension_rad - m.joint_margin_rad),
            max_rad: limits.hip_flexion_rad - m.joint_margin_rad,
        };
        let knee = AngleRange {
            min_rad: -(limits.knee_extension_rad - m.joint_margin_rad)
                .max(m.knee_hyperextension_tolerance_rad),
            max_rad: limits.knee_flexion_rad - m.joint_margin_rad,
        };
        let ankle = AngleRange {
            min_rad: -(limits.ankle_plantarflexion_rad - m.ankle_margin_rad)
                .max(m.ankle_plantarflexion_tolerance_rad),
            max_rad: limits.ankle_dorsiflexion_rad + m.ankle_stop_tolerance_rad,
        };
        Self {
            dt_s: 0.001,
            joint_range: [hip, knee, hip, knee],
            ankle_range: [ankle, ankle],
            // Hip 6, knee 8 rad/s: above what the planned gaits use (the walk
            // table's swing knee extends at up to 5.5 rad/s before landing;
            // healthy walking reaches 6–7), below a runaway.
            velocity_limit_rad_s: [6.0, 8.0, 6.0, 8.0],
            velocity_filter_alpha: 0.2,
            tracking_error_limit_rad: 0.15,
            tracking_error_ticks: 100,
            encoder_debounce: Debounce {
                count: 3,
                window_ticks: 100,
            },
            max_jump_counts_per_tick: 100,
            frozen_ticks: 100,
            frozen_reference_speed_rad_s: 0.1,
            frozen_command_fraction: 0.9,
            force_debounce: Debounce {
                count: 3,
                window_ticks: 100,
            },
            force_min_n: -50.0,
            force_max_n: 2000.0,
            saturation_ticks: 200,
            // On the stop within 0.5° while the plan is 5° or more below it,
            // for 50 ms: the walk and stair-ascent tables never come within
            // 9° of the stop; a descent plans its heel-off.
            heel_off_rad: limits.ankle_dorsiflexion_rad,
            heel_off_reading_tolerance_rad: 0.5 * DEG,
            heel_off_plan_margin_rad: 5.0 * DEG,
            heel_off_ticks: 50,
            deadline_miss_count: 3,
            deadline_window_ticks: 1000,
        }
    }

    /// Checks the configuration (all finite, ranges ordered, windows in
    /// bounds), so the tick need not.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let positive = [
            self.dt_s,
            self.velocity_filter_alpha,
            self.tracking_error_limit_rad,
            self.frozen_reference_speed_rad_s,
            self.frozen_command_fraction,
            self.heel_off_rad,
            self.heel_off_reading_tolerance_rad,
            self.heel_off_plan_margin_rad,
        ];
        let velocities_ok = self
            .velocity_limit_rad_s
            .iter()
            .all(|v| v.is_finite() && *v > 0.0);
        if !(positive.iter().all(|v| v.is_finite() && *v > 0.0) && velocities_ok)
            || self.velocity_filter_alpha > 1.0
        {
            return Err(ConfigError::NotPositive);
        }
        let range_ok = |r: &AngleRange| {
            r.min_rad.is_finite() && r.max_rad.is_finite() && r.min_rad < r.max_rad
        };
        if !(self.joint_range.iter().all(range_ok) && self.ankle_range.iter().all(range_ok)) {
            return Err(ConfigError::BadRange);
        }
        if !(self.force_min_n.is_finite()
            && self.force_max_n.is_finite()
            && self.force_min_n < self.force_max_n)
        {
            return Err(ConfigError::BadRange);
        }
        let debounce_ok = |d: &Debounce| {
            d.count >= 1 && d.count <= d.window_ticks && d.window_ticks <= MAX_SAMPLE_WINDOW_TICKS
        };
        if !(debounce_ok(&self.encoder_debounce) && debounce_ok(&self.force_debounce))
            || self.deadline_miss_count == 0
            || self.deadline_miss_count > MAX_DEADLINE_MISSES
            || self.deadline_window_ticks == 0
            || self.tracking_error_ticks == 0
            || self.frozen_ticks == 0
            || self.saturation_ticks == 0
            || self.heel_off_ticks == 0
            || self.max_jump_counts_per_tick == 0
        {
            return Err(ConfigError::BadWindow);
        }
        Ok(())
    }
}

/// Why a configuration was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// A value that must be finite and > 0 is not (or α > 1).
    NotPositive,
    /// An angle or force range is not finite or not ordered.
    BadRange,
    /// A debounce count, window or tick count is zero or out of bounds.
    BadWindow,
}

/// Why a clinician reset was refused; nothing was cleared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ResetRefused {
    /// The controller does not report a safe posture.
    NotSafePosture,
    /// These faults' conditions were still present at the last check.
    ConditionPresent(FaultSet),
}

/// The supervisor's decision for one tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Verdict {
    /// The most severe reaction over all latched faults.
    pub reaction: Reaction,
    /// Every latched fault.
    pub latched: FaultSet,
    /// Faults latched by this call (not latched before it).
    pub new: FaultSet,
}

/// One post-mortem record: written when a fault latches, and again when
/// the same fault appears on another channel while latched.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FaultRecord {
    /// `input.tick` of the check that raised it.
    pub tick: u32,
    /// The fault.
    pub code: FaultCode,
    /// Joint, ankle, force sensor or motor index; [`NO_CHANNEL`] for none.
    pub channel: u8,
    /// The offending value: angle or error (rad), velocity (rad/s), raw
    /// count change, force (N), command (N·m), or a count (bad samples,
    /// ticks, misses), as listed in `docs/safety.md`.
    pub value: f32,
}

/// Sliding window over the last ≤ 128 ticks: bit 0 is this tick.
#[derive(Debug, Clone, Copy, Default)]
struct SampleWindow {
    history: u128,
}

impl SampleWindow {
    fn push(&mut self, bad: bool) {
        self.history = (self.history << 1) | u128::from(bad);
    }

    fn count(&self, window_ticks: u8) -> u32 {
        let mask = match 1u128.checked_shl(u32::from(window_ticks)) {
            Some(b) => b.wrapping_sub(1),
            None => u128::MAX,
        };
        (self.history & mask).count_ones()
    }
}

/// An accepted encoder sample.
#[derive(Debug, Clone, Copy)]
struct Accepted {
    raw: u16,
    angle_rad: f32,
}

/// History of one encoder (joint or ankle).
#[derive(Debug, Clone, Copy, Default)]
struct EncoderTrack {
    window: SampleWindow,
    /// Code of the latest bad frame (reported when the window trips).
    last_bad: Option<FaultCode>,
    /// Latest accepted sample; `None` until the first and after a re-seed.
    last: Option<Accepted>,
    /// Ticks since `last` was accepted.
    since_last: u32,
    /// Consecutive frames rejected as jumps (re-seed at the debounce count).
    consecutive_jumps: u8,
}

/// What this tick's encoder frame turned out to be.
#[derive(Debug, Clone, Copy)]
enum Frame {
    /// Accepted; `delta_counts` and the elapsed ticks since the previous
    /// accepted sample, if there was one.
    Accepted {
        angle_rad: f32,
        delta: Option<(i16, u32)>,
        previous_angle_rad: f32,
    },
    /// Not used this tick.
    Rejected,
}

impl EncoderTrack {
    /// Classifies `sense`; raises the immediate invalid-value fault through
    /// `invalid`. Returns the frame and whether it was bad.
    fn update(
        &mut self,
        sense: &EncoderSense,
        debounce: Debounce,
        max_jump: u16,
    ) -> (Frame, Option<f32>) {
        self.since_last = self.since_last.saturating_add(1);
        let mut invalid = None;
        let bad_code = match sense.status {
            EncoderStatus::BusError => Some(FaultCode::EncoderBusError),
            EncoderStatus::Parity => Some(FaultCode::EncoderParity),
            EncoderStatus::ErrorFlag => Some(FaultCode::EncoderErrorFlag),
            EncoderStatus::Ok => {
                let angle_ok = sense.angle_rad.abs() <= MAX_ENCODER_ANGLE_RAD;
                if sense.raw_counts > DATA_MASK || !angle_ok {
                    invalid = Some(sense.angle_rad);
                    Some(FaultCode::EncoderInvalidValue)
                } else {
                    None
                }
            }
        };
        if let Some(code) = bad_code {
            self.window.push(true);
            self.last_bad = Some(code);
            return (Frame::Rejected, invalid);
        }
        let current = Accepted {
            raw: sense.raw_counts,
            angle_rad: sense.angle_rad,
        };
        let window = u32::from(debounce.window_ticks);
        let previous = self.last.filter(|_| self.since_last <= window);
        let Some(previous) = previous else {
            // First sample, or a gap longer than the window: (re-)seed.
            self.window.push(false);
            self.accept(current);
            return (
                Frame::Accepted {
                    angle_rad: current.angle_rad,
                    delta: None,
                    previous_angle_rad: current.angle_rad,
                },
                None,
            );
        };
        let delta = wrapped_delta(previous.raw, current.raw);
        let allowed = u32::from(max_jump).saturating_mul(self.since_last);
        if u32::from(delta.unsigned_abs()) > allowed {
            self.window.push(true);
            self.last_bad = Some(FaultCode::EncoderJump);
            self.consecutive_jumps = self.consecutive_jumps.saturating_add(1);
            if self.consecutive_jumps >= debounce.count {
                // The jump persists: it is where the encoder now reads.
                // The fault is raised by the window; take the new value
                // as the reference so the condition can clear.
                self.last = None;
                self.consecutive_jumps = 0;
            }
            return (Frame::Rejected, None);
        }
        let elapsed = self.since_last;
        self.window.push(false);
        self.accept(current);
        (
            Frame::Accepted {
                angle_rad: current.angle_rad,
                delta: Some((delta, elapsed)),
                previous_angle_rad: previous.angle_rad,
            },
            None,
        )
    }

    fn accept(&mut self, sample: Accepted) {
        self.last = Some(sample);
        self.since_last = 0;
        self.consecutive_jumps = 0;
    }

    /// The debounced bad-frame fault, if the window holds enough.
    fn tripped(&self, debounce: Debounce) -> Option<(FaultCode, u32)> {
        let n = self.window.count(debounce.window_ticks);
        if n >= u32::from(debounce.count) {
            self.last_bad.map(|c| (c, n))
        } else {
            None
        }
    }
}

/// Per-joint history.
#[derive(Debug, Clone, Copy, Default)]
struct JointTrack {
    encoder: EncoderTrack,
    velocity_rad_s: f32,
    velocity_valid: bool,
    tracking_ticks: u32,
    frozen_ticks: u32,
    saturated_ticks: u32,
}

/// Per-force-sensor history.
#[derive(Debug, Clone, Copy, Default)]
struct ForceTrack {
    window: SampleWindow,
    last_bad: Option<FaultCode>,
}

/// The safety supervisor. See the module docs and `docs/safety.md`.
#[derive(Debug, Clone)]
pub struct Supervisor {
    cfg: SupervisorConfig,
    /// Calls of `check` so far (the supervisor's own clock).
    calls: u32,
    latched: FaultSet,
    /// Faults whose condition held at the last check.
    present: FaultSet,
    /// Per fault (by index), channels already logged since it latched.
    logged_channels: [u8; FaultCode::COUNT],
    /// Whether a no-channel record was logged since the fault latched.
    logged_none: FaultSet,
    log: HistoryBuf<FaultRecord, LOG_LEN>,
    joints: [JointTrack; JOINTS],
    ankles: [EncoderTrack; ANKLES],
    /// Consecutive ticks each ankle has rested on its stop unplanned.
    heel_off_ticks: [u32; ANKLES],
    forces: [ForceTrack; FORCES],
    previous_reference_rad: Option<[f32; JOINTS]>,
    /// `calls` at the latest deadline misses (ring).
    misses: [Option<u32>; MAX_DEADLINE_MISSES as usize],
    miss_next: usize,
    deadline_misses_total: u32,
}

/// Collects what one check raised.
struct Tick {
    tick: u32,
    present: FaultSet,
    new: FaultSet,
}

impl Supervisor {
    /// Checks `cfg` and starts with nothing latched.
    pub fn new(cfg: SupervisorConfig) -> Result<Self, ConfigError> {
        cfg.validate()?;
        Ok(Self {
            cfg,
            calls: 0,
            latched: FaultSet::EMPTY,
            present: FaultSet::EMPTY,
            logged_channels: [0; FaultCode::COUNT],
            logged_none: FaultSet::EMPTY,
            log: HistoryBuf::new(),
            joints: [JointTrack::default(); JOINTS],
            ankles: [EncoderTrack::default(); ANKLES],
            heel_off_ticks: [0; ANKLES],
            forces: [ForceTrack::default(); FORCES],
            previous_reference_rad: None,
            misses: [None; MAX_DEADLINE_MISSES as usize],
            miss_next: 0,
            deadline_misses_total: 0,
        })
    }

    /// The configuration in use.
    pub const fn config(&self) -> &SupervisorConfig {
        &self.cfg
    }

    /// Every latched fault.
    pub const fn latched(&self) -> FaultSet {
        self.latched
    }

    /// Faults whose condition held at the last check (always a subset of
    /// [`Supervisor::latched`]).
    pub const fn present(&self) -> FaultSet {
        self.present
    }

    /// Deadline misses seen since start (single misses do not latch).
    pub const fn deadline_misses(&self) -> u32 {
        self.deadline_misses_total
    }

    /// The post-mortem log, oldest record first (the newest [`LOG_LEN`]).
    pub fn log(&self) -> impl Iterator<Item = &FaultRecord> {
        self.log.oldest_ordered()
    }

    /// Clinician reset (MODE + GO held 3 s, `docs/operation.md`). Honoured
    /// only in a safe posture and only if no latched fault's condition was
    /// present at the last check; then every latched fault is cleared at
    /// once (the log is kept). Refused otherwise, and nothing changes.
    pub fn request_reset(&mut self, safe_posture: bool) -> Result<(), ResetRefused> {
        if !safe_posture {
            return Err(ResetRefused::NotSafePosture);
        }
        let still = self.present.intersection(self.latched);
        if !still.is_empty() {
            return Err(ResetRefused::ConditionPresent(still));
        }
        self.latched = FaultSet::EMPTY;
        self.logged_channels = [0; FaultCode::COUNT];
        self.logged_none = FaultSet::EMPTY;
        Ok(())
    }

    /// The per-tick check: updates every detector with `input`, latches
    /// what tripped, and returns the reaction over all latched faults.
    pub fn check(&mut self, input: &SupervisorInput) -> Verdict {
        self.calls = self.calls.wrapping_add(1);
        let mut t = Tick {
            tick: input.tick,
            present: FaultSet::EMPTY,
            new: FaultSet::EMPTY,
        };
        self.check_operator_inputs(input, &mut t);
        self.check_deadline(input, &mut t);
        self.check_motors(input, &mut t);
        self.check_joints(input, &mut t);
        self.check_ankles(input, &mut t);
        self.check_forces(input, &mut t);
        self.previous_reference_rad = Some(input.joint_reference_rad);
        self.present = t.present;
        Verdict {
            reaction: self.latched.reaction(),
            latched: self.latched,
            new: t.new,
        }
    }

    /// Records that `code`'s condition holds now on `channel`: latches it,
    /// and logs it once per channel while latched.
    fn raise(&mut self, t: &mut Tick, code: FaultCode, channel: u8, value: f32) {
        t.present.insert(code);
        if !self.latched.contains(code) {
            self.latched.insert(code);
            t.new.insert(code);
        }
        let index = usize::from(code.index());
        let first_time = if channel == NO_CHANNEL {
            let first = !self.logged_none.contains(code);
            self.logged_none.insert(code);
            first
        } else {
            let bit = 1u8.checked_shl(u32::from(channel)).unwrap_or(0);
            match self.logged_channels.get_mut(index) {
                Some(mask) => {
                    let first = *mask & bit == 0;
                    *mask |= bit;
                    first
                }
                None => false,
            }
        };
        if first_time {
            self.log.write(FaultRecord {
                tick: t.tick,
                code,
                channel,
                value,
            });
        }
    }

    fn check_operator_inputs(&mut self, input: &SupervisorInput, t: &mut Tick) {
        if input.e_stop_pressed {
            self.raise(t, FaultCode::EStopPressed, NO_CHANNEL, 1.0);
        }
        if input.e_stop_read_error {
            self.raise(t, FaultCode::EStopInputFault, NO_CHANNEL, 1.0);
        }
        if input.button_input_fault {
            self.raise(t, FaultCode::ButtonInputFault, NO_CHANNEL, 1.0);
        }
    }

    fn check_deadline(&mut self, input: &SupervisorInput, t: &mut Tick) {
        if input.deadline_missed {
            self.deadline_misses_total = self.deadline_misses_total.saturating_add(1);
            if let Some(slot) = self.misses.get_mut(self.miss_next) {
                *slot = Some(self.calls);
            }
            self.miss_next = (self.miss_next + 1) % self.misses.len();
        }
        let now = self.calls;
        let window = self.cfg.deadline_window_ticks;
        let recent = self
            .misses
            .iter()
            .flatten()
            .filter(|&&at| now.wrapping_sub(at) < window)
            .count();
        if recent >= usize::from(self.cfg.deadline_miss_count) {
            self.raise(t, FaultCode::DeadlineMissed, NO_CHANNEL, recent as f32);
        }
    }

    fn check_motors(&mut self, input: &SupervisorInput, t: &mut Tick) {
        let limit_ticks = self.cfg.saturation_ticks;
        for (i, m) in input.motors.iter().enumerate() {
            let ch = i as u8;
            let finite = m.commanded_nm.is_finite() && m.applied_nm.is_finite();
            // `!(limit > 0)` so NaN trips; infinity is caught by is_finite.
            let limit_ok = m.limit_nm.is_finite() && m.limit_nm > 0.0;
            if !(finite && limit_ok) {
                let bad = [m.commanded_nm, m.applied_nm, m.limit_nm]
                    .into_iter()
                    .find(|v| !v.is_finite())
                    .unwrap_or(m.limit_nm);
                self.raise(t, FaultCode::ControlValueInvalid, ch, bad);
            }
            let Some(track) = self.joints.get_mut(i) else {
                continue;
            };
            if m.commanded_nm.abs() < m.limit_nm {
                track.saturated_ticks = 0;
            } else {
                track.saturated_ticks = track.saturated_ticks.saturating_add(1);
            }
            let saturated = track.saturated_ticks >= limit_ticks;
            if saturated {
                self.raise(t, FaultCode::MotorSaturated, ch, m.commanded_nm);
            }
            if m.thermal_fault {
                self.raise(t, FaultCode::MotorThermal, ch, m.applied_nm);
            }
            if m.output_fault {
                self.raise(t, FaultCode::MotorOutputStage, ch, m.commanded_nm);
            }
        }
    }

    fn check_joints(&mut self, input: &SupervisorInput, t: &mut Tick) {
        let cfg = self.cfg;
        for i in 0..JOINTS {
            let ch = i as u8;
            let (Some(sense), Some(&reference), Some(range), Some(&vmax), Some(motor)) = (
                input.joints.get(i),
                input.joint_reference_rad.get(i),
                cfg.joint_range.get(i),
                cfg.velocity_limit_rad_s.get(i),
                input.motors.get(i),
            ) else {
                continue;
            };
            if !reference.is_finite() {
                self.raise(t, FaultCode::ControlValueInvalid, ch, reference);
            }
            let reference_speed = match self.previous_reference_rad.as_ref().and_then(|p| p.get(i))
            {
                Some(&previous) => (reference - previous).abs() / cfg.dt_s,
                None => 0.0,
            };
            // NaN speed or command counts as driven.
            let driven = !(reference_speed < cfg.frozen_reference_speed_rad_s
                && motor.commanded_nm.abs() < cfg.frozen_command_fraction * motor.limit_nm);

            let Some(track) = self.joints.get_mut(i) else {
                continue;
            };
            let (frame, invalid) =
                track
                    .encoder
                    .update(sense, cfg.encoder_debounce, cfg.max_jump_counts_per_tick);
            let mut raised: [Option<(FaultCode, f32)>; 6] = [None; 6];
            if let Some(v) = invalid {
                raised[0] = Some((FaultCode::EncoderInvalidValue, v));
            }
            if let Frame::Accepted {
                angle_rad,
                delta,
                previous_angle_rad,
            } = frame
            {
                if !range.contains(angle_rad) {
                    raised[1] = Some((FaultCode::JointPositionLimit, angle_rad));
                }
                match delta {
                    Some((counts, elapsed)) => {
                        let elapsed_s = cfg.dt_s * elapsed.max(1) as f32;
                        let raw_velocity = (angle_rad - previous_angle_rad) / elapsed_s;
                        // Starts from 0 after a (re-)seed, so one noisy
                        // difference cannot trip the limit alone.
                        if !track.velocity_rad_s.is_finite() {
                            track.velocity_rad_s = 0.0;
                        }
                        track.velocity_rad_s +=
                            cfg.velocity_filter_alpha * (raw_velocity - track.velocity_rad_s);
                        track.velocity_valid = true;
                        if counts == 0 && driven {
                            track.frozen_ticks = track.frozen_ticks.saturating_add(1);
                        } else {
                            track.frozen_ticks = 0;
                        }
                    }
                    None => {
                        // (Re-)seeded: no velocity from a single sample.
                        track.velocity_rad_s = 0.0;
                        track.velocity_valid = false;
                        track.frozen_ticks = 0;
                    }
                }
                let error = angle_rad - reference;
                if error.abs() <= cfg.tracking_error_limit_rad {
                    track.tracking_ticks = 0;
                } else {
                    track.tracking_ticks = track.tracking_ticks.saturating_add(1);
                }
                if track.tracking_ticks >= cfg.tracking_error_ticks {
                    raised[2] = Some((FaultCode::TrackingError, error));
                }
            }
            // Conditions that persist while frames are rejected.
            if track.velocity_valid && !within(track.velocity_rad_s, vmax) {
                raised[3] = Some((FaultCode::JointVelocityLimit, track.velocity_rad_s));
            }
            if track.frozen_ticks >= cfg.frozen_ticks {
                raised[4] = Some((FaultCode::EncoderFrozen, track.frozen_ticks as f32));
            }
            if let Some((code, n)) = track.encoder.tripped(cfg.encoder_debounce) {
                raised[5] = Some((code, n as f32));
            }
            for (code, value) in raised.into_iter().flatten() {
                self.raise(t, code, ch, value);
            }
        }
    }

    fn check_ankles(&mut self, input: &SupervisorInput, t: &mut Tick) {
        let cfg = self.cfg;
        for i in 0..ANKLES {
            let ch = i as u8;
            let (Some(sense), Some(range), Some(track)) = (
                input.ankles.get(i),
                cfg.ankle_range.get(i),
                self.ankles.get_mut(i),
            ) else {
                continue;
            };
            let (frame, invalid) =
                track.update(sense, cfg.encoder_debounce, cfg.max_jump_counts_per_tick);
            let tripped = track.tripped(cfg.encoder_debounce);
            if let Some(v) = invalid {
                self.raise(t, FaultCode::AnkleEncoder, ch, v);
            }
            if let Some((_, n)) = tripped {
                self.raise(t, FaultCode::AnkleEncoder, ch, n as f32);
            }
            if let Frame::Accepted { angle_rad, .. } = frame {
                if !range.contains(angle_rad) {
                    self.raise(t, FaultCode::AnklePositionLimit, ch, angle_rad);
                }
                // Resting on the stop while the plan is well below it (a
                // NaN plan never counts; a rejected frame neither counts
                // nor resets).
                let plan = input.ankle_plan_rad.get(i).copied().unwrap_or(f32::NAN);
                let on_stop = angle_rad >= cfg.heel_off_rad - cfg.heel_off_reading_tolerance_rad;
                let unplanned = plan < cfg.heel_off_rad - cfg.heel_off_plan_margin_rad;
                if let Some(n) = self.heel_off_ticks.get_mut(i) {
                    *n = if on_stop && unplanned {
                        n.saturating_add(1)
                    } else {
                        0
                    };
                    if *n >= cfg.heel_off_ticks {
                        self.raise(t, FaultCode::UnplannedHeelOff, ch, angle_rad);
                    }
                }
            }
        }
    }

    fn check_forces(&mut self, input: &SupervisorInput, t: &mut Tick) {
        let cfg = self.cfg;
        for i in 0..FORCES {
            let ch = i as u8;
            let (Some(sense), Some(track)) = (input.forces.get(i), self.forces.get_mut(i)) else {
                continue;
            };
            let mut immediate = false;
            let bad = match sense.status {
                ForceStatus::BusError => Some(FaultCode::ForceBusError),
                ForceStatus::Open => Some(FaultCode::ForceOpen),
                ForceStatus::Shorted => Some(FaultCode::ForceShorted),
                ForceStatus::OutOfRange => Some(FaultCode::ForceOutOfRange),
                ForceStatus::Ok => {
                    if !sense.newtons.is_finite() {
                        immediate = true;
                        Some(FaultCode::ForceOutOfRange)
                    } else if cfg.force_min_n <= sense.newtons && sense.newtons <= cfg.force_max_n {
                        None
                    } else {
                        Some(FaultCode::ForceOutOfRange)
                    }
                }
            };
            track.window.push(bad.is_some());
            if bad.is_some() {
                track.last_bad = bad;
            }
            let n = track.window.count(cfg.force_debounce.window_ticks);
            let tripped = if n >= u32::from(cfg.force_debounce.count) {
                track.last_bad
            } else {
                None
            };
            if immediate {
                self.raise(t, FaultCode::ForceOutOfRange, ch, sense.newtons);
            }
            if let Some(code) = tripped {
                let value = if bad.is_some() {
                    sense.newtons
                } else {
                    n as f32
                };
                self.raise(t, code, ch, value);
            }
        }
    }
}
