//! Fault-table rows of the motors: saturation, a joint not answering its
//! torque (and which joint is braked for it), thermal and output stage.

use crate::supervisor::support::*;

#[test]
fn row_motor_saturated() {
    let (_, v) = inject(250, |_, input| {
        input.motors[3].commanded_nm = -LIMIT_NM;
        input.motors[3].applied_nm = -LIMIT_NM;
        currents_follow(input);
    });
    assert_row(&v, FaultCode::MotorSaturated, Reaction::SafeHold, 200);
}

/// A gearbox that slips (the drive's current follows its command, so
/// 0x0405 cannot see it): the position loop asks 125 N·m more than the
/// model's torque, the joint does not move. The residual's
/// 3 Hz critically damped low-pass passes 80 % of a step after about 160
/// ticks, and the fault latches 10 ticks later; the joint's drive is to be
/// braked.
#[test]
fn row_motor_response() {
    let (_, v) = inject(200, |_, input| {
        input.motors[1].commanded_nm = 130.0;
        input.motors[1].applied_nm = 130.0;
        input.motors[1].limit_nm = 150.0;
        currents_follow(input);
    });
    let at = detected_at(&v, FaultCode::MotorResponse).unwrap();
    assert!((150..=190).contains(&at), "detected at tick {at}");
    assert_row(&v, FaultCode::MotorResponse, Reaction::SafeHold, at);
    let verdict = v[at as usize - 1];
    assert_eq!(verdict.braked_joints, [false, true, false, false]);
}

/// A stance hip whose gear slips in a swing (the left hip, the right leg
/// swinging): the position loop asks 90 N·m more than the model's torque
/// and the joint does not move. Over the device's 100 N·m it would pass;
/// a gait that holds that hip to 70 N·m (its own healthy peak with a
/// margin) has it caught. The gait's figure is held within the device's
/// bounds (70–100 N·m), and it is the stance hip's alone.
#[test]
fn a_gait_s_own_limit_catches_a_slipping_stance_hip() {
    let slip = |joint: usize, gait_nm: f32| {
        let (_, v) = inject(400, |_, input| {
            input.swing_leg = Some(gait_control::layout::Side::Right);
            input.stance_hip_residual_nm = gait_nm;
            input.motors[joint].commanded_nm = 95.0;
            input.motors[joint].applied_nm = 95.0;
            input.motors[joint].limit_nm = 150.0;
            currents_follow(input);
        });
        detected_at(&v, FaultCode::MotorResponse).map(|at| (at, v[at as usize - 1].braked_joints))
    };
    let caught = slip(0, 70.0);
    assert!(
        matches!(caught, Some((at, [true, false, false, false])) if (150..=300).contains(&at)),
        "{caught:?}"
    );
    // Asked for less than the device allows: held to 70 N·m, caught alike.
    assert_eq!(slip(0, 40.0), caught);
    // The device's own limit: no gait figure, or one above the limit.
    for gait_nm in [f32::NAN, 0.0, 150.0] {
        assert_eq!(slip(0, gait_nm), None, "gait asks {gait_nm} N·m");
    }
    // The swing hip and the stance knee keep the device's limit.
    assert_eq!(slip(2, 70.0), None);
    assert_eq!(slip(1, 70.0), None);
}

/// A pilot leaning on the crutches drives the stance shank ahead of its
/// plan, and the hip carrying the torso feels a torque no drive gave: with
/// its ankle read more than `leaning_ankle_rad` (0.05 rad) ahead, that hip's
/// limit is doubled. The slip the gait's 70 N·m catches passes there; a
/// stuck drive's gap (250 N·m) is still caught, an ankle 0.04 rad ahead or
/// behind the plan keeps the limit, and the other hip keeps its own.
#[test]
fn a_leaning_pilot_s_hip_has_its_residual_limit_raised() {
    let run = |joint: usize, gap_nm: f32, ahead_rad: f32| {
        let (_, v) = inject(400, |_, input| {
            input.swing_leg = Some(gait_control::layout::Side::Right);
            input.stance_hip_residual_nm = 70.0;
            input.ankle_plan_rad = [STAND_ANKLES[0] - ahead_rad, f32::NAN];
            input.motors[joint].commanded_nm = gap_nm;
            input.motors[joint].applied_nm = gap_nm;
            input.motors[joint].limit_nm = 300.0;
            currents_follow(input);
        });
        detected_at(&v, FaultCode::MotorResponse)
    };
    let on_plan = run(0, 95.0, 0.0);
    assert!(
        on_plan.is_some_and(|at| (150..=300).contains(&at)),
        "{on_plan:?}"
    );
    assert_eq!(run(0, 95.0, 0.04), on_plan);
    assert_eq!(run(0, 95.0, -0.1), on_plan);
    assert_eq!(run(0, 95.0, 0.1), None, "leaning: 140 N·m");
    let stuck = run(0, 250.0, 0.1);
    assert!(stuck.is_some_and(|at| at < 200), "{stuck:?}");
    // The swing hip (the right: its own ankle has no plan) keeps 100 N·m.
    let swing_hip = run(2, 130.0, 0.1);
    assert!(swing_hip.is_some_and(|at| at < 300), "{swing_hip:?}");
}

/// 0x0404 on a joint while another is already braked: most likely the
/// braked joint dragged it, so it is held where it is with its drive
/// (latched and logged as ever, not braked), once; the residual still
/// over its limit 10 ticks on brakes it.
#[test]
fn a_response_fault_while_another_joint_is_braked_holds_the_joint_in_place_once() {
    let (sup, v) = inject(260, |_, input| {
        input.motors[2].output_fault = true;
        input.motors[1].commanded_nm = 130.0;
        input.motors[1].applied_nm = 130.0;
        input.motors[1].limit_nm = 150.0;
        currents_follow(input);
    });
    let at = detected_at(&v, FaultCode::MotorResponse).unwrap() as usize;
    assert!((150..=190).contains(&at), "detected at tick {at}");
    let held: Vec<usize> = (1..=v.len())
        .filter(|&k| v[k - 1].rehold_joints != [false; 4])
        .collect();
    assert_eq!(held, [at], "held in place once, when it latched");
    assert_eq!(v[at - 1].rehold_joints, [false, true, false, false]);
    assert_eq!(v[at - 1].braked_joints, [false, false, true, false]);
    assert_eq!(v[at - 1].reaction, Reaction::SafeHold);
    assert!(
        sup.log()
            .any(|r| r.code == FaultCode::MotorResponse && r.channel == 1),
        "logged"
    );
    let braked_at = (1..=v.len()).find(|&k| v[k - 1].braked_joints[1]).unwrap();
    assert_eq!(braked_at, at + 10, "the second trip brakes it");
    // Alone, the same fault brakes the joint at once (row_motor_response).
}

/// The same push when the joint answers it as the model says (its error
/// accelerates at u / J) is no fault; a disabled or ramping drive is not
/// checked at all.
#[test]
fn motor_response_follows_the_model_and_only_full_authority_drives() {
    let inertia = SupervisorConfig::paper().response.stance_inertia_kgm2[1];
    // Until the tracking error's bound: the error reaches 0.15 rad after
    // 136 ticks.
    let (_, v) = inject(230, |k, input| {
        let t = (k - 1) as f32 * 0.001;
        let push = 130.0;
        input.joints[1] = encoder(STAND_JOINTS[1] + 0.5 * push / inertia * t * t);
        input.motors[1].commanded_nm = 5.0 + push;
        input.motors[1].applied_nm = 5.0 + push;
        input.motors[1].limit_nm = 150.0;
        currents_follow(input);
    });
    assert_eq!(detected_at(&v, FaultCode::MotorResponse), None);
    assert!(v.last().unwrap().latched.is_empty());
    let (_, v) = inject(200, |_, input| {
        input.motors[1].commanded_nm = 130.0;
        input.motors[1].applied_nm = 130.0;
        input.motors[1].limit_nm = 150.0;
        input.motors[1].enabled = false;
    });
    assert_eq!(detected_at(&v, FaultCode::MotorResponse), None);
}

/// A swing knee that answers a push as its swing inertia says, then
/// lands and goes on at the speed it had, pushed no more: read against the
/// stance leg's inertia, 23 times the swing knee's, the swing's filtered
/// acceleration would be some 200 N·m the drive did not give. At the
/// landing the observer's acceleration starts again from 0, its rate kept.
#[test]
fn a_landing_leg_s_motion_is_not_read_against_the_stance_inertia() {
    let swing = SupervisorConfig::paper().response.swing_inertia_kgm2[1];
    let push = 20.0;
    let land_at = 60;
    let at = |k: u32| {
        let a = push / swing;
        let t = (k - 1) as f32 * 0.001;
        let t0 = (land_at - 1) as f32 * 0.001;
        if k < land_at {
            STAND_JOINTS[3] + 0.5 * a * t * t
        } else {
            STAND_JOINTS[3] + 0.5 * a * t0 * t0 + a * t0 * (t - t0)
        }
    };
    let (_, v) = inject(120, |k, input| {
        let swinging = k < land_at;
        input.swing_leg = swinging.then_some(gait_control::layout::Side::Right);
        input.joints[3] = encoder(at(k));
        let u = if swinging { push } else { 0.0 };
        input.motors[3].commanded_nm = 5.0 + u;
        input.motors[3].applied_nm = 5.0 + u;
        input.motors[3].limit_nm = 150.0;
    });
    assert_eq!(
        detected_at(&v, FaultCode::MotorResponse),
        None,
        "{:?}",
        v.last()
    );
}

/// The brake stays until a clinician's reset clears the fault, once the
/// residual is back under the limit.
#[test]
fn a_braked_joint_is_released_by_a_reset() {
    let (mut sup, v) = inject(300, |_, input| {
        input.motors[3].commanded_nm = -135.0;
        input.motors[3].applied_nm = -135.0;
        input.motors[3].limit_nm = 150.0;
    });
    assert!(v.last().unwrap().braked_joints[3]);
    let mut last = *v.last().unwrap();
    for tick in 0..20 {
        let mut input = healthy_input(WARMUP + 300 + tick);
        input.motors[3].enabled = false;
        last = sup.check(&input);
    }
    assert!(last.braked_joints[3], "held until a reset");
    sup.request_reset(true).unwrap();
    let v = sup.check(&healthy_input(WARMUP + 400));
    assert_eq!(v.braked_joints, [false; JOINTS]);
    assert!(v.latched.is_empty());
}

/// A lost encoder brakes its joint only while the closed chain of double
/// support does not give its angle; a drive fault brakes its joint
/// whatever the chain says. Both until a reset.
#[test]
fn a_lost_encoder_brakes_its_joint_only_while_the_chain_is_open() {
    let (mut sup, v) = inject(5, |_, input| {
        input.joints[1].status = EncoderStatus::BusError;
        input.motors[2].output_fault = true;
    });
    let last = *v.last().unwrap();
    assert!(last.latched.contains(FaultCode::EncoderBusError));
    assert_eq!(last.braked_joints, [false, true, true, false]);
    assert_eq!(sup.angle_lost_joints(), [false, true, false, false]);
    // The frames come back (the fault stays latched): still braked while
    // the chain is open, driven while it is closed, braked again when it
    // opens.
    for (k, closed, braked) in [(0, false, true), (1, true, false), (2, false, true)] {
        let mut input = healthy_input(WARMUP + 10 + k);
        input.chain_closed = [closed; JOINTS];
        let v = sup.check(&input);
        assert_eq!(v.braked_joints[1], braked, "chain closed: {closed}");
        assert!(
            v.braked_joints[2],
            "a drive fault brakes whatever the chain"
        );
        assert_eq!(v.reaction, Reaction::SafeHold);
    }
    // Once the encoder has read well for 100 ticks, a reset clears it.
    for tick in 0..110 {
        let mut input = healthy_input(WARMUP + 20 + tick);
        input.motors[1].enabled = false;
        input.motors[2].enabled = false;
        sup.check(&input);
    }
    sup.request_reset(true).unwrap();
    assert_eq!(sup.angle_lost_joints(), [false; JOINTS]);
    let v = sup.check(&healthy_input(WARMUP + 200));
    assert_eq!(v.braked_joints, [false; JOINTS]);
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
    assert_row(&v, FaultCode::MotorOutputStage, Reaction::SafeHold, 1);
    assert_eq!(v[0].braked_joints, [false, false, true, false]);
}
