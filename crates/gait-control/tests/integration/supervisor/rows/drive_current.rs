//! Fault-table rows of the drives' current monitors: a drive not giving
//! the current asked, a monitor that fails.

use crate::supervisor::support::*;

fn samples_of(j: u8, n: u32) -> Vec<u32> {
    (1..=n)
        .filter(|&k| healthy_input(WARMUP + k - 1).drive_current.unwrap().joint == j)
        .collect()
}

/// Joint `j`'s drive asked `asked` N·m, its monitor reading `got` (the
/// other drives give what they are asked).
fn drive_gives(j: usize, asked: f32, got: f32) -> impl FnMut(u32, &mut SupervisorInput) {
    move |_, input| {
        input.motors[j].commanded_nm = asked;
        input.motors[j].applied_nm = asked;
        input.motors[j].limit_nm = 150.0;
        currents_follow(input);
        if let Some(d) = input.drive_current.as_mut() {
            if usize::from(d.joint) == j {
                d.torque_nm = got;
            }
        }
    }
}

/// A drive stuck on an old set value: asked 60 N·m, its current gives
/// −1.2. Found on its third sample, at its own joint, which is braked.
#[test]
fn row_drive_current_mismatch() {
    let (_, v) = inject(40, drive_gives(1, 60.0, -1.2));
    let third = samples_of(1, 40)[2];
    assert!(third <= 12, "{third}");
    assert_row(
        &v,
        FaultCode::DriveCurrentMismatch,
        Reaction::SafeHold,
        third,
    );
    assert_eq!(
        v[third as usize - 1].braked_joints,
        [false, true, false, false]
    );
    // More than asked is a mismatch too (a set value stuck high).
    let (_, v) = inject(40, drive_gives(3, -10.0, -60.0));
    assert_eq!(
        detected_at(&v, FaultCode::DriveCurrentMismatch),
        Some(samples_of(3, 40)[2])
    );
}

/// A drive at half its current is found where the missing half exceeds
/// the band (10 N·m + 10 %), not below it.
#[test]
fn a_weak_drive_is_a_mismatch_once_the_missing_torque_exceeds_the_band() {
    let (_, v) = inject(40, drive_gives(0, 80.0, 40.0));
    assert_eq!(
        detected_at(&v, FaultCode::DriveCurrentMismatch),
        Some(samples_of(0, 40)[2])
    );
    let (_, v) = inject(200, drive_gives(0, 30.0, 18.0));
    assert!(v.last().unwrap().latched.is_empty(), "{:?}", v.last());
    // Two bad samples, then a good one: the count starts again.
    let mut k_seen = 0;
    let (_, v) = inject(40, move |k, input| {
        drive_gives(2, 80.0, 80.0)(k, input);
        if input.drive_current.unwrap().joint == 2 {
            k_seen += 1;
            if k_seen % 3 != 0 {
                input.drive_current.as_mut().unwrap().torque_nm = 0.0;
            }
        }
    });
    assert_eq!(detected_at(&v, FaultCode::DriveCurrentMismatch), None);
}

/// Moving fast in its torque's direction a drive cannot push the current
/// asked against the motor's back-EMF: no mismatch. Against the motion it
/// can, and must.
#[test]
fn less_current_than_asked_counts_only_where_the_back_emf_does_not_explain_it() {
    let moving = |torque: f32| {
        move |k: u32, input: &mut SupervisorInput| {
            // Joint 1 flexing at 2 rad/s, its reference with it.
            let angle = STAND_JOINTS[1] + 2.0 * 0.001 * k as f32;
            input.joints[1] = encoder(angle);
            input.joint_reference_rad[1] = angle;
            input.motors[1].feedforward_nm = torque;
            drive_gives(1, torque, 0.0)(k, input);
        }
    };
    let (_, v) = inject(60, moving(100.0));
    assert_eq!(detected_at(&v, FaultCode::DriveCurrentMismatch), None);
    let (_, v) = inject(60, moving(-100.0));
    assert!(detected_at(&v, FaultCode::DriveCurrentMismatch).is_some());
}

/// A disabled drive gives no current: nothing to compare.
#[test]
fn a_disabled_drive_s_current_is_not_compared() {
    let (_, v) = inject(100, |k, input| {
        drive_gives(1, 60.0, 0.0)(k, input);
        input.motors[1].enabled = false;
    });
    assert_eq!(detected_at(&v, FaultCode::DriveCurrentMismatch), None);
}

/// A monitor at a rail, or its conversion failing: 0x0406 on its third
/// bad sample; the drive goes on (finish the step, then hold). Reported Ok
/// but not finite: at once.
#[test]
fn row_drive_current_monitor() {
    for status in [
        ForceStatus::Open,
        ForceStatus::Shorted,
        ForceStatus::BusError,
    ] {
        let (sup, v) = inject(40, |_, input| {
            if let Some(d) = input.drive_current.as_mut() {
                if d.joint == 2 {
                    d.status = status;
                    d.torque_nm = f32::NAN;
                }
            }
        });
        let third = samples_of(2, 40)[2];
        assert_row(
            &v,
            FaultCode::DriveCurrentMonitor,
            Reaction::FinishStepThenHold,
            third,
        );
        assert_eq!(v[third as usize - 1].braked_joints, [false; JOINTS]);
        assert_eq!(sup.log().last().unwrap().channel, 2);
    }
    let first = samples_of(0, 40)[0];
    let (_, v) = inject(40, |_, input| {
        if let Some(d) = input.drive_current.as_mut() {
            if d.joint == 0 {
                d.torque_nm = f32::INFINITY;
            }
        }
    });
    assert_row(
        &v,
        FaultCode::DriveCurrentMonitor,
        Reaction::FinishStepThenHold,
        first,
    );
}
