//! Starting a step: only with a table and from its start posture, and the
//! swing only once the pilot is ready (crutches and feet loaded, the stance
//! shank at the planned angle).

use super::*;

#[test]
fn start_needs_a_table_and_the_start_posture() {
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let (pose, s) = rig.ready();
    assert_eq!(
        rig.start(Gait::StairUp, &s),
        SeqEvent::StartRefused(RefuseReason::NoTable)
    );
    let mut off = pose;
    off[1] += 0.3;
    assert_eq!(
        rig.start(Gait::Walk, &sensed(off, READY_FEET, READY_CRUTCHES)),
        SeqEvent::StartRefused(RefuseReason::NotInStartPosture)
    );
    assert_eq!(
        rig.start(Gait::Walk, &s),
        SeqEvent::StartAccepted(Gait::Walk, Side::Left)
    );
    // The mirrored posture starts with the other leg as stance.
    let mut rig = Rig::new(&img);
    let s = sensed(rig.start_pose(Side::Right), [0.0, 500.0], READY_CRUTCHES);
    assert_eq!(
        rig.start(Gait::Walk, &s),
        SeqEvent::StartAccepted(Gait::Walk, Side::Right)
    );
}

#[test]
fn swing_waits_for_the_stance_shank_at_the_planned_angle() {
    let img = walk_image();
    let (mut rig, pose, _) = started(&img);
    let tol = SequencerConfig::DEFAULT.start_ankle_tolerance_rad;
    // Forces ready, but the body is ahead of the planned start (stance
    // ankle dorsiflexed 0.1 rad more), or its ankle reading is NaN: wait.
    for ankle in [START_ANKLE + 0.1, START_ANKLE - 1.5 * tol, f32::NAN] {
        for _ in 0..200 {
            let mut s = sensed(pose, READY_FEET, READY_CRUTCHES);
            s.ankles_rad[Side::Left.ankle()] = ankle;
            rig.step(&s);
        }
        assert!(
            matches!(rig.seq.phase(), Phase::WaitingReady { .. }),
            "{ankle}"
        );
    }
    // The swing ankle's reading does not matter; the stance one within
    // tolerance starts the swing.
    let mut s = sensed(pose, READY_FEET, READY_CRUTCHES);
    s.ankles_rad[Side::Left.ankle()] = START_ANKLE + 0.8 * tol;
    s.ankles_rad[Side::Right.ankle()] = f32::NAN;
    rig.step(&s);
    assert!(matches!(rig.seq.phase(), Phase::Swing { .. }));
}

#[test]
fn swing_waits_for_crutches_and_the_feet() {
    let img = walk_image();
    let (mut rig, pose, _) = started(&img);
    // One crutch unloaded: keep waiting, however long.
    for _ in 0..2000 {
        rig.step(&sensed(pose, READY_FEET, [100.0, 10.0]));
    }
    assert!(matches!(rig.seq.phase(), Phase::WaitingReady { .. }));
    // The feet together carry too little (the device is not standing on
    // them): keep waiting. Which foot carries how much is the table's plan.
    for _ in 0..100 {
        rig.step(&sensed(pose, [50.0, 100.0], READY_CRUTCHES));
    }
    assert!(matches!(rig.seq.phase(), Phase::WaitingReady { .. }));
    // NaN forces (a faulted sensor) never count as ready.
    rig.step(&sensed(pose, [f32::NAN, 0.0], [f32::NAN, 100.0]));
    assert!(matches!(rig.seq.phase(), Phase::WaitingReady { .. }));
    rig.step(&sensed(pose, READY_FEET, READY_CRUTCHES));
    assert!(matches!(
        rig.seq.phase(),
        Phase::Swing {
            stance: Side::Left,
            ..
        }
    ));
    assert!(
        rig.events
            .contains(&SeqEvent::SwingStarted(Gait::Walk, Side::Left))
    );
}
