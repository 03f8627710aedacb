//! `gait_core::fingerprint::Fingerprint` for the controller's configuration types (see
//! `gait_core::fingerprint`): what `exogait_device::DeviceConfig::fingerprint`
//! feeds to its CRC.

use gait_core::{impl_fingerprint, impl_fingerprint_enum};

use crate::controller::ControllerConfig;
use crate::drivers::as5048a::{Calibration, Direction};
use crate::drivers::buttons::{ActiveLevel, ButtonConfig};
use crate::drivers::mcp3208::{Channel, ForceChannels};
use crate::drivers::motor::MotorConfig;
use crate::position_loop::JointGains;
use crate::sequencer::SequencerConfig;
use crate::supervisor::{
    AngleRange, BalanceCheck, CrutchIdleCheck, Debounce, DriveCurrentCheck, ErrorBounds,
    ResponseCheck, SupervisorConfig,
};

impl_fingerprint_enum!(Direction, ActiveLevel, Channel);

impl_fingerprint!(Calibration {
    zero_offset_counts,
    direction
});
impl_fingerprint!(ButtonConfig {
    active,
    debounce_ticks,
    long_press_ticks
});
// `ForceCalibration`'s private fields: in `drivers::mcp3208`.
impl_fingerprint!(ForceChannels {
    left_foot,
    right_foot,
    left_crutch,
    right_crutch
});
impl_fingerprint!(MotorConfig {
    torque_limit_nm,
    full_scale_torque_nm,
    torque_constant_nm_per_a,
    gear_ratio,
    continuous_current_a,
    i2t_warning_a2s,
    i2t_fault_a2s,
    derated_limit_nm,
    slew_nm_per_tick,
    soft_start_ticks,
    dt_s,
});
impl_fingerprint!(JointGains {
    kp_nm_per_rad,
    ki_nm_per_rad_s,
    kd_nm_s_per_rad,
    integral_limit_nm,
    torque_limit_nm,
    slew_nm_per_tick,
});
impl_fingerprint!(SequencerConfig {
    crutch_ready_n,
    feet_ready_n,
    landing_contact_n,
    landing_confirm_s,
    landing_window_fraction,
    landing_timeout_s,
    blind_landing_settle_s,
    ground_search_after_s,
    ground_search_depth_m,
    ground_search_s,
    start_tolerance_rad,
    transfer_s,
    start_ankle_tolerance_rad,
    hold_ramp_s,
    set_down_depth_m,
    set_down_s,
    set_down_joint_speed_rad_s,
    lands_after,
    level_deadband_rad,
    level_max_rad,
    level_rate_rad_s,
});
impl_fingerprint!(ControllerConfig {
    dt_s,
    gains,
    sequencer,
    force_calibration,
    drive_current_calibration,
    e_stop_active_high,
    rate_filter_hz,
    still_rate_rad_s,
    model,
});
impl_fingerprint!(AngleRange { min_rad, max_rad });
impl_fingerprint!(Debounce {
    count,
    window_ticks
});
impl_fingerprint!(SupervisorConfig {
    dt_s,
    joint_range,
    ankle_range,
    velocity_limit_rad_s,
    velocity_filter_alpha,
    tracking_error_limit_rad,
    tracking_error_ticks,
    encoder_debounce,
    max_jump_counts_per_tick,
    max_ankle_jump_counts_per_tick,
    frozen_ticks,
    frozen_reference_speed_rad_s,
    frozen_command_fraction,
    frozen_still_reset_ticks,
    frozen_ankle_plan_rad,
    force_debounce,
    force_min_n,
    force_max_n,
    saturation_ticks,
    heel_off_rad,
    heel_off_reading_tolerance_rad,
    heel_off_plan_margin_rad,
    heel_off_ticks,
    deadline_miss_count,
    deadline_window_ticks,
    response,
    balance,
    crutch_idle,
    drive_current,
});
impl_fingerprint!(CrutchIdleCheck {
    rise_n,
    forget_n_per_s,
    ticks,
});
impl_fingerprint!(BalanceCheck {
    idle,
    pushed,
    crutch_rise_n,
    crutch_forget_n_per_s,
    rate_rad_s,
    rate_filter,
    ticks,
});
impl_fingerprint!(ErrorBounds {
    feet_down_rad,
    swing_rad,
});
impl_fingerprint!(DriveCurrentCheck {
    band_nm,
    band_share,
    samples,
    full_torque_speed_rad_s,
    back_emf_speed_share,
    debounce,
});
impl_fingerprint!(ResponseCheck {
    stance_inertia_kgm2,
    swing_inertia_kgm2,
    bandwidth_hz,
    limit_nm,
    stance_hip_min_nm,
    ticks,
    leaning_ankle_rad,
    leaning_factor,
});
