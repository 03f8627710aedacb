//! Fault-table rows of the hip and knee encoders: bad frames in a
//! window, frozen counts, impossible jumps, invalid values.

use crate::supervisor::support::*;

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

/// Tick `tick` of the knee bending on at 0.5 rad/s from standing, its
/// encoder (mounted with `direction`) reading `shift` counts off: the
/// healthy input with that frame and the true angle as the reference,
/// and the frame and the true angle.
fn bending_knee(
    tick: u32,
    shift: i32,
    direction: Direction,
) -> (SupervisorInput, EncoderSense, f32) {
    let mut input = healthy_input(tick);
    let truth = STAND_JOINTS[1] + 0.0005 * tick as f32;
    let frame = offset_frame(truth, shift, direction);
    let truth_rad = offset_frame(truth, 0, direction).angle_rad;
    input.joints[1] = frame;
    input.joint_reference_rad[1] = truth_rad;
    (input, frame, truth_rad)
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
            let mut worst = 0.0f32;
            for tick in 0..600u32 {
                let shift = if tick >= 20 { offset } else { 0 };
                let (input, frame, truth) = bending_knee(tick, shift, direction);
                let taken = sup.accepts_encoder(1, &frame);
                let v = sup.check(&input);
                assert_eq!(
                    taken,
                    !(20..23).contains(&tick),
                    "{direction:?} {offset} tick {tick}"
                );
                if taken {
                    let seen = sup.encoder_angle(1, frame.angle_rad);
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
fn frames_taken_before_the_check_decide_as_the_check_alone() {
    // The controller classifies each frame once, before it acts
    // (`take_encoder`), and the check goes on from it (`check_frames`).
    // Over a run with bad frames, a seed, a persistent jump on the knee,
    // an invalid value and a frozen ankle, that path gives the check's
    // own verdicts and log, and a frame is usable exactly when
    // `accepts_encoder` said so before it.
    let mut alone = supervisor();
    let mut taking = supervisor();
    let mut stuck_frames = 0;
    for tick in 0..900u32 {
        let shift = if (300..600).contains(&tick) { 2000 } else { 0 };
        let (mut input, _, _) = bending_knee(tick, shift, Direction::Positive);
        // The right ankle rolls onto its stop with the foot in the air and
        // stays there (found stuck, 0x0207: classified, not usable), then
        // moves off it again.
        let stop = SupervisorConfig::paper().heel_off_rad;
        match tick {
            50..=52 => input.joints[0].status = EncoderStatus::Parity,
            120 => input.joints[2].raw_counts = 0xFFFF,
            200..=260 => input.ankles[1].status = EncoderStatus::BusError,
            400..=599 => {
                let roll = STAND_ANKLES[1] + 0.02 * (tick - 400) as f32;
                input.ankles[1] = encoder(roll.min(stop));
                input.airborne_leg = Some(gait_control::supervisor::Side::Right);
            }
            600..=650 => {
                input.ankles[1] = encoder(stop - 2.0 * RAD_PER_COUNT * (tick - 599) as f32);
            }
            700 => input.joints[3].angle_rad = f32::NAN,
            _ => {}
        }
        let senses = [
            input.joints[0],
            input.joints[1],
            input.joints[2],
            input.joints[3],
            input.ankles[0],
            input.ankles[1],
        ];
        let accepted: Vec<bool> = (0..6)
            .map(|i| taking.accepts_encoder(i, &senses[i]))
            .collect();
        let frames = core::array::from_fn(|i| taking.take_encoder(i, &senses[i]));
        for (i, f) in frames.iter().enumerate() {
            assert_eq!(f.usable(), accepted[i], "tick {tick} channel {i}");
        }
        if input.ankles[1].status == EncoderStatus::Ok && !frames[JOINTS + 1].usable() {
            stuck_frames += 1;
        }
        let a = alone.check(&input);
        let b = taking.check_frames(&input, &frames);
        assert_eq!(a, b, "tick {tick}");
    }
    assert!(alone.latched().contains(FaultCode::EncoderJump));
    assert!(alone.latched().contains(FaultCode::AnkleEncoder));
    // Found stuck until its counts moved: ~100 frames on the stop.
    assert!((50..200).contains(&stuck_frames), "{stuck_frames}");
    // Bit for bit: the invalid reading's value is NaN.
    let record =
        |r: &gait_control::supervisor::FaultRecord| (r.tick, r.code, r.channel, r.value.to_bits());
    assert!(alone.log().map(record).eq(taking.log().map(record)));
    assert!(
        alone
            .log()
            .any(|r| r.code == FaultCode::EncoderInvalidValue)
    );
}
