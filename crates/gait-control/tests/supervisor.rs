//! Safety supervisor: one test per row of the fault table in
//! `docs/safety.md` (code, reaction, detection bound, not before), healthy
//! runs, latching and reset, severity, NaN handling and the log.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::cast_possible_truncation,
    missing_docs
)]

use gait_control::drivers::as5048a::{COUNTS_PER_REV, Calibration, Direction};
use gait_control::faults::{FaultCode, FaultSet, Reaction};
use gait_control::supervisor::{
    ANKLES, ConfigError, EncoderSense, EncoderStatus, FORCES, ForceSense, ForceStatus, JOINTS,
    LOG_LEN, MotorSense, NO_CHANNEL, ResetRefused, Supervisor, SupervisorConfig, SupervisorInput,
    Verdict,
};
use proptest::prelude::*;

// ---------------------------------------------------------------- fixtures

const RAD_PER_COUNT: f32 = 2.0 * core::f32::consts::PI / COUNTS_PER_REV as f32;
const DEG: f32 = core::f32::consts::PI / 180.0;
/// Healthy ticks before a fault is injected.
const WARMUP: u32 = 300;

/// Standing posture: hips, knees, ankles (rad).
const STAND_JOINTS: [f32; JOINTS] = [0.10, 0.10, 0.10, 0.10];
const STAND_ANKLES: [f32; ANKLES] = [0.05, 0.05];
const LIMIT_NM: f32 = 60.0;

/// An encoder frame as the AS5048A driver would give it for `angle_rad`
/// (zero offset 0, positive direction): raw counts and the calibrated,
/// quantised angle agree.
fn encoder(angle_rad: f32) -> EncoderSense {
    let counts = (angle_rad / RAD_PER_COUNT).round() as i32;
    let raw = counts.rem_euclid(i32::from(COUNTS_PER_REV)) as u16;
    let cal = Calibration {
        zero_offset_counts: 0,
        direction: Direction::Positive,
    };
    EncoderSense {
        status: EncoderStatus::Ok,
        raw_counts: raw,
        angle_rad: cal.counts_to_rad(raw),
    }
}

/// ±1 count of sensor noise, as a real AS5048A shows.
fn dither(tick: u32, channel: usize) -> f32 {
    const PATTERN: [f32; 4] = [0.0, 1.0, 0.0, -1.0];
    PATTERN[(tick as usize + channel) % 4] * RAD_PER_COUNT
}

/// Standing still, everything healthy, with encoder noise. The reference is
/// the standing posture; the motors hold with a small torque.
fn healthy_input(tick: u32) -> SupervisorInput {
    let mut joints = [EncoderSense::default(); JOINTS];
    for (j, e) in joints.iter_mut().enumerate() {
        *e = encoder(STAND_JOINTS[j] + dither(tick, j));
    }
    let mut ankles = [EncoderSense::default(); ANKLES];
    for (a, e) in ankles.iter_mut().enumerate() {
        *e = encoder(STAND_ANKLES[a] + dither(tick, a + JOINTS));
    }
    let newtons = [300.0, 300.0, 80.0, 80.0];
    SupervisorInput {
        tick,
        joints,
        joint_reference_rad: STAND_JOINTS,
        ankles,
        forces: newtons.map(|n| ForceSense {
            status: ForceStatus::Ok,
            newtons: n,
        }),
        motors: [MotorSense {
            commanded_nm: 5.0,
            applied_nm: 5.0,
            limit_nm: LIMIT_NM,
            thermal_fault: false,
            output_fault: false,
        }; JOINTS],
        e_stop_pressed: false,
        e_stop_read_error: false,
        deadline_missed: false,
        step_in_progress: false,
        button_input_fault: false,
        ankle_plan_rad: [f32::NAN; ANKLES],
    }
}

/// Walking-like motion: every joint follows a slow sine, the reference
/// with it, moderate torques.
fn moving_input(tick: u32) -> SupervisorInput {
    let mut input = healthy_input(tick);
    let t = tick as f32 * 0.001;
    for j in 0..JOINTS {
        let phase = j as f32 * 1.3;
        let angle = 0.4 + 0.3 * libm::sinf(2.0 * core::f32::consts::PI * 0.5 * t + phase);
        input.joints[j] = encoder(angle + dither(tick, j));
        input.joint_reference_rad[j] = angle;
        input.motors[j].commanded_nm = 20.0 * libm::cosf(t + phase);
        input.motors[j].applied_nm = input.motors[j].commanded_nm;
    }
    for a in 0..ANKLES {
        input.ankles[a] = encoder(0.1 + 0.08 * libm::sinf(3.0 * t + a as f32));
    }
    input.step_in_progress = true;
    input
}

fn supervisor() -> Supervisor {
    Supervisor::new(SupervisorConfig::paper()).unwrap()
}

/// Runs `WARMUP` healthy ticks (asserting nothing faults), then `n` ticks
/// of `healthy_input` changed by `inject(k, &mut input)`, k = 1..=n.
/// Returns the supervisor and the verdicts of the injected ticks
/// (`verdicts[k - 1]` is tick k).
fn inject(n: u32, mut inject: impl FnMut(u32, &mut SupervisorInput)) -> (Supervisor, Vec<Verdict>) {
    let mut sup = supervisor();
    for tick in 0..WARMUP {
        let v = sup.check(&healthy_input(tick));
        assert_eq!(v.reaction, Reaction::None, "warm-up tick {tick}: {v:?}");
    }
    let mut verdicts = Vec::new();
    for k in 1..=n {
        let mut input = healthy_input(WARMUP + k - 1);
        inject(k, &mut input);
        verdicts.push(sup.check(&input));
    }
    (sup, verdicts)
}

/// First injected tick (1-based) at which `code` is latched.
fn detected_at(verdicts: &[Verdict], code: FaultCode) -> Option<u32> {
    verdicts
        .iter()
        .position(|v| v.latched.contains(code))
        .map(|i| i as u32 + 1)
}

fn only(code: FaultCode) -> FaultSet {
    core::iter::once(code).collect()
}

/// The row's checks: detected exactly at tick `bound` (so within it and
/// not before), alone, newly, with the row's reaction.
fn assert_row(verdicts: &[Verdict], code: FaultCode, reaction: Reaction, bound: u32) {
    assert_eq!(code.reaction(), reaction, "{}", code.name());
    assert_eq!(detected_at(verdicts, code), Some(bound), "{}", code.name());
    let v = verdicts[bound as usize - 1];
    assert_eq!(v.latched, only(code), "{}: {v:?}", code.name());
    assert_eq!(v.new, only(code));
    assert_eq!(v.reaction, reaction);
    for (k, earlier) in verdicts.iter().take(bound as usize - 1).enumerate() {
        assert_eq!(earlier.reaction, Reaction::None, "tick {}", k + 1);
    }
}

// ------------------------------------------------------ healthy operation

#[test]
fn healthy_standing_never_faults() {
    let mut sup = supervisor();
    for tick in 0..30_000 {
        let v = sup.check(&healthy_input(tick));
        assert_eq!(v.reaction, Reaction::None, "tick {tick}: {v:?}");
    }
    assert!(sup.log().next().is_none());
}

#[test]
fn healthy_motion_never_faults() {
    let mut sup = supervisor();
    for tick in 0..30_000 {
        let v = sup.check(&moving_input(tick));
        assert_eq!(v.reaction, Reaction::None, "tick {tick}: {v:?}");
    }
    assert!(sup.latched().is_empty());
}

#[test]
fn envelope_is_table_i_with_margins() {
    let cfg = SupervisorConfig::paper();
    let close = |a: f32, b_deg: f32| (a - b_deg * DEG).abs() < 1e-5;
    let hip = cfg.joint_range[0];
    let knee = cfg.joint_range[1];
    let ankle = cfg.ankle_range[0];
    assert!(
        close(hip.min_rad, -75.0) && close(hip.max_rad, 95.0),
        "{hip:?}"
    );
    assert!(
        close(knee.min_rad, -3.0) && close(knee.max_rad, 95.0),
        "{knee:?}"
    );
    assert!(
        close(ankle.min_rad, -3.0) && close(ankle.max_rad, 22.0),
        "{ankle:?}"
    );
    assert_eq!(cfg.joint_range[2], hip);
    assert_eq!(cfg.joint_range[3], knee);
}

#[test]
fn bad_configurations_are_refused() {
    let good = SupervisorConfig::paper();
    assert!(Supervisor::new(good).is_ok());
    let mut c = good;
    c.velocity_filter_alpha = 0.0;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::NotPositive));
    let mut c = good;
    c.velocity_limit_rad_s[2] = f32::NAN;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::NotPositive));
    let mut c = good;
    c.joint_range[1].min_rad = c.joint_range[1].max_rad;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::BadRange));
    let mut c = good;
    c.force_max_n = f32::INFINITY;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::BadRange));
    let mut c = good;
    c.encoder_debounce.window_ticks = 129;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::BadWindow));
    let mut c = good;
    c.force_debounce.count = 0;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::BadWindow));
    let mut c = good;
    c.deadline_miss_count = 9;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::BadWindow));
}

// ------------------------------------------------- the fault table, rows

/// Ramps joint `j` (and its reference) from standing at 1 rad/s and
/// returns the first injected tick whose reported angle is above `max`.
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
fn row_ankle_position_limit() {
    let max = SupervisorConfig::paper().ankle_range[0].max_rad;
    let ramp = |k: u32| STAND_ANKLES[0] + 0.001 * k as f32;
    let expected = (1..).find(|&k| encoder(ramp(k)).angle_rad > max).unwrap();
    let (_, v) = inject(expected + 5, |k, input| input.ankles[0] = encoder(ramp(k)));
    assert_row(
        &v,
        FaultCode::AnklePositionLimit,
        Reaction::FinishStepThenHold,
        expected,
    );
}

#[test]
fn row_unplanned_heel_off() {
    // The left ankle on its 20° stop (the heel lifting onto the toe) while
    // the plan keeps it at 6° (a walk): 50 ticks on the stop trip it.
    // The ankle rolls onto the stop at 0.02 rad per tick (no jump), then
    // stays: the 50th tick on the stop trips.
    let cfg = SupervisorConfig::paper();
    let stop = cfg.heel_off_rad;
    let ramp = |k: u32| (STAND_ANKLES[0] + 0.02 * k as f32).min(stop);
    let on_stop = |k: u32| encoder(ramp(k)).angle_rad >= stop - cfg.heel_off_reading_tolerance_rad;
    let first = (1..).find(|&k| on_stop(k)).unwrap();
    let (_, v) = inject(first + 60, |k, input| {
        input.ankles[0] = encoder(ramp(k));
        input.ankle_plan_rad[0] = 0.1;
    });
    assert_row(
        &v,
        FaultCode::UnplannedHeelOff,
        Reaction::FinishStepThenHold,
        first + cfg.heel_off_ticks - 1,
    );
    // Planned (a descent's stance heel lifts on schedule), nothing planned
    // (NaN: standing, the swing ankle), or off the stop: nothing.
    for (reading, plan) in [
        (stop, stop + 0.2),
        (stop, stop - 3.0 * DEG),
        (stop, f32::NAN),
        (stop - 1.0 * DEG, 0.1),
    ] {
        let (_, v) = inject(200, |k, input| {
            input.ankles[0] = encoder((STAND_ANKLES[0] + 0.02 * k as f32).min(reading));
            input.ankle_plan_rad[0] = plan;
        });
        assert!(
            v.iter().all(|x| x.reaction == Reaction::None),
            "reading {reading}, plan {plan}"
        );
    }
    // Leaving the stop restarts the count: 49 on, 1 off, 49 on: nothing.
    let (_, v) = inject(first + 98, |k, input| {
        let dip = k == first + 49;
        input.ankles[0] = encoder(if dip { stop - 2.0 * DEG } else { ramp(k) });
        input.ankle_plan_rad[0] = 0.1;
    });
    assert!(v.iter().all(|x| x.reaction == Reaction::None));
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

fn bad_frames(status: EncoderStatus, code: FaultCode) {
    let (_, v) = inject(10, |_, input| input.joints[1].status = status);
    assert_row(&v, code, Reaction::SafeHold, 3);
}

#[test]
fn row_encoder_bus_error() {
    bad_frames(EncoderStatus::BusError, FaultCode::EncoderBusError);
}

#[test]
fn row_encoder_parity() {
    bad_frames(EncoderStatus::Parity, FaultCode::EncoderParity);
}

#[test]
fn row_encoder_error_flag() {
    bad_frames(EncoderStatus::ErrorFlag, FaultCode::EncoderErrorFlag);
}

#[test]
fn encoder_bad_frames_counted_in_a_100_tick_window() {
    // Three within 100 ticks: the third trips.
    let (_, v) = inject(120, |k, input| {
        if [1, 50, 100].contains(&k) {
            input.joints[0].status = EncoderStatus::Parity;
        }
    });
    assert_row(&v, FaultCode::EncoderParity, Reaction::SafeHold, 100);
    // Three spread over 101 ticks: never.
    let (_, v) = inject(300, |k, input| {
        if [1, 50, 101, 160, 250].contains(&k) {
            input.joints[0].status = EncoderStatus::BusError;
        }
    });
    assert!(v.iter().all(|v| v.latched.is_empty()));
}

#[test]
fn row_encoder_frozen() {
    // The reference moves at 0.5 rad/s; the encoder repeats the last
    // warm-up frame, so every injected tick is an unchanged one.
    let frozen = healthy_input(WARMUP - 1).joints[0];
    let (_, v) = inject(150, |k, input| {
        input.joints[0] = frozen;
        input.joint_reference_rad[0] = STAND_JOINTS[0] + 0.0005 * k as f32;
    });
    assert_row(&v, FaultCode::EncoderFrozen, Reaction::SafeHold, 100);
}

#[test]
fn frozen_under_a_large_command_too() {
    let frozen = healthy_input(WARMUP - 1).joints[0];
    let (_, v) = inject(150, |_, input| {
        input.joints[0] = frozen;
        input.motors[0].commanded_nm = 0.95 * LIMIT_NM;
    });
    assert_row(&v, FaultCode::EncoderFrozen, Reaction::SafeHold, 100);
    // Holding a still joint with a large but not near-saturated command (a
    // heavy stance knee) is not "driven": constant counts are fine.
    let (_, v) = inject(500, |_, input| {
        input.joints[0] = frozen;
        input.motors[0].commanded_nm = 0.7 * LIMIT_NM;
    });
    assert!(v.iter().all(|v| v.latched.is_empty()));
    // Not driven (still reference, small command): constant counts are fine.
    let (_, v) = inject(500, |_, input| input.joints[0] = frozen);
    assert!(v.iter().all(|v| v.latched.is_empty()));
}

#[test]
fn row_encoder_jump() {
    let jumped = encoder(STAND_JOINTS[1] + 2000.0 * RAD_PER_COUNT);
    let (_, v) = inject(10, |_, input| input.joints[1] = jumped);
    assert_row(&v, FaultCode::EncoderJump, Reaction::SafeHold, 3);
}

#[test]
fn a_single_jump_frame_is_dropped() {
    let jumped = encoder(STAND_JOINTS[1] + 2000.0 * RAD_PER_COUNT);
    let (_, v) = inject(300, |k, input| {
        if k == 1 {
            input.joints[1] = jumped;
        }
    });
    assert!(v.iter().all(|v| v.latched.is_empty()));
}

#[test]
fn jump_threshold_is_wrap_aware() {
    // A joint reading near the ±π seam of the counts moves by 10 counts
    // per tick across it: no jump.
    let mut sup = supervisor();
    for tick in 0..200u32 {
        let mut input = healthy_input(tick);
        let raw = (COUNTS_PER_REV - 100 + 10 * tick as u16 % COUNTS_PER_REV) % COUNTS_PER_REV;
        input.joints[0].raw_counts = raw;
        let v = sup.check(&input);
        assert!(!v.latched.contains(FaultCode::EncoderJump), "tick {tick}");
    }
}

#[test]
fn row_encoder_invalid_value() {
    let (_, v) = inject(3, |_, input| input.joints[2].angle_rad = f32::NAN);
    assert_row(&v, FaultCode::EncoderInvalidValue, Reaction::SafeHold, 1);
    let (_, v) = inject(3, |_, input| input.joints[2].raw_counts = 0x4000);
    assert_row(&v, FaultCode::EncoderInvalidValue, Reaction::SafeHold, 1);
    let (_, v) = inject(3, |_, input| input.joints[2].angle_rad = 4.0);
    assert_row(&v, FaultCode::EncoderInvalidValue, Reaction::SafeHold, 1);
}

#[test]
fn row_ankle_encoder() {
    let (_, v) = inject(10, |_, input| {
        input.ankles[1].status = EncoderStatus::Parity
    });
    assert_row(&v, FaultCode::AnkleEncoder, Reaction::FinishStepThenHold, 3);
    let (_, v) = inject(10, |_, input| input.ankles[1].angle_rad = f32::INFINITY);
    assert_row(&v, FaultCode::AnkleEncoder, Reaction::FinishStepThenHold, 1);
}

fn bad_force(status: ForceStatus, code: FaultCode) {
    let (_, v) = inject(10, |_, input| input.forces[2].status = status);
    assert_row(&v, code, Reaction::FinishStepThenHold, 3);
}

#[test]
fn row_force_bus_error() {
    bad_force(ForceStatus::BusError, FaultCode::ForceBusError);
}

#[test]
fn row_force_open() {
    bad_force(ForceStatus::Open, FaultCode::ForceOpen);
}

#[test]
fn row_force_shorted() {
    bad_force(ForceStatus::Shorted, FaultCode::ForceShorted);
}

#[test]
fn row_force_out_of_range() {
    bad_force(ForceStatus::OutOfRange, FaultCode::ForceOutOfRange);
    // Reported Ok but outside the configured rated range.
    let (_, v) = inject(10, |_, input| input.forces[0].newtons = 5000.0);
    assert_row(
        &v,
        FaultCode::ForceOutOfRange,
        Reaction::FinishStepThenHold,
        3,
    );
    // Not finite: at once.
    let (_, v) = inject(10, |_, input| input.forces[0].newtons = f32::NAN);
    assert_row(
        &v,
        FaultCode::ForceOutOfRange,
        Reaction::FinishStepThenHold,
        1,
    );
}

#[test]
fn row_motor_saturated() {
    let (_, v) = inject(250, |_, input| {
        input.motors[3].commanded_nm = -LIMIT_NM;
        input.motors[3].applied_nm = -LIMIT_NM;
    });
    assert_row(&v, FaultCode::MotorSaturated, Reaction::SafeHold, 200);
}

#[test]
fn row_motor_thermal() {
    let (_, v) = inject(3, |_, input| {
        input.motors[0].thermal_fault = true;
        input.motors[0].applied_nm = 0.0;
    });
    assert_row(&v, FaultCode::MotorThermal, Reaction::SafeHold, 1);
}

#[test]
fn row_motor_output_stage() {
    let (_, v) = inject(3, |_, input| input.motors[2].output_fault = true);
    assert_row(&v, FaultCode::MotorOutputStage, Reaction::DisableMotors, 1);
}

#[test]
fn row_e_stop_pressed() {
    let (_, v) = inject(3, |_, input| input.e_stop_pressed = true);
    assert_row(&v, FaultCode::EStopPressed, Reaction::DisableMotors, 1);
}

#[test]
fn row_e_stop_input_fault() {
    let (_, v) = inject(3, |_, input| input.e_stop_read_error = true);
    assert_row(&v, FaultCode::EStopInputFault, Reaction::DisableMotors, 1);
}

#[test]
fn row_button_input_fault() {
    let (_, v) = inject(3, |_, input| input.button_input_fault = true);
    assert_row(
        &v,
        FaultCode::ButtonInputFault,
        Reaction::FinishStepThenHold,
        1,
    );
}

#[test]
fn row_deadline_missed() {
    // Third miss within 1000 ticks trips.
    let (sup, v) = inject(600, |k, input| {
        input.deadline_missed = [1, 2, 500].contains(&k);
    });
    assert_row(&v, FaultCode::DeadlineMissed, Reaction::SafeHold, 500);
    assert_eq!(sup.deadline_misses(), 3);
}

#[test]
fn sparse_deadline_misses_only_count() {
    let (sup, v) = inject(3000, |k, input| input.deadline_missed = k % 600 == 1);
    assert!(v.iter().all(|v| v.latched.is_empty()));
    assert_eq!(sup.deadline_misses(), 5);
}

#[test]
fn row_control_value_invalid() {
    let (_, v) = inject(3, |_, input| input.motors[1].commanded_nm = f32::NAN);
    assert_row(&v, FaultCode::ControlValueInvalid, Reaction::SafeHold, 1);
    let (_, v) = inject(3, |_, input| input.joint_reference_rad[0] = f32::NAN);
    assert_eq!(detected_at(&v, FaultCode::ControlValueInvalid), Some(1));
    let (_, v) = inject(3, |_, input| input.motors[2].limit_nm = 0.0);
    assert_eq!(detected_at(&v, FaultCode::ControlValueInvalid), Some(1));
}

#[test]
fn codes_are_stable_unique_and_grouped() {
    // Codes unique, grouped, round-trip; ALL agrees with index().
    for (i, c) in FaultCode::ALL.iter().enumerate() {
        assert_eq!(usize::from(c.index()), i);
        assert_eq!(FaultCode::from_code(c.code()), Some(*c));
        assert!(matches!(c.code() >> 8, 0x01..=0x06), "{c:?}");
        assert!(!c.name().is_empty());
    }
    assert_eq!(FaultCode::EStopPressed.code(), 0x0501);
    assert_eq!(FaultCode::JointPositionLimit.code(), 0x0101);
    assert_eq!(FaultCode::from_code(0x0000), None);
}

// -------------------------------------------------- latching and reset

#[test]
fn faults_latch_until_reset_in_a_safe_posture() {
    let mut sup = supervisor();
    let mut input = healthy_input(0);
    input.e_stop_pressed = true;
    let v = sup.check(&input);
    assert_eq!(v.reaction, Reaction::DisableMotors);
    // Still pressed: refused, even in a safe posture.
    assert_eq!(
        sup.request_reset(true),
        Err(ResetRefused::ConditionPresent(only(
            FaultCode::EStopPressed
        )))
    );
    // Released: still latched.
    let v = sup.check(&healthy_input(1));
    assert_eq!(v.reaction, Reaction::DisableMotors);
    assert!(v.new.is_empty());
    // Not in a safe posture: refused.
    assert_eq!(sup.request_reset(false), Err(ResetRefused::NotSafePosture));
    assert_eq!(
        sup.check(&healthy_input(2)).reaction,
        Reaction::DisableMotors
    );
    // Safe and gone: accepted, and the next verdict is clear.
    assert_eq!(sup.request_reset(true), Ok(()));
    assert!(sup.latched().is_empty());
    let v = sup.check(&healthy_input(3));
    assert_eq!(v.reaction, Reaction::None);
    assert!(v.latched.is_empty());
}

#[test]
fn debounced_fault_resets_only_after_its_window_clears() {
    let (mut sup, _) = inject(3, |_, input| {
        input.joints[1].status = EncoderStatus::BusError
    });
    assert!(sup.latched().contains(FaultCode::EncoderBusError));
    let start = WARMUP + 3;
    // Three bad frames stay in the 100-tick window for 97 more ticks.
    for k in 0..96 {
        sup.check(&healthy_input(start + k));
        assert!(matches!(
            sup.request_reset(true),
            Err(ResetRefused::ConditionPresent(_))
        ));
    }
    sup.check(&healthy_input(start + 96));
    sup.check(&healthy_input(start + 97));
    assert_eq!(sup.request_reset(true), Ok(()));
    assert_eq!(
        sup.check(&healthy_input(start + 98)).reaction,
        Reaction::None
    );
}

#[test]
fn a_fault_that_returns_latches_again() {
    let mut sup = supervisor();
    let mut input = healthy_input(0);
    input.button_input_fault = true;
    sup.check(&input);
    sup.check(&healthy_input(1));
    assert_eq!(sup.request_reset(true), Ok(()));
    let v = sup.check(&input);
    assert_eq!(v.new, only(FaultCode::ButtonInputFault));
    assert_eq!(v.reaction, Reaction::FinishStepThenHold);
}

#[test]
fn reset_with_nothing_latched_is_accepted() {
    let mut sup = supervisor();
    sup.check(&healthy_input(0));
    assert_eq!(sup.request_reset(true), Ok(()));
}

// ------------------------------------------------------------- severity

#[test]
fn the_most_severe_reaction_wins() {
    assert!(Reaction::None < Reaction::FinishStepThenHold);
    assert!(Reaction::FinishStepThenHold < Reaction::SafeHold);
    assert!(Reaction::SafeHold < Reaction::DisableMotors);

    let (_, v) = inject(2, |k, input| {
        input.button_input_fault = true;
        if k == 2 {
            input.motors[0].thermal_fault = true;
        }
    });
    assert_eq!(v[0].reaction, Reaction::FinishStepThenHold);
    assert_eq!(v[1].reaction, Reaction::SafeHold);
    assert_eq!(v[1].new, only(FaultCode::MotorThermal));

    // A warning after a fatal fault does not lower the reaction.
    let (_, v) = inject(2, |k, input| {
        input.e_stop_pressed = k == 1;
        input.button_input_fault = k == 2;
    });
    assert_eq!(v[0].reaction, Reaction::DisableMotors);
    assert_eq!(v[1].reaction, Reaction::DisableMotors);
    assert_eq!(v[1].latched.len(), 2);
}

// ------------------------------------------------------------------ NaN

/// Every float field of the input, by name, with a setter.
type Setter = fn(&mut SupervisorInput, f32);
const FLOAT_FIELDS: &[(&str, Setter)] = &[
    ("joints[0].angle_rad", |i, x| i.joints[0].angle_rad = x),
    ("joints[3].angle_rad", |i, x| i.joints[3].angle_rad = x),
    ("joint_reference_rad[1]", |i, x| {
        i.joint_reference_rad[1] = x
    }),
    ("ankles[0].angle_rad", |i, x| i.ankles[0].angle_rad = x),
    ("ankles[1].angle_rad", |i, x| i.ankles[1].angle_rad = x),
    ("forces[0].newtons", |i, x| i.forces[0].newtons = x),
    ("forces[3].newtons", |i, x| i.forces[3].newtons = x),
    ("motors[0].commanded_nm", |i, x| {
        i.motors[0].commanded_nm = x
    }),
    ("motors[1].applied_nm", |i, x| i.motors[1].applied_nm = x),
    ("motors[2].limit_nm", |i, x| i.motors[2].limit_nm = x),
];

#[test]
fn nan_or_infinity_in_any_float_field_trips_at_once() {
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        for (name, set) in FLOAT_FIELDS {
            let (sup, v) = inject(1, |_, input| set(input, bad));
            assert_ne!(v[0].reaction, Reaction::None, "{name} = {bad}");
            let record = sup.log().last().unwrap();
            assert!(
                !record.value.is_finite() || record.value <= 0.0,
                "{name}: {record:?}"
            );
        }
    }
}

fn float() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => -4.0f32..4.0,
        1 => any::<f32>(),
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
    ]
}

fn encoder_sense() -> impl Strategy<Value = EncoderSense> {
    (
        prop_oneof![
            4 => Just(EncoderStatus::Ok),
            1 => Just(EncoderStatus::BusError),
            1 => Just(EncoderStatus::Parity),
            1 => Just(EncoderStatus::ErrorFlag),
        ],
        any::<u16>(),
        float(),
    )
        .prop_map(|(status, raw_counts, angle_rad)| EncoderSense {
            status,
            raw_counts,
            angle_rad,
        })
}

fn random_input() -> impl Strategy<Value = SupervisorInput> {
    let force = (
        prop_oneof![
            4 => Just(ForceStatus::Ok),
            1 => Just(ForceStatus::BusError),
            1 => Just(ForceStatus::Open),
            1 => Just(ForceStatus::Shorted),
            1 => Just(ForceStatus::OutOfRange),
        ],
        float(),
    )
        .prop_map(|(status, newtons)| ForceSense { status, newtons });
    let motor = (float(), float(), float(), any::<bool>(), any::<bool>()).prop_map(
        |(commanded_nm, applied_nm, limit_nm, thermal_fault, output_fault)| MotorSense {
            commanded_nm,
            applied_nm,
            limit_nm,
            thermal_fault,
            output_fault,
        },
    );
    (
        any::<u32>(),
        proptest::array::uniform4(encoder_sense()),
        proptest::array::uniform4(float()),
        proptest::array::uniform2(encoder_sense()),
        proptest::array::uniform4(force),
        proptest::array::uniform4(motor),
        proptest::array::uniform5(any::<bool>()),
    )
        .prop_map(
            |(tick, joints, joint_reference_rad, ankles, forces, motors, flags)| SupervisorInput {
                tick,
                joints,
                joint_reference_rad,
                ankles,
                forces,
                motors,
                e_stop_pressed: flags[0],
                e_stop_read_error: flags[1],
                deadline_missed: flags[2],
                step_in_progress: flags[3],
                button_input_fault: flags[4],
                ankle_plan_rad: [f32::NAN; ANKLES],
            },
        )
}

/// Whether a value that a check reads is NaN (encoder angles and forces
/// count only when their status is Ok: otherwise they are ignored).
fn has_nan(input: &SupervisorInput) -> bool {
    let enc = |e: &EncoderSense| e.status == EncoderStatus::Ok && e.angle_rad.is_nan();
    input.joints.iter().any(enc)
        || input.ankles.iter().any(enc)
        || input.joint_reference_rad.iter().any(|r| r.is_nan())
        || input
            .forces
            .iter()
            .any(|f| f.status == ForceStatus::Ok && f.newtons.is_nan())
        || input
            .motors
            .iter()
            .any(|m| m.commanded_nm.is_nan() || m.applied_nm.is_nan() || m.limit_nm.is_nan())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Random sequences, NaN and infinities included: no panic; the
    /// verdict is the most severe latched reaction; a NaN an enabled check
    /// reads (any joint angle reported Ok among them) never gives `None`.
    #[test]
    fn random_inputs_never_pass_nan(inputs in proptest::collection::vec(random_input(), 1..12)) {
        let mut sup = supervisor();
        let mut latched_before = FaultSet::EMPTY;
        for input in &inputs {
            let v = sup.check(input);
            prop_assert_eq!(v.reaction, v.latched.reaction());
            prop_assert_eq!(v.new.intersection(latched_before), FaultSet::EMPTY);
            prop_assert_eq!(v.latched, latched_before.union(v.new));
            if input.joints.iter().any(|j| j.status == EncoderStatus::Ok && j.angle_rad.is_nan()) {
                prop_assert!(v.latched.contains(FaultCode::EncoderInvalidValue));
            }
            if has_nan(input) {
                prop_assert_ne!(v.reaction, Reaction::None);
            }
            prop_assert!(sup.present().intersection(v.latched) == sup.present());
            latched_before = v.latched;
        }
        prop_assert!(sup.log().count() <= LOG_LEN);
    }

    /// After a healthy history, one tick with NaN in random joint angles
    /// (status Ok) is never `None`.
    #[test]
    fn nan_joint_angle_after_healthy_history(mask in 1u8..16, warmup in 1u32..50) {
        let mut sup = supervisor();
        for tick in 0..warmup {
            sup.check(&moving_input(tick));
        }
        let mut input = moving_input(warmup);
        for j in 0..JOINTS {
            if mask & (1 << j) != 0 {
                input.joints[j].angle_rad = f32::NAN;
            }
        }
        let v = sup.check(&input);
        prop_assert_ne!(v.reaction, Reaction::None);
        prop_assert!(v.latched.contains(FaultCode::EncoderInvalidValue));
    }
}

// ------------------------------------------------------------------ log

#[test]
fn the_log_keeps_the_newest_records() {
    let mut sup = supervisor();
    let mut tick = 0;
    let cycles = LOG_LEN as u32 + 8;
    for _ in 0..cycles {
        let mut input = healthy_input(tick);
        input.e_stop_pressed = true;
        sup.check(&input);
        tick += 1;
        sup.check(&healthy_input(tick));
        tick += 1;
        assert_eq!(sup.request_reset(true), Ok(()));
    }
    let records: Vec<_> = sup.log().copied().collect();
    assert_eq!(records.len(), LOG_LEN);
    // Oldest first, and the 8 oldest cycles are gone.
    let ticks: Vec<u32> = records.iter().map(|r| r.tick).collect();
    let expected: Vec<u32> = (8..cycles).map(|c| 2 * c).collect();
    assert_eq!(ticks, expected);
    assert!(records.iter().all(|r| r.code == FaultCode::EStopPressed));
    assert!(records.iter().all(|r| r.channel == NO_CHANNEL));
}

#[test]
fn the_log_records_each_channel_once_while_latched() {
    let (sup, _) = inject(20, |k, input| {
        input.motors[0].thermal_fault = true;
        if k > 10 {
            input.motors[3].thermal_fault = true;
        }
    });
    let records: Vec<_> = sup.log().copied().collect();
    assert_eq!(records.len(), 2, "{records:?}");
    assert_eq!(records[0].channel, 0);
    assert_eq!(records[1].channel, 3);
    assert_eq!(records[1].tick, WARMUP + 10);
    assert!(records.iter().all(|r| r.code == FaultCode::MotorThermal));
}

#[test]
fn sizes_are_small() {
    // The supervisor lives in a static on the board: keep it small.
    assert!(core::mem::size_of::<Supervisor>() < 2048);
    assert_eq!(FORCES, 4);
}
