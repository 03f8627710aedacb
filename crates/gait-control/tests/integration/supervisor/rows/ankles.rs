//! Fault-table rows of the passive ankles: position limit, unplanned
//! heel-off, a lost ankle encoder.

use crate::supervisor::support::*;

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
    // (NaN: standing, the swing ankle), or off the stop: no heel-off (an
    // ankle that rolls 0.2 rad off its plan in 10 ms is the pilot's
    // balance, 0x0701/0x0702).
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
            v.iter()
                .all(|x| !x.latched.contains(FaultCode::UnplannedHeelOff)),
            "reading {reading}, plan {plan}"
        );
        // Nor is a shank that got there in 15 ms and stands still a pilot
        // falling: its error no longer grows.
        assert_eq!(detected_at(&v, FaultCode::PilotFallingForward), None);
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
    // (Still while the plan turns it, with the crutches idle, is the
    // pilot falling back, 0x0702: not a lost encoder.)
    let noisy = |k: u32, _| STAND_ANKLES[1] + RAD_PER_COUNT * (k % 2) as f32;
    let v = right_stance_in_a_swing(rate, noisy).1;
    assert_eq!(detected_at(&v, FaultCode::AnkleEncoder), None);
    assert!(detected_at(&v, FaultCode::PilotFallingBack).is_some());
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

/// The left ankle moving away from its plan (the standing angle) at
/// `rate` rad a tick, in a right swing when `swing`, the crutches' sum
/// `push_n` above the standing rig's from the second tick on (NaN: a
/// crutch sensor that cannot tell); its verdicts.
fn left_shank_leaving_its_plan(rate: f32, swing: bool, push_n: f32) -> Vec<Verdict> {
    use gait_control::layout::force::LEFT_CRUTCH;
    inject(900, |k, input| {
        input.ankles[0] = encoder(STAND_ANKLES[0] + rate * k as f32);
        input.ankle_plan_rad[0] = STAND_ANKLES[0];
        if swing {
            input.swing_leg = Some(gait_control::layout::Side::Right);
        }
        if k > 1 {
            input.forces[LEFT_CRUTCH].newtons += push_n;
        }
    })
    .1
}

#[test]
fn row_pilot_falling() {
    // The shank turning away from the plan at 0.5 rad/s (a pilot who no
    // longer balances the body over the foot) with the crutches carrying
    // no more than the least they carried lately: from the first frame
    // more than 0.1 rad off (0.05 rad in a swing), 30 frames moving away
    // trip it, forward 0x0701 (in a swing the step lands first), back
    // 0x0702 (the foot is set down).
    use gait_control::faults::InSwing;
    let cfg = SupervisorConfig::paper().balance;
    let rate = 0.5e-3;
    let off =
        |k: u32, rate: f32| encoder(STAND_ANKLES[0] + rate * k as f32).angle_rad - STAND_ANKLES[0];
    let first_beyond = |bound: f32, rate: f32| (1..).find(|&k| off(k, rate).abs() > bound).unwrap();
    let at = |bound: f32, rate: f32| first_beyond(bound, rate) + cfg.ticks - 1;
    for (swing, bound) in [(false, cfg.idle.feet_down_rad), (true, cfg.idle.swing_rad)] {
        let v = left_shank_leaving_its_plan(rate, swing, 0.0);
        assert_row(
            &v,
            FaultCode::PilotFallingForward,
            Reaction::SafeHold,
            at(bound, rate),
        );
        // (Back by 0.1 rad the standing shank is past its plantarflexion
        // range too: 0x0104 comes with it.)
        let v = left_shank_leaving_its_plan(-rate, swing, 0.0);
        assert_eq!(
            detected_at(&v, FaultCode::PilotFallingBack),
            Some(at(bound, -rate))
        );
    }
    assert_eq!(FaultCode::PilotFallingBack.reaction(), Reaction::SafeHold);
    assert_eq!(
        FaultCode::PilotFallingForward.in_swing(),
        InSwing::LandFirst
    );
    assert_eq!(FaultCode::PilotFallingBack.in_swing(), InSwing::HoldNow);
    // A pilot pushing on the crutches (more than 40 N over the least they
    // carried lately: 80 N, as the least forgets at 20 N/s meanwhile) may
    // let the shank lag or overshoot: 0.2 rad with both feet down, 0.25
    // in a swing. A crutch sensor that cannot tell never lowers the bound.
    let pushing = 2.0 * cfg.crutch_rise_n;
    for (push, swing, bound) in [
        (pushing, false, cfg.pushed.feet_down_rad),
        (pushing, true, cfg.pushed.swing_rad),
        (f32::NAN, true, cfg.pushed.swing_rad),
    ] {
        let v = left_shank_leaving_its_plan(rate, swing, push);
        assert_eq!(
            detected_at(&v, FaultCode::PilotFallingForward),
            Some(at(bound, rate)),
            "push {push} N, swing {swing}"
        );
    }
    // A pilot bringing the shank back, or a shank drifting off slower
    // than 0.25 rad/s and held there: nothing.
    let quiet = |v: &[Verdict]| v.iter().all(|x| x.reaction == Reaction::None);
    assert!(quiet(&left_shank_leaving_its_plan(0.2e-3, false, 0.0)));
    // Out at 0.2 rad/s to 0.14 rad, then back at 0.5 rad/s.
    let (_, v) = inject(1100, |k, input| {
        let k = k as f32;
        let off = (0.2e-3 * k).min(0.14 - 0.5e-3 * (k - 700.0));
        input.ankles[0] = encoder(STAND_ANKLES[0] + off.max(0.0));
        input.ankle_plan_rad[0] = STAND_ANKLES[0];
    });
    assert!(quiet(&v));
    // A plan that steps (a swing's table takes over from the standing
    // angle, the stance swaps at a landing) is not the shank moving: the
    // count starts again from the new plan.
    let (_, v) = inject(900, |k, input| {
        input.ankles[0] = encoder(STAND_ANKLES[0]);
        input.ankle_plan_rad[0] = STAND_ANKLES[0] - if k > 100 { 0.15 } else { 0.0 };
    });
    assert!(quiet(&v));
}

#[test]
fn a_pilot_who_unloads_the_crutches_mid_swing_is_found_at_the_tighter_bound() {
    // A swing's stance shank lagging its plan at 0.5 rad/s while the pilot
    // pushes 200 N more than standing (the bound 0.25 rad), who then lets
    // go of the crutches at tick 150 (0.075 rad off): from then on the
    // bound is 0.05 rad, and 30 frames later it is the pilot falling back.
    // Pushing all along, from before the swing's plan began (the least
    // value outlives the plan), it is found only past 0.25 rad.
    use gait_control::layout::force::LEFT_CRUTCH;
    let cfg = SupervisorConfig::paper().balance;
    let rate = 0.5e-3;
    let run = |let_go: u32| {
        inject(900, move |k, input| {
            // Standing on the start posture's plan until tick 20, then the
            // swing's (a step of 0.02 rad: the track restarts).
            let swing = k >= 20;
            let plan = STAND_ANKLES[0] + if swing { 0.02 } else { 0.0 };
            input.ankles[0] = encoder(plan - rate * k.saturating_sub(20) as f32);
            input.ankle_plan_rad[0] = plan;
            if swing {
                input.swing_leg = Some(gait_control::layout::Side::Right);
            }
            if (10..let_go).contains(&k) {
                input.forces[LEFT_CRUTCH].newtons += 200.0;
            }
        })
        .1
    };
    assert_eq!(
        detected_at(&run(150), FaultCode::PilotFallingBack),
        Some(150 + cfg.ticks - 1)
    );
    let pushing = detected_at(&run(u32::MAX), FaultCode::PilotFallingBack).unwrap();
    let plan = STAND_ANKLES[0] + 0.02;
    let off = |k: u32| plan - encoder(plan - rate * k as f32).angle_rad;
    let beyond = 20 + (1..).find(|&k| off(k) > cfg.pushed.swing_rad).unwrap();
    assert_eq!(pushing, beyond + cfg.ticks - 1);
}

#[test]
fn crutches_that_cannot_be_read_never_tighten_the_bound() {
    // A crutch sensor in error from the plan's start: the pilot's pushing
    // is unknown, so the swing's bound stays 0.25 rad.
    use gait_control::layout::force::RIGHT_CRUTCH;
    let cfg = SupervisorConfig::paper().balance;
    let rate = 0.5e-3;
    let (_, v) = inject(900, |k, input| {
        input.ankles[0] = encoder(STAND_ANKLES[0] + rate * k as f32);
        input.ankle_plan_rad[0] = STAND_ANKLES[0];
        input.swing_leg = Some(gait_control::layout::Side::Right);
        input.forces[RIGHT_CRUTCH].status = ForceStatus::BusError;
    });
    let off = |k: u32| encoder(STAND_ANKLES[0] + rate * k as f32).angle_rad - STAND_ANKLES[0];
    let beyond = (1..).find(|&k| off(k) > cfg.pushed.swing_rad).unwrap();
    assert_eq!(
        detected_at(&v, FaultCode::PilotFallingForward),
        Some(beyond + cfg.ticks - 1)
    );
}

#[test]
fn with_both_feet_down_a_foot_planned_past_its_stop_is_not_watched() {
    // A trailing foot whose plan lifts the heel past the stop (its
    // shank's angle, not an ankle's) and whose ankle reads well below
    // it, moving away: nothing with both feet down; in a swing the same
    // stance ankle is watched.
    let cfg = SupervisorConfig::paper();
    let past = cfg.heel_off_rad + 0.3;
    let run = |swing: bool| {
        inject(600, move |k, input| {
            input.ankles[0] = encoder(STAND_ANKLES[0] - 0.5e-3 * k as f32);
            input.ankle_plan_rad[0] = past;
            if swing {
                input.swing_leg = Some(gait_control::layout::Side::Right);
            }
        })
        .1
    };
    assert_eq!(detected_at(&run(false), FaultCode::PilotFallingBack), None);
    assert!(detected_at(&run(true), FaultCode::PilotFallingBack).is_some());
}
