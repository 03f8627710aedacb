//! Which joint a fault brakes: a drive that does not follow its command,
//! a lost encoder (driven again from the closed chain while both feet are
//! down), a slipping gear, a broken current monitor (none braked).

use exogait_device::DeviceConfig;
use gait_control::faults::FaultCode;
use gait_control::operator::Gait;
use sim::inject::Injection;
use sim::outcome::outcome;
use sim::scenario::{flash_tables, instant_pilot, run_tables_with};

use super::{run, run_faulted};

#[test]
fn a_joint_whose_encoder_is_lost_is_not_driven_on_its_stale_angle() {
    // The swing hip's encoder fails early in the swing: the safe hold
    // follows, and the blind hip runs on the model's torque alone instead
    // of PID on its last angle (which drove it 0.6° past its stop).
    let o = run(Gait::Walk, 2, 8.0, None, &["encoder-parity:right-hip@2.6"]);
    assert_eq!(
        o.faults.first().map(|f| f.code),
        Some(FaultCode::EncoderParity)
    );
    assert!(o.fell.is_none(), "{o:?}");
    assert!(o.worst_limit_margin_rad > 0.1, "{o:?}");
}

/// Plays `kind` on each hip and knee at 0.8 s (standing), 2.5 s and 3.0 s
/// (the first swings) of a walk, a stair ascent and a descent (36 runs),
/// two steps asked, 4 s after the fault; hands each run to `each` with its
/// case's name, the struck joint and the time.
fn each_joint_run(kind: &str, mut each: impl FnMut(&str, usize, f64, &sim::scenario::StepRun<'_>)) {
    let device = DeviceConfig::exogait().unwrap();
    let joints = ["left-hip", "left-knee", "right-hip", "right-knee"];
    for gait in [Gait::Walk, Gait::StairUp, Gait::StairDown] {
        for (j, name) in joints.iter().enumerate() {
            for at in [0.8, 2.5, 3.0] {
                let fault = format!("{kind}:{name}@{at}");
                let run = run_faulted(&device, gait, at + 4.0, 2, None, &[&fault]);
                each(
                    &format!("{gait:?}, {kind} on {name} at {at} s"),
                    j,
                    at,
                    &run,
                );
            }
        }
    }
}

/// The first fault of `run` that braked a joint.
fn first_braking<'r>(
    run: &'r sim::scenario::StepRun<'_>,
) -> Option<&'r gait_control::supervisor::FaultRecord> {
    run.rig
        .controller
        .supervisor()
        .log()
        .find(|r| r.code.brakes_joint())
}

/// `kind` on every hip and knee, standing, early and late in the first
/// swing, walking, climbing and descending (36 runs): how many braked the
/// joint a braking fault was raised on first, how many of those ended
/// driven again (a lost encoder's joint whose angle the closed chain
/// gives: the angle control used then within half a degree of the
/// truth), and the runs that fell.
fn braked_joint_runs(kind: &str) -> (usize, usize, Vec<String>) {
    let (mut braked_right, mut driven_again, mut falls) = (0, 0, Vec::new());
    each_joint_run(kind, |case, j, _, run| {
        let o = outcome(&run.rig, run.ended_by.as_ref());
        if o.fell.is_some() {
            falls.push(case.to_string());
        }
        let first = first_braking(run).map(|r| usize::from(r.channel));
        let last = run.rig.trace.last().unwrap();
        if first == Some(j) {
            braked_right += 1;
            assert!(last.report.motors_enabled, "{case}: the others hold");
            if last.report.command_nm[j] != 0.0 {
                driven_again += 1;
                let off = f64::from(last.report.joints_rad[j]) - last.state.joint_angles_rad[j];
                assert!(
                    off.abs() < 0.5f64.to_radians(),
                    "{case}: driven on an angle {off} rad off"
                );
            }
        }
    });
    (braked_right, driven_again, falls)
}

#[test]
fn a_drive_that_does_not_follow_its_command_is_braked_and_stays_braked() {
    // A drive stuck on its set value (`motor-stuck`: its output keeps the
    // torque it gave, whatever is commanded). Measured: braked in all 36
    // runs (by its current, 0x0405:
    // `a_drive_stuck_on_its_set_value_is_found_by_its_current_at_its_own_joint`),
    // no fall. The torque residual (0x0404) alone cannot tell the stuck
    // joint from one it drags, and a safe hold that fights the stuck
    // torque instead of braking the joint drops the pilot: the joint is
    // braked, and stays braked.
    let (braked_right, driven_again, falls) = braked_joint_runs("motor-stuck");
    assert!(falls.len() <= 1, "falls: {falls:?}");
    assert_eq!(driven_again, 0, "a drive that does not follow stays braked");
    assert_eq!(
        braked_right, 36,
        "the stuck joint braked in {braked_right} of 36"
    );
}

#[test]
fn a_joint_whose_encoder_is_lost_is_braked_while_the_others_hold() {
    // The encoder's bus lost on every hip and knee. Measured: the joint
    // braked in all 36 runs, and driven again from the closed chain once
    // both feet are down and flat in 2; none falls. A joint without its
    // angle cannot be held by its own loop: held on its feed-forward
    // instead of braked, it drops the pilot more often.
    let (braked_right, driven_again, falls) = braked_joint_runs("encoder-bus");
    assert!(falls.len() <= 2, "falls: {falls:?}");
    assert_eq!(braked_right, 36);
    eprintln!("driven again from the closed chain: {driven_again} of 36");
    assert!(driven_again >= 1, "the closed chain never took over");
}

#[test]
fn a_lost_knee_is_driven_from_the_closed_chain_while_both_feet_are_down() {
    // A stair ascent's stance knee loses its encoder in a swing: braked
    // while the left leg stands alone (nothing on the board sees that
    // angle), the right foot set down on the tread. While both feet are
    // down and flat the other five encoders give the knee's angle, and
    // its drive holds it from there instead of its brake; when the right
    // foot carries nothing for a while (the body back on the left leg, the
    // brake at the drive's full damping holding it there) the chain is
    // open and the brake holds the knee again. (The pilot who meets the
    // hold at once: with the campaign's, who reacts 0.15 s late, the body
    // sinks onto the stance leg and the residual brakes another joint
    // first, a run that shows no chain.)
    let device = DeviceConfig::exogait().unwrap();
    let fault: Injection = "encoder-bus:left-knee@3.4".parse().unwrap();
    let run = run_tables_with(
        &device,
        flash_tables(),
        Gait::StairUp,
        instant_pilot(),
        fault.at_s + 4.0,
        2,
        |rig| {
            rig.set_sensor_noise(3, 10, 7);
            rig.schedule(fault);
        },
    )
    .unwrap();
    let o = outcome(&run.rig, run.ended_by.as_ref());
    assert!(o.fell.is_none(), "{o:?}");
    let codes: Vec<_> = o.faults.iter().map(|f| f.code).collect();
    assert_eq!(codes, [FaultCode::EncoderBusError], "no other joint braked");
    let lost_s = o.faults.first().map(|f| f.detected_s).unwrap();
    let after: Vec<_> = run
        .rig
        .trace
        .iter()
        .filter(|s| s.state.time_s > lost_s)
        .collect();
    let driven = |s: &sim::closed_loop::Sample| s.report.command_nm[1] != 0.0;
    // Braked first (the right foot in the air), then driven from the chain
    // for most of the rest of the run (1 s into the hold).
    let first_driven = after.iter().position(|s| driven(s)).unwrap();
    assert!(first_driven > 100, "braked for {first_driven} ticks");
    let rest = &after[first_driven..];
    let driven_ticks = rest.iter().filter(|s| driven(s)).count();
    assert!(
        driven_ticks > 400,
        "driven {driven_ticks} of {} ticks",
        rest.len()
    );
    // Never driven while a foot has carried nothing for 30 ms: the chain
    // is open, and the knee's angle unknown.
    for (k, s) in rest.iter().enumerate().skip(30) {
        let unloaded = (0..2).any(|f| {
            rest.get(k - 30..=k)
                .is_some_and(|w| w.iter().all(|x| x.state.foot_forces_n[f] == 0.0))
        });
        assert!(
            !(unloaded && driven(s)),
            "driven at {} s with a foot unloaded",
            s.state.time_s
        );
    }
    // The chain's estimate, in control: within 1.5° of the truth as it
    // takes over (the landed foot still turning flat: 1.06° measured),
    // within half a degree 20 ms into each stretch it drives (five encoders' noise of
    // ±3 counts alone sums to ±0.33°).
    let off = |s: &sim::closed_loop::Sample| {
        (f64::from(s.report.joints_rad[1]) - s.state.joint_angles_rad[1]).abs()
    };
    let mut stretch = 0;
    let (mut worst, mut settled) = (0.0f64, 0.0f64);
    for s in rest {
        stretch = if driven(s) { stretch + 1 } else { 0 };
        if stretch > 0 {
            worst = worst.max(off(s));
        }
        if stretch > 20 {
            settled = settled.max(off(s));
        }
    }
    assert!(worst < 1.5f64.to_radians(), "estimate off by {worst} rad");
    assert!(
        settled < 0.5f64.to_radians(),
        "estimate off by {settled} rad"
    );
}

/// The first fault that braked a joint: code, joint, seconds after the
/// injection.
type FirstBrake = (FaultCode, usize, f64);

/// Each run of [`each_joint_run`]: its case, the struck joint and the
/// first fault that braked a joint ([`FirstBrake`]).
fn first_brakes(kind: &str) -> Vec<(String, usize, Option<FirstBrake>)> {
    let mut out = Vec::new();
    each_joint_run(kind, |case, j, at, run| {
        let dt = f64::from(run.rig.device().dt_s);
        let first = first_braking(run)
            .map(|r| (r.code, usize::from(r.channel), f64::from(r.tick) * dt - at));
        out.push((case.to_string(), j, first));
    });
    out
}

#[test]
fn a_drive_stuck_on_its_set_value_is_found_by_its_current_at_its_own_joint() {
    // Stuck at the torque it was giving, a drive is found once its command
    // moves more than the band (10 N·m + 10 %) away: measured 0.10–1.47 s
    // after the injection (median 0.20 s), every time first at its own
    // joint. The residual alone (0x0404) found 5 of 36 first at a joint the
    // stuck one dragged, and the hold then braked a healthy joint.
    for (case, stuck, first) in first_brakes("motor-stuck") {
        let (code, joint, after_s) = first.unwrap_or_else(|| panic!("{case}: never braked"));
        assert_eq!(code, FaultCode::DriveCurrentMismatch, "{case}");
        assert_eq!(joint, stuck, "{case}");
        assert!(after_s < 2.0, "{case}: {after_s} s");
    }
}

#[test]
fn a_broken_current_monitor_finishes_the_step_and_holds_with_every_drive_on() {
    // The monitor's line open or shorted, on a stance and a swing knee and
    // hip, standing and in the first swing: 0x0406 on that drive's channel
    // within its 3 bad samples (at most 12 ticks), nothing braked, no fall.
    for (fault, gait) in [
        ("current-open:left-knee@2.5", Gait::Walk),
        ("current-short:right-hip@2.6", Gait::StairUp),
        ("current-open:right-knee@0.8", Gait::StairDown),
    ] {
        let o = run(gait, 2, 6.0, Some(7), &[fault]);
        assert!(o.fell.is_none(), "{fault}: {:?}", o.fell);
        let codes: Vec<_> = o.faults.iter().map(|f| f.code).collect();
        assert_eq!(codes, [FaultCode::DriveCurrentMonitor], "{fault}");
        let f = &o.faults[0];
        let latency = f.latency_ticks.unwrap();
        assert!(latency <= 12, "{fault}: {latency} ticks");
        assert_eq!(o.braked_joints, [false; 4], "{fault}");
        assert!(o.worst_limit_margin_rad > 0.0, "{fault}");
    }
}

#[test]
fn a_slipping_gear_is_found_by_its_residual_not_its_current() {
    // The gearbox passes a third of the motor's torque; the current, and
    // its monitor, stay what was asked: the current check cannot see it,
    // the residual (0x0404) must. Measured with the campaign's pilot, who
    // meets a hold 0.15 s late: 19 of 36 braked first at their own joint
    // by the residual (it shows only under load), 5 at a joint the
    // slipping one drags, all on stairs, 12 not within the 4 s played. One
    // of these (the walk's left knee slipping before the first swing) is
    // held first for the crutches left at rest (0x0703): the slipping
    // stance knee lets the body down, the pilot's push rests 0.8 s of the
    // swing, and the residual no longer trips in the hold; no fall.
    let (mut own, mut other) = (0, 0);
    for (case, slipping, first) in first_brakes("gear-slip=0.3") {
        let Some((code, joint, _)) = first else {
            continue;
        };
        assert_eq!(code, FaultCode::MotorResponse, "{case}");
        own += usize::from(joint == slipping);
        other += usize::from(joint != slipping);
    }
    assert!(
        own >= 19 && other <= 5,
        "{own} of 36 at their own joint, {other} elsewhere"
    );
}

#[test]
fn a_slipping_stance_hip_in_a_swing_has_the_swing_foot_set_down() {
    // Seed 1's campaign runs of a hip gear slipping before the swing it
    // stands on: its drive saturates under the torso late in the swing
    // (0x0401), and the hold sets the swing foot down, so the other hip,
    // its leg on the ground, shares the torso. With the foot held in the
    // air the torso tipped past 60° on the weak hip in both.
    for (gait, fault, seed) in [
        (
            Gait::Walk,
            "gear-slip=0.775491943846832:left-hip@1.204",
            71_001,
        ),
        (
            Gait::StairUp,
            "gear-slip=0.6070844373799871:right-hip@1.829",
            751_222,
        ),
    ] {
        let r = crate::common::campaign_run(gait, fault, seed);
        let o = &r.outcome;
        assert!(o.fell.is_none(), "{fault}: {o:?}");
        let first = o.faults.first().unwrap();
        assert_eq!(first.code, FaultCode::MotorSaturated, "{fault}: {o:?}");
    }
}

#[test]
fn a_stance_hip_slipping_under_the_device_limit_is_caught_by_its_gait_s_limit() {
    // Seed 1's campaign run of a right hip slipping in the first swing,
    // where its leg swings unloaded; it shows in the next swing, which
    // stands on it: command -112 N·m, the motor -41, tracking within
    // 0.005 rad, a residual of about 70-80 N·m, under the device's
    // 100 N·m. The built-in walk holds that hip to its own 72 N·m (its
    // healthy peak, a pilot 2° off the plan included, is 51): 0x0404 brakes the hip and the hold sets the
    // swing foot down. Over the device's limit alone the torso tipped past
    // 60° when the drive saturated.
    let fault = "gear-slip=0.3675953748980325:right-hip@2.481";
    let r = crate::common::campaign_run(Gait::Walk, fault, 790_233);
    let o = &r.outcome;
    assert!(o.fell.is_none(), "{fault}: {o:?}");
    let first = o.faults.first().unwrap();
    assert_eq!(first.code, FaultCode::MotorResponse, "{fault}: {o:?}");
    assert_eq!(first.channel, Some(2), "{fault}: {o:?}");
}

/// A stair descent's swing knee lost late in the swing (stuck or its
/// direction line failed; seeds 1 and 2 of the campaign): braked, the step
/// lands and the hold keeps the body on the trailing leg's bent knee. The
/// pilot tips forward and the hold's levelling turns the torso back, but
/// with a joint braked never behind where it was then: levelled further,
/// the trailing knee took the torso's load, sank onto its stop and the hip
/// came down to 0.4 m.
#[test]
fn a_hold_with_a_braked_knee_does_not_level_the_torso_onto_the_other_knee() {
    use crate::common::campaign_run_on;
    let device = DeviceConfig::exogait().unwrap();
    for (fault, seed) in [
        ("dir-fail:right-knee@2.928", 913_374),
        ("motor-stuck:right-knee@2.931", 360_846),
        ("motor-stuck:right-knee@2.74", 77_561),
    ] {
        let run = campaign_run_on(
            &device,
            Gait::StairDown,
            fault,
            seed,
            sim::scenario::strong_pilot(),
        );
        assert!(run.outcome.fell.is_none(), "{fault}: {:?}", run.outcome);
        assert!(
            run.outcome.worst_limit_margin_rad > 0.0,
            "{fault}: {:?}",
            run.outcome
        );
    }
}
