//! The campaign's named cases: a stop crossed is the device's unless a
//! named case's reason took the joint there.

use gait_control::operator::Gait;

use crate::common::instant_pilot_run;

#[test]
fn a_stop_crossed_is_the_device_s_unless_a_named_case_s_reason_took_the_joint_there() {
    // Seed 1's campaign with the instant pilot. The e-stop late in a stair descent: every drive
    // off and braked, the bent knee that carries the body sinks at load /
    // brake damping onto its flexion stop: a descent knee without its
    // drive, named.
    let estop = instant_pilot_run(Gait::StairDown, "estop@4.733", 526_588);
    assert!(estop.past_a_stop(), "{:?}", estop.outcome);
    assert_eq!(estop.outcome.worst_limit_joint, 1);
    assert!(estop.outcome.limit_margins[1].1, "the flexion stop");
    assert_eq!(
        estop.named_stop(),
        Some(sim::campaign::NamedCase::DescentKneeWithoutDrive)
    );
    assert!(!estop.unnamed_stop());
    // A stair descent's stance knee whose encoder's bus fails: braked at
    // the drive's full 375 N·m·s/rad while the chain does not give its
    // angle, it sinks slowly and stays 0.07 rad short of its stop (a brake
    // of 167 N·m·s/rad, under half that damping, would let it cross).
    let held = instant_pilot_run(Gait::StairDown, "encoder-bus:right-knee@1.925", 732265);
    assert!(held.outcome.braked_joints[3], "{:?}", held.outcome);
    assert!(!held.past_a_stop(), "{:?}", held.outcome);
    // The other knee, though, may take the body past what its working
    // drive gives: that is the device's (a knee braked for a lost
    // encoder, not one whose drive gave all it has, is not a named case).
    let lost = instant_pilot_run(Gait::StairDown, "encoder-parity:left-knee@2.091", 225828);
    assert!(lost.past_a_stop(), "{:?}", lost.outcome);
    assert_eq!(lost.outcome.worst_limit_joint, 3);
    assert!(lost.outcome.limit_margins[3].1, "the flexion stop");
    assert!(lost.outcome.braked_joints[1] && !lost.outcome.braked_joints[3]);
    assert_eq!(lost.named_stop(), None);
    assert!(lost.unnamed_stop());
}

#[test]
fn a_joint_whose_working_drive_gave_all_it_has_is_the_named_case_s() {
    // Seed 1's campaign with the instant pilot. A descent's stance knee whose gear
    // slips: the other knee takes the body as the set-down's foot lands,
    // its drive at its full torque against the flexion stop and the knee
    // not being stopped by it (a load the drive cannot overcome), and crosses;
    // only after that does the residual trip on it (a brake that comes then
    // does not change what took the knee there). A descent's knee without
    // its drive reaches it.
    let slip = instant_pilot_run(
        Gait::StairDown,
        "gear-slip=0.29826299163274117:right-knee@4.036",
        8_167,
    );
    // The left knee crossed its flexion stop resisting it with its drive
    // (so not braked before it crossed), the right knee braked.
    let left_knee_gave_all = |o: &sim::outcome::Outcome| {
        assert!(o.limit_margins[1].0 < 0.0 && o.limit_margins[1].1, "{o:?}");
        assert!(o.resisted_at_limit[1], "{o:?}");
        assert!(o.braked_joints[3], "{o:?}");
    };
    left_knee_gave_all(&slip.outcome);
    assert_eq!(
        slip.named_stop(),
        Some(sim::campaign::NamedCase::DescentKneeWithoutDrive)
    );
    // A descent's knee loses its encoder (error flag) late in the run:
    // braked, it sinks and the other knee takes the body, its drive at
    // its full torque against the flexion stop and not holding it, and
    // crosses; but a lost encoder is no drive lost: the device's.
    let blind = instant_pilot_run(
        Gait::StairDown,
        "encoder-error-flag:right-knee@4.659",
        98_331,
    );
    left_knee_gave_all(&blind.outcome);
    assert!(blind.unnamed_stop());
    // An ascent's stance hip loses its PWM in the first swing; the other
    // leg's straightened knee, braked in the cascade that follows, meets
    // its extension stop: braked, it did not resist it, and the stance
    // hip's case does not reach the knee.
    let hip = instant_pilot_run(Gait::StairUp, "pwm-fail:left-hip@2.224", 471_508);
    let o = &hip.outcome;
    assert!(o.limit_margins[3].0 < 0.0 && !o.limit_margins[3].1, "{o:?}");
    assert!(o.braked_joints[3] && !o.resisted_at_limit[3], "{o:?}");
    assert!(hip.unnamed_stop());
}
