//! Fault-table rows of the hip and knee angles: position and velocity
//! limits, tracking error.

use crate::supervisor::support::*;

/// Joint `j`'s angle at injected tick `k` of a ramp from standing at
/// 1 rad/s.
fn ramp_joint(j: usize, k: u32) -> f32 {
    STAND_JOINTS[j] + 0.001 * k as f32
}

#[test]
fn row_joint_position_limit() {
    let max = SupervisorConfig::paper().joint_range[1].max_rad;
    let expected = (1..)
        .find(|&k| encoder(ramp_joint(1, k)).angle_rad > max)
        .unwrap();
    let (_, v) = inject(expected + 5, |k, input| {
        let angle = ramp_joint(1, k);
        input.joints[1] = encoder(angle);
        input.joint_reference_rad[1] = angle;
    });
    assert_row(
        &v,
        FaultCode::JointPositionLimit,
        Reaction::SafeHold,
        expected,
    );
}

#[test]
fn row_joint_position_limit_hyperextension() {
    // The knee may read 3° past its 0° stop, not more.
    let (_, v) = inject(1, |_, input| {
        input.joints[3] = encoder(-2.5 * DEG);
        input.joint_reference_rad[3] = -2.5 * DEG;
    });
    assert!(v[0].latched.is_empty());
    let (_, v) = inject(200, |k, input| {
        let angle = 0.1 - 0.001 * k as f32;
        input.joints[3] = encoder(angle);
        input.joint_reference_rad[3] = angle;
    });
    let at = detected_at(&v, FaultCode::JointPositionLimit).unwrap();
    assert!(encoder(0.1 - 0.001 * at as f32).angle_rad < -3.0 * DEG);
    assert!(encoder(0.1 - 0.001 * (at - 1) as f32).angle_rad >= -3.0 * DEG);
}

#[test]
fn row_joint_velocity_limit() {
    // 8 rad/s on a hip (1.33× its 6 rad/s limit, 21 counts per tick: no
    // jump). The filter (α = 0.2) passes 6 rad/s after
    // ceil(ln(1 − 6/8)/ln 0.8) = 7 samples; quantisation moves that by at
    // most one tick.
    let (_, v) = inject(20, |k, input| {
        let angle = STAND_JOINTS[0] + 0.008 * k as f32;
        input.joints[0] = encoder(angle);
        input.joint_reference_rad[0] = angle;
    });
    let at = detected_at(&v, FaultCode::JointVelocityLimit).unwrap();
    assert!((6..=8).contains(&at), "detected at {at}");
    assert_row(&v, FaultCode::JointVelocityLimit, Reaction::SafeHold, at);
}

#[test]
fn velocity_below_the_limit_is_fine() {
    let (_, v) = inject(300, |k, input| {
        let angle = STAND_JOINTS[0] + 0.004 * k as f32;
        input.joints[0] = encoder(angle);
        input.joint_reference_rad[0] = angle;
    });
    assert!(v.iter().all(|v| v.latched.is_empty()));
}

#[test]
fn row_tracking_error() {
    let (_, v) = inject(150, |_, input| input.joint_reference_rad[2] += 0.2);
    assert_row(&v, FaultCode::TrackingError, Reaction::SafeHold, 100);
}

#[test]
fn tracking_check_itself_trips_on_nan() {
    // A NaN reference is invalid at once, and is also a tracking error
    // once the bound has passed (the comparison does not let NaN through).
    let (_, v) = inject(120, |_, input| input.joint_reference_rad[1] = f32::NAN);
    assert_eq!(detected_at(&v, FaultCode::ControlValueInvalid), Some(1));
    assert_eq!(detected_at(&v, FaultCode::TrackingError), Some(100));
}

#[test]
fn tracking_error_needs_consecutive_ticks() {
    // 99 ticks over, one back, 99 over again: never 100 in a row.
    let (_, v) = inject(199, |k, input| {
        if k != 100 {
            input.joint_reference_rad[2] += 0.2;
        }
    });
    assert!(v.iter().all(|v| v.latched.is_empty()));
}
