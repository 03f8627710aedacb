//! Holds: the safe hold (ramped, or landing the step first, or at once),
//! a finish-the-step block, the swing foot set down until it feels the
//! ground, joints held in place, and the hold after a restart.

use super::*;

#[test]
fn safe_hold_ramps_to_the_measured_posture_and_blocks_starts() {
    let img = walk_image();
    let (mut rig, s) = walking_in_a_swing(&img);
    let measured = [0.3, 0.2, 0.1, 0.4];
    let before = rig.seq.reference();
    // The controller asks for the hold every tick while the fault is
    // latched. In a swing the step lands first, then the hold begins.
    let mut last = before;
    let mut max_step = 0.0f32;
    let mut phases = Vec::new();
    // The swing plays on, times out its landing (no contact here), stands,
    // then holds.
    let ticks =
        ((rig.table.duration_s() + SequencerConfig::DEFAULT.landing_timeout_s) / DT) as usize;
    for _ in 0..ticks {
        rig.hold(measured, InSwing::LandFirst);
        let r = rig.step(&sensed(measured, READY_FEET, READY_CRUTCHES));
        for i in 0..JOINTS {
            max_step = max_step.max((r[i] - last[i]).abs());
        }
        last = r;
        let kind = std::mem::discriminant(&rig.seq.phase());
        if phases.last() != Some(&kind) {
            phases.push(kind);
        }
    }
    let swing = std::mem::discriminant(&Phase::Swing {
        stance: Side::Left,
        t_s: 0.0,
    });
    let hold = std::mem::discriminant(&Phase::SafeHold { t_s: 0.0 });
    assert_eq!(phases.first(), Some(&swing), "the swing went on");
    assert_eq!(phases.last(), Some(&hold), "then held");
    assert!(
        !phases.contains(&std::mem::discriminant(&Phase::Transfer {
            stance: Side::Left,
            t_s: 0.0
        })),
        "no weight transfer after the landing: {phases:?}"
    );
    for i in 0..JOINTS {
        assert!((last[i] - measured[i]).abs() < 1e-6);
    }
    // Ramped: no jump bigger than the smoothstep's steepest tick.
    assert!(
        max_step < 0.02,
        "reference jumped {max_step} rad in one tick"
    );
    assert_eq!(
        rig.start(Gait::Walk, &s),
        SeqEvent::StartRefused(RefuseReason::Busy)
    );
    rig.request = Some(SeqRequest::ResetAfterFaults);
    rig.step(&s);
    assert_eq!(rig.seq.phase(), Phase::Standing);
}

#[test]
fn a_safe_hold_for_a_motor_fault_holds_a_swing_at_once() {
    let img = walk_image();
    let (mut rig, s) = walking_in_a_swing(&img);
    rig.hold([0.3, 0.2, 0.1, 0.4], InSwing::HoldNow);
    rig.step(&s);
    assert!(matches!(rig.seq.phase(), Phase::SafeHold { .. }));
}

#[test]
fn late_in_a_swing_a_hold_lands_the_step_while_the_stance_knee_works() {
    // From `lands_after` of the swing on (here 0.6 of the walk's), a hold
    // that would stop the swing plays it on to its landing, unless the
    // stance knee is braked: it is what lowers the body onto the foot.
    let img = walk_image();
    let mut cfg = SequencerConfig::DEFAULT;
    cfg.lands_after = [0.6, 1.0, 1.0];
    let (mut rig, _, s) = Rig::with_config(&img, cfg).walking();
    let none = [false; JOINTS];
    let mut stance_knee = [false; JOINTS];
    stance_knee[Side::Left.hip() + 1] = true;
    let mut swing_knee = [false; JOINTS];
    swing_knee[Side::Right.hip() + 1] = true;
    assert_eq!(
        rig.seq.status().in_swing_now(InSwing::HoldNow, &none),
        InSwing::HoldNow
    );
    let duration = rig.table.duration_s();
    let mut seen = (false, false);
    for _ in 0..(3.0 / DT) as usize {
        rig.step(&s);
        let Phase::Swing { t_s, .. } = rig.seq.phase() else {
            continue;
        };
        let now = rig.seq.status().in_swing_now(InSwing::HoldNow, &none);
        if t_s < 0.59 * duration {
            assert_eq!(now, InSwing::HoldNow, "{t_s} s");
            seen.0 = true;
        } else if t_s > 0.61 * duration {
            assert_eq!(now, InSwing::LandFirst, "{t_s} s");
            assert_eq!(
                rig.seq.status().in_swing_now(InSwing::HoldNow, &swing_knee),
                InSwing::LandFirst
            );
            assert_eq!(
                rig.seq
                    .status()
                    .in_swing_now(InSwing::HoldNow, &stance_knee),
                InSwing::HoldNow
            );
            seen.1 = true;
        }
    }
    assert_eq!(seen, (true, true), "the swing was seen early and late");
    // The shipped configuration's walk never lands first this way.
    let (rig, _) = walking_in_a_swing(&img);
    assert_eq!(
        rig.seq.status().in_swing_now(InSwing::HoldNow, &none),
        InSwing::HoldNow
    );
}

#[test]
fn non_fatal_block_finishes_the_step_then_refuses_new_ones() {
    let img = walk_image();
    let (mut rig, pose, s) = started(&img);
    rig.step(&s);
    rig.order(Order::FinishStepThenHold, pose);
    assert!(rig.seq.status().step_in_progress(), "the step goes on");
    swing_and_land(&mut rig, Side::Left, None);
    assert_eq!(rig.seq.phase(), Phase::Standing);
    let s2 = sensed(rig.start_pose(Side::Right), [0.0, 500.0], READY_CRUTCHES);
    assert_eq!(
        rig.start(Gait::Walk, &s2),
        SeqEvent::StartRefused(RefuseReason::Busy)
    );
}

#[test]
fn a_safe_hold_in_a_swing_sets_the_foot_down_until_it_feels_the_ground() {
    let img = walk_image();
    let (mut rig, model, s, pose) = started_with_a_model(&img);
    // Into the middle of the swing.
    let mut held = pose;
    let mut phi1 = f32::NAN;
    for _ in 0..20_000 {
        held = rig.step(&s);
        if let Phase::Swing { t_s, .. } = rig.seq.phase() {
            if t_s >= 0.5 * rig.table.duration_s() {
                phi1 = rig.table.at_time(t_s)[0];
                break;
            }
        }
    }
    assert!(phi1.is_finite());
    rig.hold(held, InSwing::HoldNow);
    let in_air = sensed(held, READY_FEET, READY_CRUTCHES);
    rig.step(&in_air);
    assert!(matches!(rig.seq.phase(), Phase::SafeHold { .. }));
    assert_eq!(
        rig.seq.status().swing_leg,
        Some(Side::Right),
        "moved as a swing leg"
    );
    let cfg = SequencerConfig::DEFAULT;
    let start = swing_ankle(&model, &held, phi1);
    let mut heights = Vec::new();
    for _ in 0..(0.5 * cfg.set_down_s / DT) as usize {
        let last = rig.step(&in_air);
        let a = swing_ankle(&model, &last, phi1);
        // Straight down while the leg reaches.
        assert!((a[0] - start[0]).abs() < 1e-4, "{a:?} from {start:?}");
        heights.push(a[1]);
        // The stance leg holds what was measured.
        assert!((last[0] - held[0]).abs() < 1e-5 && (last[1] - held[1]).abs() < 1e-5);
    }
    assert!(
        heights.windows(2).all(|w| w[1] <= w[0] + 1e-6),
        "down, never up"
    );
    let speed = heights
        .windows(2)
        .map(|w| (w[0] - w[1]) / DT)
        .fold(0.0, f32::max);
    assert!(
        speed <= 1.5 * cfg.set_down_depth_m / cfg.set_down_s + 1e-3,
        "{speed} m/s"
    );
    let depth = start[1] - heights.last().copied().unwrap_or(start[1]);
    assert!(depth > 0.03, "went down {depth} m");
    // The ground felt: the foot stays where it is, a stance leg's again.
    let contact = sensed(held, [500.0, 150.0], READY_CRUTCHES);
    let at_contact = rig.step(&contact);
    assert_eq!(rig.seq.status().swing_leg, None);
    for _ in 0..2_000 {
        assert_eq!(rig.step(&contact), at_contact);
        // Lifting off again does not restart it.
        assert_eq!(rig.step(&in_air), at_contact);
    }
    assert!(matches!(rig.seq.phase(), Phase::SafeHold { .. }));
}

#[test]
fn a_hold_on_a_swing_s_first_tick_sets_the_foot_down_as_on_any_swing() {
    // The set-down's frame is built on the stance shank the step plays:
    // on a swing's first tick that is its first sample's, the same on the
    // run's first swing (where there was none before) and on its third
    // (not the last swing's landing, a frame turned by the step's whole
    // stance-shank travel), both left stance from the same posture.
    let img = walk_image();
    let set_down = |swings_before: usize| {
        let (mut rig, model, s, _) = started_with_a_model(&img);
        let mut stance = Side::Left;
        for _ in 0..swings_before {
            for _ in 0..20_000 {
                rig.step(&s);
                if let Phase::Swing { stance: st, .. } = rig.seq.phase() {
                    stance = st;
                    break;
                }
            }
            assert!(matches!(rig.seq.phase(), Phase::Swing { .. }));
            swing_and_land(&mut rig, stance, None);
            stance = stance.other();
        }
        let mut held = None;
        for _ in 0..20_000 {
            let ready = sensed(rig.start_pose(stance), READY_FEET, READY_CRUTCHES);
            let r = rig.step(&ready);
            if let Phase::Swing { stance: st, t_s } = rig.seq.phase() {
                assert_eq!((st, t_s), (Side::Left, 0.0), "the swing's first tick");
                held = Some(r);
                break;
            }
        }
        let held = held.expect("a swing began");
        rig.hold(held, InSwing::HoldNow);
        let in_air = sensed(held, READY_FEET, READY_CRUTCHES);
        let trace: Vec<_> = (0..(0.5 * SequencerConfig::DEFAULT.set_down_s / DT) as usize)
            .map(|_| rig.step(&in_air))
            .collect();
        let ankle = |j: &[f32; JOINTS]| swing_ankle(&model, j, rig.table.first()[0]);
        let depth = ankle(&held)[1] - trace.last().map_or(f32::NAN, |j| ankle(j)[1]);
        (trace, depth)
    };
    // The trailing leg is at full reach on a swing's first tick: the foot
    // goes down along the leg, a few millimetres, not straight down as
    // from the middle of a swing.
    let (first, depth) = set_down(0);
    assert!(depth > 1e-3, "the first swing's foot went down {depth} m");
    let (third, _) = set_down(2);
    assert_eq!(first, third);
}

#[test]
fn a_swing_foot_carrying_when_the_hold_strikes_ramps_with_the_others() {
    // Early in a stair descent's swing the trailing toe still lowers the
    // body: that foot is not set down, and its leg ramps to the posture
    // measured like the rest, not held there at once (its loaded knee
    // would lose the reference's push in a tick).
    let img = walk_image();
    let (mut rig, _, s, pose) = started_with_a_model(&img);
    let mut last = pose;
    for _ in 0..20_000 {
        last = rig.step(&s);
        if matches!(rig.seq.phase(), Phase::Swing { t_s, .. } if t_s >= 0.3) {
            break;
        }
    }
    // Measured 0.1 rad off the reference at the swing (right) hip and knee.
    let mut measured = last;
    measured[2] += 0.1;
    measured[3] += 0.1;
    rig.hold(measured, InSwing::HoldNow);
    let carrying = sensed(measured, [500.0, 150.0], READY_CRUTCHES);
    let cfg = SequencerConfig::DEFAULT;
    let mut max_step = 0.0f32;
    for _ in 0..(cfg.hold_ramp_s / DT) as usize + 10 {
        let r = rig.step(&carrying);
        assert_eq!(rig.seq.status().swing_leg, None, "no set-down");
        for i in 0..JOINTS {
            max_step = max_step.max((r[i] - last[i]).abs());
        }
        last = r;
    }
    assert!(
        max_step < 0.01,
        "reference jumped {max_step} rad in one tick"
    );
    for i in 0..JOINTS {
        assert!(
            (last[i] - measured[i]).abs() < 1e-6,
            "{last:?} {measured:?}"
        );
    }
}

/// The fastest the set-down moved the swing hip or knee reference, rad/s,
/// with `cfg`, from the middle of the walk's swing, the foot never finding
/// the ground.
fn set_down_joint_speed(img: &[u8], cfg: SequencerConfig) -> f32 {
    let (mut rig, pose, s) = Rig::with_config(img, cfg)
        .with_model(paper_model())
        .walking();
    let mut held = pose;
    for _ in 0..20_000 {
        held = rig.step(&s);
        if matches!(rig.seq.phase(), Phase::Swing { t_s, .. } if t_s >= 0.5 * rig.table.duration_s())
        {
            break;
        }
    }
    rig.hold(held, InSwing::HoldNow);
    let in_air = sensed(held, READY_FEET, READY_CRUTCHES);
    let mut last = rig.step(&in_air);
    let mut fastest = 0.0f32;
    for _ in 0..(1.5 * cfg.set_down_s / DT) as usize {
        let now = rig.step(&in_air);
        for j in [Side::Right.hip(), Side::Right.hip() + 1] {
            fastest = fastest.max((now[j] - last[j]).abs() / DT);
        }
        last = now;
    }
    fastest
}

#[test]
fn the_set_down_moves_the_swing_leg_no_faster_than_its_joint_speed() {
    // Asked to go 60 cm down in 0.4 s, the ankle's target leaves the leg's
    // reach: near a straight knee the IK's answer races; the references
    // move at the set-down's joint speed at most.
    let img = walk_image();
    let mut cfg = SequencerConfig::DEFAULT;
    cfg.set_down_depth_m = 0.6;
    cfg.set_down_s = 0.4;
    let capped = set_down_joint_speed(&img, cfg);
    assert!(
        capped <= cfg.set_down_joint_speed_rad_s * 1.001 && capped > 0.5,
        "{capped} rad/s"
    );
    cfg.set_down_joint_speed_rad_s = f32::INFINITY;
    let free = set_down_joint_speed(&img, cfg);
    assert!(free > 2.0 * capped, "without the cap: {free} rad/s");
}

#[test]
fn a_safe_hold_standing_or_without_a_model_moves_no_foot() {
    let img = walk_image();
    // Without a model: the swing's joints hold what was measured.
    let (mut rig, s) = walking_in_a_swing(&img);
    let measured = rig.seq.reference();
    rig.hold(measured, InSwing::HoldNow);
    assert_eq!(rig.step(&s), measured);
    assert_eq!(rig.seq.status().swing_leg, None);
    for _ in 0..2_000 {
        assert_eq!(rig.step(&s), measured);
    }
    // Standing, with a model: nothing to set down.
    let mut rig = Rig::new(&img).with_model(paper_model());
    let pose = rig.start_pose(Side::Left);
    rig.hold(pose, InSwing::HoldNow);
    for _ in 0..2_000 {
        assert_eq!(rig.step(&sensed(pose, READY_FEET, READY_CRUTCHES)), pose);
    }
}

/// A joint the supervisor holds in place (`Verdict::rehold_joints`) is
/// held where it was measured from then on, the others as before; outside
/// a hold, or for a non-finite angle, nothing changes.
#[test]
fn a_joint_held_in_place_keeps_its_measured_angle_in_the_hold() {
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let (pose, s) = rig.ready();
    rig.rehold(1, 0.9);
    assert_eq!(rig.step(&s), pose, "standing: not a hold, nothing moves");
    rig.hold(pose, InSwing::HoldNow);
    for _ in 0..50 {
        rig.step(&s);
    }
    rig.rehold(1, 0.9);
    rig.rehold(2, f32::NAN);
    let mut want = pose;
    want[1] = 0.9;
    for _ in 0..2_000 {
        assert_eq!(rig.step(&s), want);
    }
}

#[test]
fn after_a_restart_the_foot_found_unloaded_is_set_down() {
    let img = walk_image();
    let model = paper_model();
    let found = [0.4, 0.3, 0.1, 0.6];
    let cases = [
        // Right foot carrying, left unloaded: the left is set down.
        ([0.0, 600.0], Some(Side::Left)),
        ([600.0, 10.0], Some(Side::Right)),
        // Both carrying, or a foot that cannot tell: a plain hold.
        ([400.0, 300.0], None),
        ([f32::NAN, 600.0], None),
        ([0.0, 0.0], None),
    ];
    for (feet, lifted) in cases {
        let mut rig = Rig::new(&img);
        rig.seq = rig.seq.with_model(model).restarted_at(found);
        let s = Sensed {
            joints_rad: found,
            feet_n: feet,
            crutches_n: READY_CRUTCHES,
            ankles_rad: [0.05, 0.05],
        };
        rig.orders.order = Order::HoldWhereFound;
        rig.orders.measured = Measured::of(&s);
        rig.step(&s);
        assert!(matches!(rig.seq.phase(), Phase::SafeHold { .. }));
        assert_eq!(rig.seq.status().swing_leg, lifted, "{feet:?}");
        let mut last = found;
        let mut stance_fed_forward = Side::Left;
        for _ in 0..300 {
            let r = rig.tick(&s);
            last = r.angle_rad;
            stance_fed_forward = r.stance;
        }
        match lifted {
            Some(leg) => {
                let stance = leg.other();
                assert_eq!(stance_fed_forward, stance, "{feet:?}");
                // The stance leg holds; the lifted leg's joints have moved.
                let (sh, lh) = (stance.hip(), leg.hip());
                assert_eq!(&last[sh..sh + 2], &found[sh..sh + 2], "{feet:?}");
                assert!(
                    (last[lh + 1] - found[lh + 1]).abs() > 0.01,
                    "{feet:?}: {last:?}"
                );
            }
            None => assert_eq!(last, found, "{feet:?}"),
        }
    }
}

/// A hold turns the torso back by a leaning stance shank: the stance ankle
/// read ahead of the hold's plan extends both hips (both feet down) by the
/// lean past the deadband, at most at the levelling's rate and by its
/// maximum; the knees keep their hold. A shank back on the plan or behind
/// it brings the hips back, an ankle that cannot tell leaves them, and a
/// hip held in place stays where it was measured.
#[test]
fn a_hold_turns_the_torso_back_by_a_leaning_stance_shank() {
    let img = walk_image();
    let cfg = SequencerConfig::DEFAULT;
    let mut rig = Rig::new(&img);
    let (pose, s) = rig.ready();
    rig.step(&s);
    rig.hold(pose, InSwing::HoldNow);
    for _ in 0..400 {
        assert_eq!(rig.step(&s), pose, "on its plan the shank turns nothing");
    }
    let leaning = |lean: f32| {
        let mut l = s;
        l.ankles_rad[0] = START_ANKLE + lean;
        l
    };
    let levelled = |r: [f32; JOINTS], by: f32| {
        for (i, (&got, &held)) in r.iter().zip(&pose).enumerate() {
            let want = if i % 2 == 0 { held - by } else { held };
            assert!(
                (got - want).abs() < 1e-4,
                "joint {i}: {got} not {want} ({by} back)"
            );
        }
    };
    // 0.2 rad ahead: 0.17 past the deadband, reached at the rate.
    let ticks = |s: f32| (s / DT).round() as usize;
    let mut r = pose;
    for _ in 0..ticks(0.1) {
        r = rig.step(&leaning(0.2));
    }
    levelled(r, 0.1 * cfg.level_rate_rad_s);
    for _ in 0..ticks(0.5) {
        r = rig.step(&leaning(0.2));
    }
    levelled(r, 0.2 - cfg.level_deadband_rad);
    // An ankle that cannot tell leaves the levelling where it is.
    for _ in 0..ticks(0.5) {
        r = rig.step(&leaning(f32::NAN));
    }
    levelled(r, 0.2 - cfg.level_deadband_rad);
    // Far ahead: no further than the maximum.
    for _ in 0..ticks(1.0) {
        r = rig.step(&leaning(0.6));
    }
    levelled(r, cfg.level_max_rad);
    // A hip held in place stays where it was measured.
    rig.rehold(0, pose[0] - 0.3);
    r = rig.step(&leaning(0.6));
    assert!((r[0] - (pose[0] - 0.3)).abs() < 1e-4, "held at {}", r[0]);
    // Behind the plan: back to the hold, at the rate.
    let mut last = r;
    for _ in 0..ticks(1.0) {
        r = rig.step(&leaning(-0.2));
        let moved = (r[2] - last[2]).abs();
        assert!(
            moved <= cfg.level_rate_rad_s * DT + 1e-5,
            "{moved} rad in a tick"
        );
        last = r;
    }
    assert!(
        (r[2] - pose[2]).abs() < 1e-4,
        "right hip {} back at {}",
        r[2],
        pose[2]
    );
    assert!((r[0] - (pose[0] - 0.3 + cfg.level_max_rad)).abs() < 1e-4);
}
