//! The swing and its landing: the table played, the landing taken only from
//! the foot sensor in the landing window (a held contact, not a spike),
//! blind, after a ground search, or timed out; a stop at the landing.

use super::*;

#[test]
fn swing_plays_the_table_and_lands_on_the_foot_sensor() {
    let img = walk_image();
    let (mut rig, _, _) = started(&img);
    // An early scuff at 20 % of the step is not a landing.
    let scuff = 0.2 * rig.table.duration_s();
    let trace = swing_and_land(&mut rig, Side::Left, Some(scuff));
    assert!(rig.events.contains(&SeqEvent::Landed));
    let n = trace.len() as f32 * DT;
    assert!(n >= rig.table.duration_s() - 0.01, "landed after {n} s");
    // Mid-swing the reference is the table, mapped with the left leg standing.
    let mid = trace[trace.len() / 2];
    let t_mid = (trace.len() / 2) as f32 * DT;
    let want = joints_from_phi(&rig.table.at_time(t_mid - DT), Side::Left);
    for i in 0..JOINTS {
        assert!(
            (mid[i] - want[i]).abs() < 2e-3,
            "joint {i}: {} vs {}",
            mid[i],
            want[i]
        );
    }
    // After landing the legs swap: transfer with the right leg standing, then
    // wait at the next start posture.
    assert!(matches!(
        rig.seq.phase(),
        Phase::Transfer {
            stance: Side::Right,
            ..
        }
    ));
    let right_pose = rig.start_pose(Side::Right);
    for _ in 0..1000 {
        rig.step(&sensed(right_pose, [0.0, 500.0], [10.0, 10.0]));
    }
    assert!(matches!(
        rig.seq.phase(),
        Phase::WaitingReady {
            stance: Side::Right
        }
    ));
    let r = rig.seq.reference();
    for i in 0..JOINTS {
        assert!((r[i] - right_pose[i]).abs() < 1e-5);
    }
}

#[test]
fn stop_request_ends_at_the_landing_and_no_gait_change_mid_step() {
    let img = walk_image();
    let (mut rig, _, s) = started(&img);
    rig.step(&s);
    assert!(rig.seq.status().step_in_progress());
    assert_eq!(
        rig.start(Gait::Walk, &s),
        SeqEvent::StartRefused(RefuseReason::Busy)
    );
    rig.request = Some(SeqRequest::StopAfterStep);
    swing_and_land(&mut rig, Side::Left, None);
    assert_eq!(rig.seq.phase(), Phase::Standing);
    assert!(rig.events.contains(&SeqEvent::Stopped));
    // It holds the landing posture.
    let held = rig.seq.reference();
    for _ in 0..500 {
        let r = rig.step(&s);
        assert_eq!(r, held);
    }
}

#[test]
fn landing_timeout_holds_the_posture() {
    let img = walk_image();
    let (mut rig, _, s) = started(&img);
    let steps =
        ((rig.table.duration_s() + SequencerConfig::DEFAULT.landing_timeout_s + 0.2) / DT) as usize;
    for _ in 0..steps {
        rig.step(&s); // the swing foot never reports contact
    }
    assert!(rig.events.contains(&SeqEvent::LandingTimeout));
    assert_eq!(rig.seq.phase(), Phase::Standing);
}

#[test]
fn a_blind_swing_foot_lands_once_it_has_had_time_to_follow_the_table() {
    // The swing foot's sensor is lost (NaN) from mid-swing: the step counts
    // as landed `blind_landing_settle_s` after the table's end, not at the
    // end itself (the foot lags its reference and was still above a stair's
    // tread), holding the table's last posture in between.
    let img = walk_image();
    let (mut rig, _, s) = started(&img);
    let mut blind = s;
    blind.feet_n[Side::Right.foot()] = f32::NAN;
    let duration = rig.table.duration_s();
    let settle = SequencerConfig::DEFAULT.blind_landing_settle_s;
    assert!(settle > 0.1, "{settle}");
    // The ground search has not begun: the table's last posture is held.
    assert!(SequencerConfig::DEFAULT.ground_search_after_s > settle);
    let last = joints_from_phi(&rig.table.at_time(duration), Side::Left);
    let mut landed_at = None;
    let mut n = 0usize;
    while landed_at.is_none() && n < 5000 {
        let sensed_now = if n < 1000 { s } else { blind };
        let r = rig.step(&sensed_now);
        n += 1;
        let t = n as f32 * DT;
        if matches!(rig.seq.phase(), Phase::Swing { .. }) && t > duration + 0.01 {
            for i in 0..JOINTS {
                assert!((r[i] - last[i]).abs() < 1e-4, "at {t} s joint {i}");
            }
        }
        if rig.events.contains(&SeqEvent::Landed) {
            landed_at = Some(t);
        }
    }
    let t = landed_at.expect("never landed");
    assert!(
        (t - (duration + settle)).abs() <= 2.5 * DT,
        "landed at {t} s, the table ends at {duration} s"
    );
    assert!(matches!(rig.seq.phase(), Phase::Transfer { .. }));
}

/// The swing ankle's height above the stance ankle for joint angles `j`
/// (stance left, the table's stance shank `phi1`), m.
fn swing_ankle_height(model: &BodyModel<f32>, j: &[f32; JOINTS], phi1: f32) -> f32 {
    swing_ankle(model, j, phi1)[1]
}

#[test]
fn a_swing_that_ends_without_contact_lowers_the_foot_until_it_lands() {
    let img = walk_image();
    let (mut rig, model, s, pose) = started_with_a_model(&img);
    let end_phi1 = rig.table.at_time(rig.table.duration_s())[0];
    let cfg = SequencerConfig::DEFAULT;
    // Play to the table's end with no contact: the table's last posture.
    let mut at_end = None;
    let mut heights = Vec::new();
    for _ in 0..20_000 {
        let r = rig.step(&s);
        if let Phase::Swing { t_s, .. } = rig.seq.phase() {
            if t_s <= rig.table.duration_s() {
                at_end = Some(r);
            } else {
                heights.push(swing_ankle_height(&model, &r, end_phi1));
            }
            if t_s > rig.table.duration_s() + cfg.ground_search_after_s + cfg.ground_search_s + 0.1
            {
                break;
            }
        }
    }
    let end = swing_ankle_height(&model, &at_end.unwrap(), end_phi1);
    // Down, never up, smoothly, by the configured depth at most.
    let lowest = heights.iter().copied().fold(f32::INFINITY, f32::min);
    assert!(heights.windows(2).all(|w| w[1] <= w[0] + 1e-6));
    assert!(
        heights
            .windows(2)
            .all(|w| (w[0] - w[1]) / DT <= 1.6 * cfg.ground_search_depth_m / cfg.ground_search_s),
        "faster than the search's eased speed"
    );
    // As deep as configured, or until the swing knee (right) is nearly
    // straight (this table lands with its knee nearly straight).
    let depth = end - lowest;
    let knee = rig.seq.reference()[3];
    assert!(
        depth > 0.005 && depth <= cfg.ground_search_depth_m + 1e-4,
        "{depth}"
    );
    assert!(
        depth >= cfg.ground_search_depth_m - 1e-4 || (knee - 0.1).abs() < 0.005,
        "stopped at {depth} m with the knee at {knee} rad"
    );
    assert!(rig.events.iter().all(|e| *e != SeqEvent::LandingTimeout));
    // The ground felt, and held for the landing's confirmation: the step
    // lands where the foot has got to.
    let before = rig.events.len();
    let confirm_ticks = (cfg.landing_confirm_s / DT).round() as usize;
    for tick in 1..=confirm_ticks {
        rig.step(&sensed(pose, [500.0, 200.0], READY_CRUTCHES));
        assert_eq!(
            rig.events[before..].contains(&SeqEvent::Landed),
            tick == confirm_ticks,
            "tick {tick} of {confirm_ticks}: {:?}",
            rig.events
        );
    }
    assert!(matches!(rig.seq.phase(), Phase::Transfer { .. }));
}

#[test]
fn a_force_spike_late_in_the_swing_is_not_a_landing() {
    let img = walk_image();
    let (mut rig, _model, s, pose) = started_with_a_model(&img);
    let cfg = SequencerConfig::DEFAULT;
    let confirm_ticks = (cfg.landing_confirm_s / DT).round() as usize;
    assert!(confirm_ticks > 3, "the campaign's spikes last 3 ms");
    // Into the landing window: 90 % of the table.
    for _ in 0..20_000 {
        if matches!(rig.seq.phase(), Phase::Swing { t_s, .. } if t_s > 0.9 * rig.table.duration_s())
        {
            break;
        }
        rig.step(&s);
    }
    assert!(matches!(rig.seq.phase(), Phase::Swing { .. }));
    // The swing foot's sensor (right) reads 400 N for 3 ticks, and again
    // for one tick short of the confirmation after a gap of one tick.
    let spike = sensed(pose, [500.0, 400.0], READY_CRUTCHES);
    for n in [3, confirm_ticks - 1] {
        for _ in 0..n {
            rig.step(&spike);
        }
        rig.step(&s);
    }
    assert!(!rig.events.contains(&SeqEvent::Landed), "{:?}", rig.events);
    assert!(matches!(rig.seq.phase(), Phase::Swing { .. }));
    // Held contact lands.
    for _ in 0..confirm_ticks {
        rig.step(&spike);
    }
    assert!(rig.events.contains(&SeqEvent::Landed), "{:?}", rig.events);
}

#[test]
fn without_a_model_a_swing_holds_the_tables_end_until_the_timeout() {
    let img = walk_image();
    let (mut rig, _, s) = started(&img);
    let end = joints_from_phi(&rig.table.at_time(rig.table.duration_s()), Side::Left);
    for _ in 0..20_000 {
        let r = rig.step(&s);
        if let Phase::Swing { t_s, .. } = rig.seq.phase() {
            if t_s > rig.table.duration_s() + 0.5 {
                assert_eq!(r, end);
                break;
            }
        }
    }
}

#[test]
fn the_swing_foot_is_surely_in_the_air_only_in_its_landing_window() {
    // Early in a swing the trailing toe may still hold the ground (and its
    // ankle on the stop); from the landing window on the table has the
    // foot well up: only then the supervisor's stuck-ankle check runs.
    let img = walk_image();
    let (mut rig, _model, s, _pose) = started_with_a_model(&img);
    let window = SequencerConfig::DEFAULT.landing_window_fraction * rig.table.duration_s();
    let (mut early, mut late) = (0, 0);
    for _ in 0..20_000 {
        rig.step(&s);
        match rig.seq.phase() {
            Phase::Swing { t_s, .. } if t_s < window => {
                assert_eq!(rig.seq.status().swing_leg, Some(Side::Right));
                assert_eq!(rig.seq.status().airborne_leg, None, "{t_s} s");
                early += 1;
            }
            Phase::Swing { t_s, .. } => {
                if rig.seq.status().airborne_leg.is_some() {
                    assert_eq!(rig.seq.status().airborne_leg, Some(Side::Right), "{t_s} s");
                    late += 1;
                }
            }
            _ if early > 0 => break,
            _ => assert_eq!(rig.seq.status().airborne_leg, None),
        }
    }
    assert!(
        early > 100 && late > 100,
        "{early} early, {late} late ticks"
    );
    rig.hold(rig.seq.reference(), InSwing::HoldNow);
    rig.step(&s);
    assert_eq!(rig.seq.status().airborne_leg, None, "a hold plays no table");
}
