//! The e-stop and a panic in the closed loop: the drives' brakes, not
//! limp joints; a swing foot set down before the drives go off; a restart
//! into a hold of the posture found.

use exogait_device::DeviceConfig;
use gait_control::faults::{FaultCode, Reaction};
use gait_control::operator::Gait;
use gait_control::sequencer::Phase;
use sim::outcome::outcome;

use super::{run, run_faulted};

#[test]
fn a_panic_resets_the_board_into_a_hold_of_the_posture_it_finds() {
    // Standing, in the weight transfer, early, mid and late in the swing
    // (the walk's first swing runs 1.36–3.54 s): the board is off for the
    // boot (motors limp), then holds with 0x0603 latched, and nobody falls.
    // Late in a swing the foot found in the air is set down first, so the
    // hold stands on two feet, not on the one leg. Late in a stair
    // descent's swing (3.2 s) the restart has lost the step, which a hold
    // from any other fault there plays on to its landing; the set-down
    // alone keeps the pilot up there, the simulated pilot restarting his
    // push from the set-down foot's shank when it lands (docs/safety.md,
    // "If a panic happens anyway"; docs/campaign.md).
    for gait in [Gait::Walk, Gait::StairUp, Gait::StairDown] {
        for at in [0.5, 1.2, 1.6, 2.0, 2.4, 2.8, 3.2] {
            let o = run(gait, 3, at + 3.0, None, &[&format!("panic@{at}")]);
            assert!(o.fell.is_none(), "{gait:?}, panic at {at} s: {o:?}");
            let restart = o
                .faults
                .iter()
                .find(|f| f.code == FaultCode::RestartedAfterPanic)
                .unwrap_or_else(|| panic!("{gait:?}, panic at {at} s: no 0x0603: {o:?}"));
            let boot_s = sim::inject::DEFAULT_BOOT_MS * 1e-3;
            assert!(
                (restart.detected_s - at - boot_s).abs() < 2e-3,
                "{gait:?}, panic at {at} s: restarted at {} s",
                restart.detected_s
            );
        }
    }
}

#[test]
fn motors_disabled_brake_the_joints_instead_of_letting_them_go_limp() {
    // The e-stop in mid-swing and late in it, on every gait (in a swing
    // the swing foot is set down first, then the drives are disabled).
    // With the device's dynamic brake (its full 375 N·m·s/rad) nobody
    // falls and no hip or knee reaches a stop; the same device without
    // the brake lets the joints go limp: with the campaign's pilot, who
    // meets the hold 0.15 s late, 1 of these 12 runs falls and 8
    // cross a stop by more than 0.05 rad.
    let braked = DeviceConfig::exogait().unwrap();
    let mut limp = braked;
    for d in &mut limp.drives {
        d.brake = None;
    }
    let play = |device: &DeviceConfig, gait: Gait, at: f64| {
        let run = run_faulted(device, gait, at + 4.0, 2, None, &[&format!("estop@{at}")]);
        outcome(&run.rig, run.ended_by.as_ref())
    };
    let (mut braked_falls, mut limp_falls, mut limp_crossed) = (Vec::new(), 0, 0);
    for gait in [Gait::Walk, Gait::StairUp, Gait::StairDown] {
        for at in [1.6, 2.0, 2.4, 3.2] {
            let b = play(&braked, gait, at);
            if b.fell.is_some() {
                braked_falls.push((gait, at));
            }
            assert!(b.worst_limit_margin_rad > 0.0, "{gait:?}, {at} s: {b:?}");
            let l = play(&limp, gait, at);
            limp_falls += usize::from(l.fell.is_some());
            limp_crossed += usize::from(l.worst_limit_margin_rad < -0.05);
        }
    }
    assert!(
        limp_falls >= 1 && limp_crossed >= 8,
        "limp: {limp_falls} falls, {limp_crossed} past a stop"
    );
    assert!(braked_falls.is_empty(), "falls: {braked_falls:?}");
}

/// The e-stop in a swing: the drives set the swing foot down first and
/// are disabled as its sensor feels the ground, or once the set-down's
/// time is up (a stop of category 1); standing, at once (category 0,
/// `e_stop_disables_the_motors_in_the_same_tick_and_latches`).
#[test]
fn an_e_stop_in_a_swing_sets_the_foot_down_before_it_disables_the_drives() {
    let device = DeviceConfig::exogait().unwrap();
    let contact = f64::from(device.controller.sequencer.landing_contact_n);
    let set_down_s = f64::from(device.controller.sequencer.set_down_s);
    let play =
        |device: &DeviceConfig| run_faulted(device, Gait::StairDown, 6.4, 2, None, &["estop@2.4"]);
    let run = play(&device);
    let o = outcome(&run.rig, run.ended_by.as_ref());
    assert!(o.fell.is_none(), "{o:?}");
    let trace = &run.rig.trace;
    let pressed = trace
        .iter()
        .position(|s| s.report.faults.contains(FaultCode::EStopPressed))
        .unwrap();
    let at = &trace[pressed];
    assert!(
        matches!(trace[pressed - 1].report.phase, Phase::Swing { .. }),
        "struck in a swing"
    );
    assert_eq!(at.report.reaction, Reaction::SafeHold);
    assert!(at.report.motors_enabled);
    assert!(matches!(at.report.phase, Phase::SafeHold { .. }));
    // The swing (right) foot finds the ground, and on that tick the drives
    // go off, for good.
    let off = trace.iter().position(|s| !s.report.motors_enabled).unwrap();
    let landed = (pressed..trace.len())
        .find(|&k| trace[k].report.forces_n[1] >= contact as f32)
        .unwrap();
    assert!(
        landed <= off && off <= landed + 1,
        "disabled {off}, foot down {landed}"
    );
    assert!(off > pressed + 100, "set down for {} ticks", off - pressed);
    assert!((off - pressed) as f64 * 1e-3 <= set_down_s + 2e-3);
    for s in &trace[off..] {
        assert!(!s.report.motors_enabled && s.report.command_nm == [0.0; 4]);
        assert_eq!(s.report.reaction, Reaction::DisableMotors);
    }
    // A fault's set-down already under way when the e-stop comes goes on
    // to the tread, the faulted joint still braked, and the drives are
    // off as the foot lands.
    let both = ["encoder-parity:left-hip@2.35", "estop@2.4"];
    let run = run_faulted(&device, Gait::StairDown, 6.4, 2, None, &both);
    let trace = &run.rig.trace;
    let pressed = trace
        .iter()
        .position(|s| s.report.faults.contains(FaultCode::EStopPressed))
        .unwrap();
    assert!(matches!(
        trace[pressed - 1].report.phase,
        Phase::SafeHold { .. }
    ));
    let off = trace.iter().position(|s| !s.report.motors_enabled).unwrap();
    let landed = (pressed..trace.len())
        .find(|&k| trace[k].report.forces_n[1] >= contact as f32)
        .unwrap();
    assert!(
        off > pressed + 50 && landed <= off && off <= landed + 1,
        "e-stop {pressed}, disabled {off}, foot down {landed}"
    );
    assert!(
        trace[pressed..off]
            .iter()
            .all(|s| s.braked[0] && s.report.command_nm[0] == 0.0)
    );
    // However far the foot has to go, the drives are off once the
    // set-down's time is up.
    let mut short = device;
    short.controller.sequencer.set_down_s = 0.05;
    let run = play(&short);
    let trace = &run.rig.trace;
    let pressed = trace
        .iter()
        .position(|s| s.report.faults.contains(FaultCode::EStopPressed))
        .unwrap();
    let off = trace.iter().position(|s| !s.report.motors_enabled).unwrap();
    assert!(
        (49..=51).contains(&(off - pressed)),
        "disabled {} ticks after the e-stop",
        off - pressed
    );
}
