//! Re-planning a step from where the stance ankle is: the sequencer asks
//! the idle-time re-planner through the slot, takes its answer exactly at
//! the latency, plays the re-planned samples, and the table whenever the
//! answer is late, declined, refused or stale.

use gait_control::replan::{ReplanConfig, ReplanOutcome, ReplanResult, ReplanSlot, Ticket};

use super::*;

const RC: ReplanConfig = ReplanConfig::DEFAULT;

/// The stance ankle's offset from the table's start in these tests:
/// beyond the table's own tolerance, within the re-planner's.
const OFF: f32 = 0.06;
const _: () = assert!(OFF > SequencerConfig::DEFAULT.start_ankle_tolerance_rad);
const _: () = assert!(OFF < RC.ankle_tolerance_rad);

/// A walk rig with a re-planner on `slot`, asked to start; its posture.
fn replanning<'t>(img: &'t [u8], slot: &'t ReplanSlot) -> (Rig<'t>, [f32; JOINTS]) {
    let mut rig = Rig::new(img);
    rig.seq = rig.seq.with_replanner(slot, RC);
    let (rig, pose, _) = rig.walking();
    (rig, pose)
}

/// Ready, with the stance (left) ankle at `ankle`.
fn ready_at(pose: [f32; JOINTS], ankle: f32) -> Sensed {
    let mut s = sensed(pose, READY_FEET, READY_CRUTCHES);
    s.ankles_rad[Side::Left.ankle()] = ankle;
    s
}

/// The table's samples with φ1 moved by `d` throughout (a stand-in for the
/// re-planner's answer: any samples the slot holds are what is played).
fn shifted(table: &GaitTable<'_>, d: f32) -> Vec<[f32; 5]> {
    (0..table.len())
        .map(|k| {
            let mut p = table.sample(k).unwrap();
            p[0] += d;
            p
        })
        .collect()
}

/// Ticks until the slot holds a request, taken as the re-planner takes
/// it; its ticket.
fn until_requested(rig: &mut Rig<'_>, slot: &ReplanSlot, s: &Sensed) -> Ticket {
    for _ in 1..=10 {
        rig.step(s);
        if let Some((req, ticket)) = slot.take_request() {
            assert_eq!(req.stance, Side::Left);
            assert_eq!(req.slot, 0);
            assert_eq!(req.phi1_rad, s.ankles_rad[0]);
            return ticket;
        }
    }
    panic!("no request");
}

#[test]
fn a_replanned_step_is_played_exactly_at_the_latency() {
    let img = walk_image();
    let slot = ReplanSlot::new();
    let (mut rig, pose) = replanning(&img, &slot);
    let ankle = START_ANKLE + OFF;
    let s = ready_at(pose, ankle);
    let ticket = until_requested(&mut rig, &slot, &s);
    let answer = shifted(&rig.table, OFF);
    assert!(slot.publish(ticket, ReplanOutcome::Replanned, &answer));
    // Answered at once, but taken only at the latency.
    for _ in 1..RC.latency_ticks {
        rig.step(&s);
        assert!(matches!(rig.seq.phase(), Phase::WaitingReady { .. }));
    }
    let first = rig.tick(&s);
    assert!(matches!(rig.seq.phase(), Phase::Swing { .. }));
    assert!(
        rig.events
            .contains(&SeqEvent::Replan(ReplanResult::Answered(
                ReplanOutcome::Replanned
            )))
    );
    assert_eq!(first.angle_rad, joints_from_phi(&answer[0], Side::Left));
    // 0.3 s into the swing the reference is the answer's sample 30, not
    // the table's.
    let mut r = first;
    for _ in 0..300 {
        r = rig.tick(&s);
    }
    let played = joints_from_phi(&answer[30], Side::Left);
    for (a, b) in r.angle_rad.iter().zip(&played) {
        assert!((a - b).abs() < 1e-5, "{:?} vs {:?}", r.angle_rad, played);
    }
    let motion = r.motion.unwrap();
    assert!((motion.phi[0] - answer[30][0]).abs() < 1e-5);
}

#[test]
fn late_declined_or_stale_answers_play_the_table_where_the_ankle_allows() {
    let img = walk_image();
    let within = START_ANKLE + 0.5 * SequencerConfig::DEFAULT.start_ankle_tolerance_rad;
    let beyond = START_ANKLE + OFF;
    for (case, ankle, answer) in [
        ("late", within, None),
        ("declined", within, Some(ReplanOutcome::Declined)),
        ("refused", within, Some(ReplanOutcome::Refused)),
        ("late, beyond the table", beyond, None),
    ] {
        let slot = ReplanSlot::new();
        let (mut rig, pose) = replanning(&img, &slot);
        let s = ready_at(pose, ankle);
        let ticket = until_requested(&mut rig, &slot, &s);
        if let Some(outcome) = answer {
            assert!(slot.publish(ticket, outcome, &[]));
        }
        for _ in 0..RC.latency_ticks {
            rig.step(&s);
        }
        let expected = match answer {
            Some(o) => ReplanResult::Answered(o),
            None => ReplanResult::Late,
        };
        assert!(rig.events.contains(&SeqEvent::Replan(expected)), "{case}");
        if ankle == within {
            assert!(matches!(rig.seq.phase(), Phase::Swing { .. }), "{case}");
            let r = rig.tick(&s);
            let table = joints_from_phi(&rig.table.at_time(0.001), Side::Left);
            for (a, b) in r.angle_rad.iter().zip(&table) {
                assert!((a - b).abs() < 1e-5, "{case}");
            }
        } else {
            // Still waiting, and asking again from where the ankle is.
            assert!(matches!(rig.seq.phase(), Phase::WaitingReady { .. }));
            rig.step(&s);
            assert!(slot.take_request().is_some(), "{case}");
        }
    }
    // An answer for an ankle that has since moved is not played.
    let slot = ReplanSlot::new();
    let (mut rig, pose) = replanning(&img, &slot);
    let ticket = until_requested(&mut rig, &slot, &ready_at(pose, beyond));
    assert!(slot.publish(ticket, ReplanOutcome::Replanned, &shifted(&rig.table, OFF)));
    let moved = ready_at(pose, beyond + 1.5 * RC.ankle_drift_rad);
    for _ in 0..RC.latency_ticks {
        rig.step(&moved);
    }
    assert!(matches!(rig.seq.phase(), Phase::WaitingReady { .. }));
}

#[test]
fn a_request_is_withdrawn_when_the_pilot_unloads_and_never_made_beyond_reach() {
    let img = walk_image();
    let slot = ReplanSlot::new();
    let (mut rig, pose) = replanning(&img, &slot);
    // Beyond the re-planner's reach: no request, the step waits.
    let far = ready_at(pose, START_ANKLE + 1.5 * RC.ankle_tolerance_rad);
    for _ in 0..200 {
        rig.step(&far);
    }
    assert!(slot.take_request().is_none());
    assert!(matches!(rig.seq.phase(), Phase::WaitingReady { .. }));
    // Asked for, then the crutches unload: the request is withdrawn, and a
    // re-planner still working on it cannot publish.
    let s = ready_at(pose, START_ANKLE + OFF);
    rig.step(&s);
    let (_, ticket) = slot.take_request().unwrap();
    let mut unloaded = s;
    unloaded.crutches_n = [0.0; 2];
    rig.step(&unloaded);
    assert!(!slot.still_wanted(ticket));
    assert!(!slot.publish(ticket, ReplanOutcome::Replanned, &shifted(&rig.table, OFF)));
}

#[test]
fn the_selected_tables_samples_are_played_when_a_movement_has_several() {
    // Two walk tables: the second one's samples shifted, selected by slot.
    let img = walk_image();
    let first = GaitTable::parse(&img).unwrap();
    let other: Vec<[f32; 5]> = shifted(&first, 0.01);
    let mut img2 = vec![0u8; image_len(other.len())];
    encode(
        GaitKind::Walk,
        10_000,
        first.ik_options(),
        &other,
        &mut img2,
    )
    .unwrap();
    let second = GaitTable::parse(&img2).unwrap();
    let list = [Some(first), Some(second)];
    let tables = GaitTables::in_order(&list);
    let start = joints_from_phi(&second.first(), Side::Left);
    let mut seq = Sequencer::new(SequencerConfig::DEFAULT, tables, start);
    let choice = gait_control::operator::GaitChoice {
        kind: Gait::Walk,
        slot: 1,
        flashes: 2,
    };
    let mut s = sensed(start, READY_FEET, READY_CRUTCHES);
    s.ankles_rad = [second.first()[0]; 2];
    let mut request = Some(SeqRequest::Start(choice));
    let mut last = None;
    for _ in 0..302 {
        let r = seq.update(&SeqInput {
            sensed: &s,
            selected: choice,
            request: request.take(),
            orders: &Orders::NONE,
            braked: &[false; JOINTS],
            hold_joint_at: None,
            restart: false,
            dt_s: DT,
            ahead: None,
        });
        last = Some(r);
    }
    assert!(matches!(seq.phase(), Phase::Swing { .. }));
    let phi = last.unwrap().motion.unwrap().phi;
    let t = match seq.phase() {
        Phase::Swing { t_s, .. } => t_s,
        _ => unreachable!(),
    };
    let expected = second.at_time(t);
    assert!(
        (phi[0] - expected[0]).abs() < 1e-6,
        "{phi:?} vs {expected:?}"
    );
}

#[test]
fn a_pilot_on_the_plan_steps_at_once_without_a_request() {
    let img = walk_image();
    let slot = ReplanSlot::new();
    let (mut rig, pose) = replanning(&img, &slot);
    rig.step(&ready_at(pose, START_ANKLE + 0.5 * RC.min_offset_rad));
    assert!(matches!(rig.seq.phase(), Phase::Swing { .. }));
    assert!(slot.take_request().is_none());
    assert!(!rig.events.iter().any(|e| matches!(e, SeqEvent::Replan(_))));
}

/// The stance hip's residual limit a table carries (0x0404) is the one a
/// step played from it is checked with; a re-planned step, which the
/// generator did not measure, is checked with the device's.
#[test]
fn a_table_s_step_carries_its_stance_hip_limit_and_a_replanned_one_the_device_s() {
    let img = walk_image();
    let table = GaitTable::parse(&img)
        .unwrap()
        .with_stance_hip_residual_nm(70);
    let slot = ReplanSlot::new();
    let start = |ankle: f32| {
        let mut rig = Rig::with_table(table, SequencerConfig::DEFAULT);
        rig.seq = rig.seq.with_replanner(&slot, RC);
        let (mut rig, pose, _) = rig.walking();
        let s = ready_at(pose, ankle);
        if let Some(ticket) = (ankle != START_ANKLE).then(|| until_requested(&mut rig, &slot, &s)) {
            assert!(slot.publish(ticket, ReplanOutcome::Replanned, &shifted(&table, OFF)));
        }
        for _ in 0..=RC.latency_ticks {
            rig.step(&s);
            if matches!(rig.seq.phase(), Phase::Swing { .. }) {
                return rig.seq.stance_hip_residual_nm();
            }
        }
        panic!("no swing");
    };
    assert_eq!(start(START_ANKLE), 70.0);
    assert!(start(START_ANKLE + OFF).is_nan());
}

#[test]
fn a_hold_withdraws_the_request() {
    let img = walk_image();
    let slot = ReplanSlot::new();
    let (mut rig, pose) = replanning(&img, &slot);
    let s = ready_at(pose, START_ANKLE + OFF);
    let ticket = until_requested(&mut rig, &slot, &s);
    // A safe hold while the re-planner works: the request is withdrawn,
    // its answer is not published, and no step starts from it.
    rig.hold(pose, InSwing::HoldNow);
    rig.step(&s);
    assert!(!slot.still_wanted(ticket));
    assert!(!slot.publish(ticket, ReplanOutcome::Replanned, &shifted(&rig.table, OFF)));
    for _ in 0..RC.latency_ticks {
        rig.step(&s);
    }
    assert!(matches!(rig.seq.phase(), Phase::SafeHold { .. }));
    assert!(!rig.events.iter().any(|e| matches!(e, SeqEvent::Replan(_))));
}

#[test]
fn an_answer_counts_only_for_the_request_it_was_worked_on() {
    let slot = ReplanSlot::new();
    let request = |phi1_rad: f32| gait_control::replan::ReplanRequest {
        slot: 0,
        stance: Side::Left,
        phi1_rad,
        joints_rad: [0.0; JOINTS],
        persist: RC.persist,
    };
    slot.request(&request(0.1));
    let (_, old) = slot.take_request().unwrap();
    // The tick withdraws it and asks again; the re-planner takes the new
    // one before the old answer is out.
    slot.release();
    slot.request(&request(0.2));
    let (taken, new) = slot.take_request().unwrap();
    assert_eq!(taken.phi1_rad, 0.2);
    assert!(!slot.publish(old, ReplanOutcome::Replanned, &[[0.0; 5]; 4]));
    assert!(slot.publish(new, ReplanOutcome::Declined, &[]));
    assert_eq!(
        slot.view(),
        gait_control::replan::SlotView::Done(ReplanOutcome::Declined)
    );
}

#[test]
fn a_hold_on_a_replanned_step_s_first_tick_sets_the_foot_down_in_that_step_s_frame() {
    // The set-down's frame is the stance shank of the step played: a
    // re-planned step's first sample (here `OFF` from the table's start),
    // as if those samples were the table.
    let img = walk_image();
    let table = GaitTable::parse(&img).unwrap();
    let answer = shifted(&table, OFF);
    let mut answer_img = vec![0u8; image_len(answer.len())];
    encode(
        GaitKind::Walk,
        10_000,
        table.ik_options(),
        &answer,
        &mut answer_img,
    )
    .unwrap();
    let ankle = START_ANKLE + OFF;
    // The foot set down from a hold on the swing's first tick, the rig
    // ticked by `to_swing` until then.
    let set_down = |mut rig: Rig<'_>, to_swing: &mut dyn FnMut(&mut Rig<'_>) -> [f32; JOINTS]| {
        let held = to_swing(&mut rig);
        assert!(
            matches!(rig.seq.phase(), Phase::Swing { t_s, .. } if t_s == 0.0),
            "the swing's first tick"
        );
        rig.hold(held, InSwing::HoldNow);
        let in_air = sensed(held, READY_FEET, READY_CRUTCHES);
        let trace: Vec<_> = (0..200).map(|_| rig.step(&in_air)).collect();
        (held, trace)
    };
    let slot = ReplanSlot::new();
    let mut replanned = Rig::new(&img).with_model(paper_model());
    replanned.seq = replanned.seq.with_replanner(&slot, RC);
    let (replanned, pose, _) = replanned.walking();
    let s = ready_at(pose, ankle);
    let (held, from_replan) = set_down(replanned, &mut |rig| {
        let ticket = until_requested(rig, &slot, &s);
        assert!(slot.publish(ticket, ReplanOutcome::Replanned, &answer));
        (1..=RC.latency_ticks).map(|_| rig.step(&s)).last().unwrap()
    });
    assert_eq!(held, joints_from_phi(&answer[0], Side::Left));
    let (planned, pose, _) = Rig::new(&answer_img).with_model(paper_model()).walking();
    let s = ready_at(pose, ankle);
    let (_, from_table) = set_down(planned, &mut |rig| {
        for _ in 0..10 {
            let r = rig.step(&s);
            if matches!(rig.seq.phase(), Phase::Swing { .. }) {
                return r;
            }
        }
        panic!("no swing");
    });
    let down = |j: &[f32; JOINTS]| -> f32 {
        let phi = gait_control::posture::phi_from_joints(j, answer[0][0], Side::Left);
        gait_core::kinematics::forward_kinematics(&paper_model(), &phi)[4][1]
    };
    let depth = down(&held) - down(from_replan.last().unwrap());
    assert!(depth > 1e-3, "went down {depth} m");
    assert_eq!(from_replan, from_table);
}
