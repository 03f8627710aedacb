//! The supervisor's limits and detection bounds: the envelope of each
//! joint and ankle, the debounce windows, and how they are derived from the
//! body model's joint limits; checked once when the supervisor is built.

use super::*;

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

pub(super) const DEG: f32 = core::f32::consts::PI / 180.0;

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
    /// Largest plausible change of a hip or knee encoder's raw counts per
    /// tick ([`SupervisorConfig::physical_jump_counts`]).
    pub max_jump_counts_per_tick: u16,
    /// The same for the passive ankles, which slap onto the ground at a
    /// landing far faster than a driven joint moves.
    pub max_ankle_jump_counts_per_tick: u16,
    /// Driven ticks of unchanged raw counts that make a frozen-encoder
    /// fault; ticks not driven between them do not count, and restart the
    /// count only as a still stretch of
    /// [`SupervisorConfig::frozen_still_reset_ticks`]; changed counts do.
    pub frozen_ticks: u32,
    /// The joint counts as driven when its reference moves at least this
    /// fast, rad/s …
    pub frozen_reference_speed_rad_s: f32,
    /// … or when |command| ≥ this fraction of the motor's limit. Near the
    /// limit (0.9 by default), not below: a still stance knee holding the
    /// body, or a joint held against its stop, legitimately reads constant
    /// counts under a large command.
    pub frozen_command_fraction: f32,
    /// A still stretch this long (not driven, counts unchanged) restarts
    /// the frozen count: longer than a weight transfer (0.4 s), whose still
    /// reference a joint frozen as its swing ends sits through, so that
    /// driven ticks scattered over a long rest (a command that now and
    /// then reaches the limit's 0.9 on a still joint) never add up.
    pub frozen_still_reset_ticks: u32,
    /// How far the plan turns a stance ankle, rad, with its counts not
    /// changing once, before the encoder counts as frozen (0x0207): a
    /// stance shank turns over its foot through every swing, and even one
    /// count is 0.022°; a reading held since the swing began would set the
    /// posture the step plays on with at its end.
    pub frozen_ankle_plan_rad: f32,
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
    /// The drives' torque residual (0x0404).
    pub response: ResponseCheck,
    /// The balance check (0x0701, 0x0702).
    pub balance: BalanceCheck,
    /// The idle-crutches check (0x0703).
    pub crutch_idle: CrutchIdleCheck,
    /// The drives' currents against their commands (0x0405, 0x0406).
    pub drive_current: DriveCurrentCheck,
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
            max_ankle_jump_counts_per_tick: 100,
            frozen_ticks: 100,
            // A joint following a reference this fast moves 13 counts in
            // 100 ticks; slower, a stance knee frozen late in an ascent's
            // swing, its reference creeping, would go unseen.
            frozen_reference_speed_rad_s: 0.05,
            frozen_command_fraction: 0.9,
            frozen_still_reset_ticks: 500,
            // 2.9°, some 130 counts: a healthy walk's stance shank turns
            // 0.3–0.5 rad in a swing.
            frozen_ankle_plan_rad: 0.05,
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
            response: ResponseCheck::DEFAULT,
            balance: BalanceCheck::DEFAULT,
            crutch_idle: CrutchIdleCheck::DEFAULT,
            drive_current: DriveCurrentCheck::DEFAULT,
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
            self.frozen_ankle_plan_rad,
            self.heel_off_rad,
            self.heel_off_reading_tolerance_rad,
            self.heel_off_plan_margin_rad,
        ];
        let velocities_ok = self
            .velocity_limit_rad_s
            .iter()
            .all(|v| v.is_finite() && *v > 0.0);
        if !(positive.iter().all(|v| v.is_finite() && *v > 0.0)
            && velocities_ok
            && self.response.is_valid()
            && self.balance.is_valid()
            && self.crutch_idle.is_valid()
            && self.drive_current.is_valid())
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
        if !(debounce_ok(&self.encoder_debounce)
            && debounce_ok(&self.force_debounce)
            && debounce_ok(&self.drive_current.debounce))
            || self.deadline_miss_count == 0
            || self.deadline_miss_count > MAX_DEADLINE_MISSES
            || self.deadline_window_ticks == 0
            || self.tracking_error_ticks == 0
            || self.frozen_ticks == 0
            || self.frozen_still_reset_ticks == 0
            || self.saturation_ticks == 0
            || self.heel_off_ticks == 0
            || self.max_jump_counts_per_tick == 0
            || self.max_ankle_jump_counts_per_tick == 0
        {
            return Err(ConfigError::BadWindow);
        }
        Ok(())
    }

    /// The largest change of an encoder's reading per tick that a joint
    /// can physically make, counts (rounded up): the fastest joint velocity
    /// limit (beyond it 0x0102 trips anyway) over one tick. Any larger
    /// change is a jump, however many frames were dropped before it: the
    /// allowance grows by this per tick elapsed, so a step the joint could
    /// not have made trips within the bad-frame debounce.
    pub fn physical_jump_counts(&self) -> u16 {
        let fastest = self
            .velocity_limit_rad_s
            .iter()
            .fold(0.0f32, |m, &v| if v > m { v } else { m });
        let rad_per_count =
            2.0 * core::f32::consts::PI / f32::from(crate::drivers::as5048a::COUNTS_PER_REV);
        let counts = libm::ceilf(fastest * self.dt_s / rad_per_count);
        if counts.is_finite() && counts >= 1.0 && counts <= f32::from(u16::MAX) {
            counts as u16
        } else {
            self.max_jump_counts_per_tick
        }
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
