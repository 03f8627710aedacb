//! Fixtures shared by the supervisor's tests: healthy inputs standing and
//! moving, fault injection into them, and the check of one fault-table row.

pub use gait_control::drivers::as5048a::{COUNTS_PER_REV, Calibration, Direction};
pub use gait_control::faults::{FaultCode, FaultSet, Reaction};
pub use gait_control::supervisor::{
    ANKLES, ConfigError, DriveCurrentSense, EncoderSense, EncoderStatus, FORCES, ForceSense,
    ForceStatus, JOINTS, LOG_LEN, MotorSense, NO_CHANNEL, ResetRefused, Supervisor,
    SupervisorConfig, SupervisorInput, Verdict,
};
pub use proptest::prelude::*;

// ---------------------------------------------------------------- fixtures

pub const RAD_PER_COUNT: f32 = 2.0 * core::f32::consts::PI / COUNTS_PER_REV as f32;
pub const DEG: f32 = core::f32::consts::PI / 180.0;
/// Healthy ticks before a fault is injected.
pub const WARMUP: u32 = 300;

/// Standing posture: hips, knees, ankles (rad).
pub const STAND_JOINTS: [f32; JOINTS] = [0.10, 0.10, 0.10, 0.10];
pub const STAND_ANKLES: [f32; ANKLES] = [0.05, 0.05];
pub const LIMIT_NM: f32 = 60.0;

/// An encoder frame as the AS5048A driver would give it for `angle_rad`
/// (zero offset 0, positive direction): raw counts and the calibrated,
/// quantised angle agree.
pub fn encoder(angle_rad: f32) -> EncoderSense {
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
pub fn dither(tick: u32, channel: usize) -> f32 {
    const PATTERN: [f32; 4] = [0.0, 1.0, 0.0, -1.0];
    PATTERN[(tick as usize + channel) % 4] * RAD_PER_COUNT
}

/// Standing still, everything healthy, with encoder noise. The reference is
/// the standing posture; the motors hold with a small torque.
pub fn healthy_input(tick: u32) -> SupervisorInput {
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
            enabled: true,
            feedforward_nm: 5.0,
        }; JOINTS],
        e_stop_pressed: false,
        e_stop_read_error: false,
        deadline_missed: false,
        step_in_progress: false,
        button_input_fault: false,
        ankle_plan_rad: [f32::NAN; ANKLES],
        swing_leg: None,
        stance_hip_residual_nm: f32::NAN,
        airborne_leg: None,
        chain_closed: [false; JOINTS],
        // One drive a tick, in turn, giving what it was asked.
        drive_current: Some(DriveCurrentSense {
            joint: (tick % JOINTS as u32) as u8,
            status: ForceStatus::Ok,
            torque_nm: 5.0 + dither(tick, 0) * 100.0,
        }),
    }
}

/// Walking-like motion: every joint follows a slow sine, the reference
/// with it, moderate torques.
pub fn moving_input(tick: u32) -> SupervisorInput {
    let mut input = healthy_input(tick);
    let t = tick as f32 * 0.001;
    for j in 0..JOINTS {
        let phase = j as f32 * 1.3;
        let angle = 0.4 + 0.3 * libm::sinf(2.0 * core::f32::consts::PI * 0.5 * t + phase);
        input.joints[j] = encoder(angle + dither(tick, j));
        input.joint_reference_rad[j] = angle;
        input.motors[j].commanded_nm = 20.0 * libm::cosf(t + phase);
        input.motors[j].applied_nm = input.motors[j].commanded_nm;
        // The model's torque for this motion is what is commanded.
        input.motors[j].feedforward_nm = input.motors[j].commanded_nm;
    }
    if let Some(d) = input.drive_current.as_mut() {
        d.torque_nm = input.motors[usize::from(d.joint)].applied_nm;
    }
    for a in 0..ANKLES {
        input.ankles[a] = encoder(0.1 + 0.08 * libm::sinf(3.0 * t + a as f32));
    }
    input.step_in_progress = true;
    input
}

/// The drive sampled this tick gives the current it was asked for (its
/// monitor reads the applied torque): a fault the monitor cannot see, or
/// none.
pub fn currents_follow(input: &mut SupervisorInput) {
    if let Some(d) = input.drive_current.as_mut() {
        d.torque_nm = input.motors[usize::from(d.joint)].applied_nm;
    }
}

pub fn supervisor() -> Supervisor {
    Supervisor::new(SupervisorConfig::paper()).unwrap()
}

/// Runs `WARMUP` healthy ticks (asserting nothing faults), then `n` ticks
/// of `healthy_input` changed by `inject(k, &mut input)`, k = 1..=n.
/// Returns the supervisor and the verdicts of the injected ticks
/// (`verdicts[k - 1]` is tick k).
pub fn inject(
    n: u32,
    mut inject: impl FnMut(u32, &mut SupervisorInput),
) -> (Supervisor, Vec<Verdict>) {
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
pub fn detected_at(verdicts: &[Verdict], code: FaultCode) -> Option<u32> {
    verdicts
        .iter()
        .position(|v| v.latched.contains(code))
        .map(|i| i as u32 + 1)
}

pub fn only(code: FaultCode) -> FaultSet {
    core::iter::once(code).collect()
}

/// The row's checks: detected exactly at tick `bound` (so within it and
/// not before), alone, newly, with the row's reaction.
pub fn assert_row(verdicts: &[Verdict], code: FaultCode, reaction: Reaction, bound: u32) {
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
