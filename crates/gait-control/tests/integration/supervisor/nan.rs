//! Safety supervisor: a NaN anywhere in its input can only trip a fault,
//! never pass a check.

use super::support::*;

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
    ("drive_current.torque_nm", |i, x| {
        if let Some(d) = i.drive_current.as_mut() {
            d.torque_nm = x;
        }
    }),
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
    let drive_current = (
        0u8..4,
        prop_oneof![
            4 => Just(ForceStatus::Ok),
            1 => Just(ForceStatus::BusError),
            1 => Just(ForceStatus::Open),
            1 => Just(ForceStatus::Shorted),
        ],
        float(),
    )
        .prop_map(|(joint, status, torque_nm)| DriveCurrentSense {
            joint,
            status,
            torque_nm,
        });
    let motor = (
        float(),
        float(),
        float(),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        float(),
    )
        .prop_map(
            |(commanded_nm, applied_nm, limit_nm, thermal_fault, output_fault, enabled, ff)| {
                MotorSense {
                    commanded_nm,
                    applied_nm,
                    limit_nm,
                    thermal_fault,
                    output_fault,
                    enabled,
                    feedforward_nm: ff,
                }
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
        proptest::option::of(drive_current),
    )
        .prop_map(
            |(tick, joints, joint_reference_rad, ankles, forces, motors, flags, drive_current)| {
                SupervisorInput {
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
                    swing_leg: None,
                    stance_hip_residual_nm: f32::NAN,
                    airborne_leg: None,
                    chain_closed: [false; 4],
                    drive_current,
                }
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
        || input
            .drive_current
            .is_some_and(|d| d.status == ForceStatus::Ok && d.torque_nm.is_nan())
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
