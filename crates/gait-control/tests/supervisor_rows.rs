//! Safety supervisor: one test per row of the fault table in
//! `docs/safety.md` (code, reaction, detection bound, not before).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::cast_possible_truncation,
    missing_docs
)]

mod supervisor_support;

use supervisor_support::*;

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
    // A reference creeping at 0.06 rad/s still drives the joint 16 counts
    // in 100 ticks (an ascent's stance knee late in its swing moves under
    // 0.1 rad/s, and its frozen encoder must still be found); at 0.04 rad/s
    // it counts as still (the bound is 0.05 rad/s).
    let creeping = |rad_s: f32| {
        inject(150, |k, input| {
            input.joints[0] = frozen;
            input.joint_reference_rad[0] = STAND_JOINTS[0] + rad_s * 1e-3 * k as f32;
        })
        .1
    };
    let v = creeping(0.06);
    assert_row(&v, FaultCode::EncoderFrozen, Reaction::SafeHold, 100);
    assert!(creeping(0.04).iter().all(|v| v.latched.is_empty()));
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
fn frozen_counts_add_up_over_driven_stretches_with_still_ones_between() {
    // Driven for 40 ticks (reference at 0.5 rad/s), still for 60, and so
    // on: an encoder frozen throughout trips on its 100th driven tick, in
    // the third stretch. A short still stretch neither counts nor forgives
    // (a hip frozen at the end of its swing sat through the weight
    // transfer's still reference and, with the count restarted, dropped the
    // pilot in the next step).
    let frozen = healthy_input(WARMUP - 1).joints[0];
    let drive = |still: u32| {
        move |k: u32, input: &mut SupervisorInput| {
            let driven = |i: u32| (i - 1) % (40 + still) < 40;
            input.joints[0] = frozen;
            let moving = (1..=k).filter(|&i| driven(i)).count() as f32;
            input.joint_reference_rad[0] = STAND_JOINTS[0] + 0.0005 * moving;
        }
    };
    let (_, v) = inject(260, drive(60));
    assert_row(&v, FaultCode::EncoderFrozen, Reaction::SafeHold, 220);
    // Counts that move in a still stretch restart the count: nothing.
    let (_, v) = inject(260, |k, input| {
        drive(60)(k, input);
        if k == 150 {
            input.joints[0] = encoder(frozen.angle_rad + 2.0 * RAD_PER_COUNT);
        }
    });
    assert!(v.iter().all(|v| v.latched.is_empty()));
    // A still stretch of `frozen_still_reset_ticks` (longer than a weight
    // transfer) restarts it too: driven ticks scattered over a long rest
    // never add up.
    let rest = SupervisorConfig::paper().frozen_still_reset_ticks;
    let (_, v) = inject(3 * (40 + rest), drive(rest));
    assert!(v.iter().all(|v| v.latched.is_empty()));
    let (_, v) = inject(3 * (40 + rest), drive(rest - 1));
    assert!(detected_at(&v, FaultCode::EncoderFrozen).is_some());
}

#[test]
fn a_frozen_encoder_is_reset_once_its_counts_change_or_it_has_rested() {
    // Latched while driven, then still with the reference on the reading:
    // the condition stays while the counts do, up to a still stretch of
    // `frozen_still_reset_ticks` (then the next driven stretch judges the
    // encoder again); counts that move clear it at once.
    let rest = SupervisorConfig::paper().frozen_still_reset_ticks;
    let frozen = healthy_input(WARMUP - 1).joints[0];
    let latched = || {
        let (sup, v) = inject(150, |k, input| {
            input.joints[0] = frozen;
            input.joint_reference_rad[0] = STAND_JOINTS[0] + 0.0005 * k as f32;
        });
        assert!(detected_at(&v, FaultCode::EncoderFrozen).is_some());
        sup
    };
    let still = |sup: &mut Supervisor, angle: f32, ticks: u32| {
        for tick in 0..ticks {
            let mut input = healthy_input(WARMUP + 150 + tick);
            input.joints[0] = encoder(angle);
            input.joint_reference_rad[0] = encoder(angle).angle_rad;
            sup.check(&input);
        }
    };
    let refused = Err(ResetRefused::ConditionPresent(only(
        FaultCode::EncoderFrozen,
    )));
    // The first still tick's reference jumps onto the reading: driven.
    let mut sup = latched();
    still(&mut sup, frozen.angle_rad, rest);
    assert_eq!(sup.request_reset(true), refused);
    still(&mut sup, frozen.angle_rad + 2.0 * RAD_PER_COUNT, 5);
    assert_eq!(sup.request_reset(true), Ok(()));
    let mut sup = latched();
    still(&mut sup, frozen.angle_rad, 1 + rest);
    assert_eq!(sup.request_reset(true), Ok(()));
}

#[test]
fn row_encoder_jump() {
    let jumped = encoder(STAND_JOINTS[1] + 2000.0 * RAD_PER_COUNT);
    let (_, v) = inject(10, |_, input| input.joints[1] = jumped);
    assert_row(&v, FaultCode::EncoderJump, Reaction::SafeHold, 3);
}

/// A frame of an encoder mounted with `direction`, reading `angle_rad`
/// plus `offset` counts (a magnet that slipped on its shaft).
fn offset_frame(angle_rad: f32, offset: i32, direction: Direction) -> EncoderSense {
    let counts = (angle_rad / RAD_PER_COUNT).round() as i32;
    let signed = match direction {
        Direction::Positive => counts,
        Direction::Negative => -counts,
    };
    let raw = (signed + offset).rem_euclid(i32::from(COUNTS_PER_REV)) as u16;
    let cal = Calibration {
        zero_offset_counts: 0,
        direction,
    };
    EncoderSense {
        status: EncoderStatus::Ok,
        raw_counts: raw,
        angle_rad: cal.counts_to_rad(raw),
    }
}

#[test]
fn a_persistent_jump_is_taken_out_of_the_frames_after_it() {
    // The knee reads 2,000 counts (44°) off from the 20th tick on while it
    // bends on at 0.5 rad/s; its reference follows the true angle. The
    // jump latches 0x0205, and from then on the supervisor takes the
    // frames without the offset: they continue from the last accepted
    // one, control is given the true angle, and nothing else trips (a
    // reading left 44° off would trip the tracking error).
    for direction in [Direction::Positive, Direction::Negative] {
        for offset in [2000, -2000, 9000] {
            let mut sup = supervisor();
            let base = STAND_JOINTS[1];
            let mut worst = 0.0f32;
            for tick in 0..600u32 {
                let mut input = healthy_input(tick);
                let truth = base + 0.0005 * tick as f32;
                let shift = if tick >= 20 { offset } else { 0 };
                let frame = offset_frame(truth, shift, direction);
                input.joints[1] = frame;
                input.joint_reference_rad[1] = offset_frame(truth, 0, direction).angle_rad;
                let taken = sup.accepts_encoder(1, &frame);
                let v = sup.check(&input);
                assert_eq!(
                    taken,
                    !(20..23).contains(&tick),
                    "{direction:?} {offset} tick {tick}"
                );
                if taken {
                    let seen = sup.encoder_angle(1, frame.angle_rad);
                    let truth = offset_frame(truth, 0, direction).angle_rad;
                    worst = worst.max((seen - truth).abs());
                }
                let others = v.latched.iter().filter(|&c| c != FaultCode::EncoderJump);
                assert_eq!(
                    others.count(),
                    0,
                    "{direction:?} {offset} tick {tick}: {v:?}"
                );
                assert_eq!(v.latched.contains(FaultCode::EncoderJump), tick >= 22);
            }
            // The joint's motion over the three jumping frames goes into
            // the offset: 3 ticks at 0.5 rad/s.
            assert!(worst < 0.0016, "{direction:?} {offset}: {worst} rad");
            // The window drains: the condition is gone, a reset is allowed.
            assert!(sup.request_reset(true).is_ok());
        }
    }
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

/// The right foot in the air, its ankle frozen at `reading` (the warm-up's
/// dither stops: the counts no longer change).
/// It rolls there at 0.02 rad a tick (no jump), then stays.
fn right_ankle_frozen_in_the_air(reading: f32, airborne: bool) -> (Supervisor, Vec<Verdict>) {
    inject(150, |k, input| {
        let step = 0.02 * k as f32;
        let start = STAND_ANKLES[1];
        input.ankles[1] = encoder(if reading > start {
            (start + step).min(reading)
        } else {
            (start - step).max(reading)
        });
        input.swing_leg = Some(gait_control::layout::Side::Right);
        input.airborne_leg = airborne.then_some(gait_control::layout::Side::Right);
        input.forces[1].newtons = 0.0;
    })
}

#[test]
fn an_ankle_stuck_on_its_stop_in_the_air_is_a_lost_ankle_encoder() {
    // Only the ground holds an ankle on its dorsiflexion stop; in the air
    // its spring takes it off. Counts that stay there, unchanged, for 100
    // ticks of a foot surely in the air: 0x0207, and control stops taking
    // them (a stuck reading taken for the landing's lean dropped the
    // pilot in a stair descent).
    let cfg = SupervisorConfig::paper();
    let stop = cfg.heel_off_rad;
    let (sup, v) = right_ankle_frozen_in_the_air(stop, true);
    // 15 ticks to roll onto the stop (0.35 rad); the 100th frame read
    // unchanged there trips.
    let on_stop = (1..)
        .find(|&k| STAND_ANKLES[1] + 0.02 * k as f32 >= stop)
        .unwrap();
    assert_row(
        &v,
        FaultCode::AnkleEncoder,
        Reaction::FinishStepThenHold,
        on_stop + cfg.frozen_ticks,
    );
    assert!(!sup.accepts_encoder(JOINTS + 1, &encoder(stop)));
    // The other ankle's frames are still taken.
    assert!(sup.accepts_encoder(JOINTS, &encoder(STAND_ANKLES[0])));
    // Counts that move again are taken again.
    let mut sup = sup;
    let mut input = healthy_input(WARMUP + 200);
    input.ankles[1] = encoder(stop - 2.0 * RAD_PER_COUNT);
    assert!(!sup.accepts_encoder(JOINTS + 1, &input.ankles[1]));
    sup.check(&input);
    assert!(sup.accepts_encoder(JOINTS + 1, &encoder(stop - 3.0 * RAD_PER_COUNT)));

    // Not yet surely in the air (a trailing toe may still hold the stop),
    // off the stop (at the spring's rest), or moving: nothing.
    for (reading, airborne) in [(stop, false), (0.0, true), (stop - 1.0 * DEG, true)] {
        let (sup, v) = right_ankle_frozen_in_the_air(reading, airborne);
        assert!(
            v.iter().all(|x| x.reaction == Reaction::None),
            "reading {reading}, airborne {airborne}"
        );
        assert!(sup.accepts_encoder(JOINTS + 1, &encoder(reading)));
    }
    let (_, v) = inject(300, |k, input| {
        let ramp = (STAND_ANKLES[1] + 0.02 * k as f32).min(stop);
        input.ankles[1] = encoder(ramp - 2.0 * RAD_PER_COUNT * (k % 2) as f32);
        input.airborne_leg = Some(gait_control::layout::Side::Right);
    });
    assert!(v.iter().all(|x| x.reaction == Reaction::None));
}

/// A left swing (right stance) whose plan turns the right shank by
/// `rate` rad a tick from the standing angle, the right ankle reading
/// `reading(k, planned)` at tick k.
fn right_stance_in_a_swing(
    rate: f32,
    reading: impl Fn(u32, f32) -> f32,
) -> (Supervisor, Vec<Verdict>) {
    inject(200, |k, input| {
        let planned = STAND_ANKLES[1] + rate * k as f32;
        input.ankles[1] = encoder(reading(k, planned));
        input.swing_leg = Some(gait_control::layout::Side::Left);
        input.ankle_plan_rad = [f32::NAN, planned];
        input.forces[0].newtons = 0.0;
    })
}

#[test]
fn a_stance_ankle_that_does_not_turn_with_the_plan_is_a_lost_ankle_encoder() {
    // A walk's stance ankle frozen mid-swing: its stale reading would set
    // the posture the step plays on with past the table's end, the
    // residual would brake the stance knee and the pilot fall. Counts that
    // do not change once while the plan turns the shank by 0.05 rad:
    // 0x0207, and control stops taking them.
    let cfg = SupervisorConfig::paper();
    let rate = 0.5e-3; // 0.5 rad/s
    let (sup, v) = right_stance_in_a_swing(rate, |_, _| STAND_ANKLES[1]);
    let bound = (cfg.frozen_ankle_plan_rad / rate).ceil() as u32;
    let at = detected_at(&v, FaultCode::AnkleEncoder).unwrap();
    assert!(at.abs_diff(bound) <= 1, "{at} against {bound}");
    assert_row(
        &v,
        FaultCode::AnkleEncoder,
        Reaction::FinishStepThenHold,
        at,
    );
    assert!(!sup.accepts_encoder(JOINTS + 1, &encoder(STAND_ANKLES[1])));
    assert!(sup.accepts_encoder(JOINTS, &encoder(STAND_ANKLES[0])));

    // Following the plan, lagging it by 0.1 rad, or still with a count of
    // noise, as a pilot who stops the shank may: nothing. Nor when the
    // plan does not turn it (a frozen reading on a held shank is a good
    // one), nor on the dorsiflexion stop (a heel up), nor with no swing.
    let quiet = |v: &[Verdict]| v.iter().all(|x| x.reaction == Reaction::None);
    assert!(quiet(&right_stance_in_a_swing(rate, |_, p| p).1));
    assert!(quiet(&right_stance_in_a_swing(rate, |_, p| p - 0.1).1));
    let noisy = |k: u32, _| STAND_ANKLES[1] + RAD_PER_COUNT * (k % 2) as f32;
    assert!(quiet(&right_stance_in_a_swing(rate, noisy).1));
    assert!(quiet(
        &right_stance_in_a_swing(0.0, |_, _| STAND_ANKLES[1]).1
    ));
    let stop = cfg.heel_off_rad;
    let (_, v) = inject(200, |k, input| {
        input.ankles[1] = encoder((STAND_ANKLES[1] + 0.02 * k as f32).min(stop));
        input.swing_leg = Some(gait_control::layout::Side::Left);
        input.ankle_plan_rad = [f32::NAN, stop + rate * k as f32];
        input.forces[0].newtons = 0.0;
    });
    assert!(
        quiet(&v),
        "{:?}",
        v.iter().find(|x| x.reaction != Reaction::None)
    );
    let (_, v) = inject(200, |k, input| {
        input.ankle_plan_rad = [f32::NAN, STAND_ANKLES[1] + rate * k as f32];
    });
    assert!(quiet(&v));
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

/// The injected ticks (1-based) on which joint `j`'s drive is sampled.
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
