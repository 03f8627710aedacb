//! The simulated pilot in a hold: he reacts late and slowly, and does not
//! shove the body when a set-down foot lands.

use exogait_device::DeviceConfig;
use gait_control::operator::Gait;
use gait_control::sequencer::Phase;
use sim::inject::Injection;
use sim::scenario::{flash_tables, instant_pilot, run_tables_with, strong_pilot};

use super::{run_faulted, stands_clear_of_the_stops};

#[test]
fn the_simulated_pilot_reacts_to_a_hold_late_and_slowly() {
    // The campaign's pilot goes on with the step's shank for its reaction
    // time, then eases it to the hold's aim; an instant one
    // (`scenario::instant_pilot`) meets the hold at once with the crutches'
    // full torque (`docs/campaign.md`).
    let device = DeviceConfig::exogait().unwrap();
    let fault: Injection = "dir-fail:right-hip@2.497".parse().unwrap();
    let crutches_after_hold = |pilot: sim::pilot::PilotConfig| {
        let run = run_tables_with(
            &device,
            flash_tables(),
            Gait::StairDown,
            pilot,
            fault.at_s + 1.0,
            2,
            |rig| {
                rig.set_sensor_noise(3, 10, 730_010);
                rig.schedule(fault);
            },
        )
        .unwrap();
        let trace = &run.rig.trace;
        let held = trace
            .iter()
            .position(|s| matches!(s.report.phase, Phase::SafeHold { .. }))
            .unwrap();
        let before = trace[held - 1].state.crutch_forces_n[0];
        let peak = |ms: usize| {
            trace[held..held + ms]
                .iter()
                .map(|s| s.state.crutch_forces_n[0])
                .fold(0.0, f64::max)
        };
        (before, peak(10), peak(140), peak(400))
    };
    let instant = instant_pilot();
    let most =
        0.5 * (instant.torque_limit_nm / instant.crutch_lever_m + instant.baseline_crutch_load_n);
    let (_, first_10ms, _, _) = crutches_after_hold(instant);
    assert!(first_10ms > 0.95 * most, "{first_10ms} N of {most}");
    let reacting = strong_pilot();
    assert_eq!(
        (reacting.hold_reaction_s, reacting.hold_recovery_s),
        (0.15, 1.5)
    );
    let (before, _, reaction, later) = crutches_after_hold(reacting);
    assert!(
        reaction < before + 60.0,
        "{reaction} N within the reaction time, {before} N before"
    );
    assert!(later > reaction + 20.0, "then it pushes: {later} N");
}

#[test]
fn the_pilot_does_not_shove_the_body_when_the_set_down_foot_lands() {
    // Seed 1's campaign: a descent's stance knee encoder lost late in the
    // swing (the knee braked, the swing foot set down). The simulated
    // pilot's eased move in the hold restarts from the landed shank once
    // the landed foot becomes the plant's stance foot (its shank at
    // −0.03): going on from the old stance shank's angle (0.49 rad), the
    // crutches would push at their full 300 N·m and pitch the torso past
    // 60°. Restarted, the pilot stands, with no stop crossed.
    stands_clear_of_the_stops(
        Gait::StairDown,
        &[
            ("encoder-parity:left-knee@2.97", 886_658),
            ("encoder-error-flag:left-knee@2.97", 7_735),
        ],
    );
}

#[test]
fn a_pilot_who_stops_balancing_on_the_stairs_is_found_by_the_shank_and_kept_up() {
    // The pilot stops balancing on a stair ascent: early in the first
    // swing (1.0 s) or in the weight transfer after it (3.5 s), the stance
    // shank tips back from its plan with the crutches idle, 0x0702 is the
    // first fault and the swing foot is set down; the hold keeps the pilot
    // up, and the same runs without the check fall. In the second half of
    // the first swing (2.5 s) the body tips forward instead: the step lands
    // (3.8 s) before the tipping has built up, and 0x0701 finds it in the
    // weight transfer, where both feet carry the body and it tips slower;
    // without the check, the heel-off check holds it later.
    // The crutches' check (0x0703) would find each of these first: it is
    // off here, to try the shank's.
    use gait_control::faults::FaultCode;
    let mut device = DeviceConfig::exogait().unwrap();
    device.supervisor.crutch_idle.ticks = u32::MAX;
    let mut unchecked = device;
    unchecked.supervisor.balance.ticks = u32::MAX;
    for (fault, code, found_within_s) in [
        (
            "pilot-stops-balancing@1.0",
            FaultCode::PilotFallingBack,
            1.2,
        ),
        (
            "pilot-stops-balancing@3.5",
            FaultCode::PilotFallingBack,
            1.5,
        ),
        (
            "pilot-stops-balancing@2.5",
            FaultCode::PilotFallingForward,
            1.7,
        ),
    ] {
        let at_s: f64 = fault.rsplit('@').next().unwrap().parse().unwrap();
        let run = run_faulted(&device, Gait::StairUp, 10.0, 2, None, &[fault]);
        let o = sim::outcome::outcome(&run.rig, run.ended_by.as_ref());
        let first = o.faults.first().unwrap();
        assert_eq!(first.code, code, "{fault}: {o:?}");
        assert!(first.detected_s - at_s < found_within_s, "{fault}: {o:?}");
        assert!(o.fell.is_none(), "{fault}: {o:?}");
        if code == FaultCode::PilotFallingForward {
            assert!(o.landings >= 1, "{fault}: the step lands first: {o:?}");
        }

        let run = run_faulted(&unchecked, Gait::StairUp, 10.0, 2, None, &[fault]);
        let u = sim::outcome::outcome(&run.rig, run.ended_by.as_ref());
        if code == FaultCode::PilotFallingForward {
            let later = u.faults.first().map_or(f64::INFINITY, |f| f.detected_s);
            assert!(later > first.detected_s, "{fault} without the check: {u:?}");
        } else {
            assert!(u.fell.is_some(), "{fault} without the check: {u:?}");
        }
    }
}

#[test]
fn a_fast_clinical_walk_of_a_tall_heavy_patient_does_not_trip_the_balance_check() {
    // The 1.90 m, 95 kg patient's walk at 0.35 m/s, slowed by 0.4 s (the
    // attempt that clears it: the pace as asked asks the stance hip for
    // more than its drive), overshoots each transfer's aim by up to
    // 0.12 rad, pushing on the crutches: cleared at that attempt, with
    // no fault in its closed loop (a check that tripped on it would leave
    // the patient a slower gait).
    use exogait_device::fitting::{Measures, fit};
    use gait_opt::family::{ATTEMPTS, Outcome, WALK_HANDOVER_S, design, walk_plan};
    let device = DeviceConfig::exogait().unwrap();
    let patient = fit(
        &device,
        &Measures {
            height_m: 1.90,
            mass_kg: 95.0,
            thigh_m: None,
            shank_m: None,
            foot_m: None,
        },
    )
    .unwrap();
    let fitted = device.fitted(&patient.model).unwrap();
    let links = fitted.body.links();
    let plan = walk_plan(0.35, links[0].length_m + links[1].length_m, WALK_HANDOVER_S);
    let Outcome::Cleared(gait) = design(&plan, &fitted, gait_opt::family::DEFAULT_EVALS) else {
        panic!("walk-0.35 left out");
    };
    let slowed = gait.plan.step_time_s - plan.step_time_s;
    assert!(
        (slowed - ATTEMPTS[1].0).abs() < 0.011,
        "slowed by {slowed} s"
    );
}

#[test]
fn a_pilot_who_stops_balancing_in_a_descents_swing_is_set_down_on_the_tread_he_left() {
    // Seed 1's campaign runs of a pilot who stops pushing on the crutches
    // early in a stair descent's swing: the stance heel is on its stop,
    // so the ankle does not see it, and the body sinks back onto the tread
    // it left. The crutches left at their resting load find it 0.8 s
    // later (0x0703), while the swing foot is still over that tread: it is
    // set down there, and the pilot stands on two feet, no stop crossed.
    use gait_control::faults::FaultCode;
    for (fault, seed) in [
        ("pilot-stops-balancing@1.821", 284_074),
        ("pilot-stops-balancing@4.197", 557_637),
    ] {
        let r = crate::common::campaign_run(Gait::StairDown, fault, seed);
        let o = &r.outcome;
        assert!(o.fell.is_none(), "{fault}: {o:?}");
        assert!(o.worst_limit_margin_rad > 0.0, "{fault}: {o:?}");
        let first = o.faults.first().unwrap();
        assert_eq!(first.code, FaultCode::PilotNotBalancing, "{fault}: {o:?}");
        let latency = first.latency_ticks.unwrap();
        // Within the window of a crutch rest that may begin before the stop.
        assert!(latency <= 810, "{fault}: {latency} ticks");
    }
}

#[test]
fn a_balancing_pilot_never_leaves_the_crutches_idle_near_the_window() {
    // The longest stretch of a swing with the crutches within the check's
    // rise of their resting load, in healthy runs of every built-in gait,
    // without sensor noise (where it is longest: the pilot's torque passes
    // slowly through zero mid-swing) and with the device's: at most 85 %
    // of the window that makes 0x0703.
    use gait_control::layout::force::CRUTCHES;
    use gait_control::sequencer::Phase;
    let device = DeviceConfig::exogait().unwrap();
    let cfg = device.supervisor.crutch_idle;
    for gait in [Gait::Walk, Gait::StairUp, Gait::StairDown] {
        for noise in [None, Some(2026)] {
            let run = run_tables_with(
                &device,
                flash_tables(),
                gait,
                strong_pilot(),
                40.0,
                4,
                |rig| {
                    if let Some(seed) = noise {
                        rig.set_sensor_noise(3, 10, seed);
                    }
                },
            )
            .unwrap();
            let (mut least, mut stretch, mut longest) = (f32::INFINITY, 0u32, 0u32);
            for s in &run.rig.trace {
                let sum: f32 = CRUTCHES.iter().map(|&i| s.report.forces_n[i]).sum();
                least = (least + cfg.forget_n_per_s * 1e-3).min(sum);
                let swing = matches!(s.report.phase, Phase::Swing { .. });
                stretch = if swing && sum - least < cfg.rise_n {
                    stretch + 1
                } else {
                    0
                };
                longest = longest.max(stretch);
            }
            assert!(run.rig.trace.len() > 8000, "{gait:?}: a short run");
            assert!(
                longest as f32 <= 0.85 * cfg.ticks as f32,
                "{gait:?}, noise {noise:?}: idle for {longest} ticks of a swing"
            );
        }
    }
}

/// A pilot who leans while standing or in a weight transfer (seed 1's
/// campaign runs) takes the stance shank 0.14–0.19 rad forward, and the
/// torso with it while hips and knees hold: the hold that follows turns
/// the torso back by the lean (`SequencerConfig::level_deadband_rad`), and
/// the pilot stays up; without the levelling each of these falls, the
/// torso past 60° on a stance hip at its drive's torque.
#[test]
fn a_hold_levels_the_torso_of_a_pilot_who_leans_and_keeps_him_up() {
    use crate::common::campaign_run_on;
    let device = DeviceConfig::exogait().unwrap();
    let mut unlevelled = device;
    unlevelled.controller.sequencer.level_max_rad = 0.0;
    for (gait, fault, seed) in [
        (
            Gait::StairDown,
            "pilot-lean=0.1709088956590995@0.847",
            527_273,
        ),
        (Gait::Walk, "pilot-lean=0.1834888582466021@0.993", 762_989),
        (
            Gait::StairUp,
            "pilot-lean=0.19346292951739208@3.962",
            222_347,
        ),
    ] {
        let run = campaign_run_on(&device, gait, fault, seed, strong_pilot());
        assert!(run.outcome.fell.is_none(), "{fault}: {:?}", run.outcome);
        assert!(
            !run.outcome.faults.is_empty(),
            "{fault}: held: {:?}",
            run.outcome
        );
        let run = campaign_run_on(&unlevelled, gait, fault, seed, strong_pilot());
        assert!(
            run.outcome.fell.is_some(),
            "{fault} unlevelled: {:?}",
            run.outcome
        );
    }
}

/// A pilot who leans in a walk's swing (seed 1's campaign runs): the stance
/// hip carries the torso alone and feels the lean as a torque its drive did
/// not give. Braked for it (0x0404 at the gait's 70 N·m), the hip let the
/// torso fall; with its ankle ahead of the plan its limit is doubled
/// (`ResponseCheck::leaning_factor`), the drive holds on, and the hold
/// that comes levels the torso.
#[test]
fn a_leaning_pilot_s_stance_hip_is_not_braked_for_the_lean() {
    use crate::common::campaign_run_on;
    use gait_control::faults::FaultCode;
    let device = DeviceConfig::exogait().unwrap();
    let mut braking = device;
    braking.supervisor.response.leaning_factor = 1.0;
    for (fault, seed) in [
        ("pilot-lean=0.10707749997101226@1.488", 863_411),
        ("pilot-lean=0.1424855890356891@4.166", 680_097),
    ] {
        let run = campaign_run_on(&device, Gait::Walk, fault, seed, strong_pilot());
        assert!(run.outcome.fell.is_none(), "{fault}: {:?}", run.outcome);
        let run = campaign_run_on(&braking, Gait::Walk, fault, seed, strong_pilot());
        assert!(
            run.outcome.fell.is_some(),
            "{fault} braked: {:?}",
            run.outcome
        );
        assert!(
            run.outcome
                .faults
                .iter()
                .any(|f| f.code == FaultCode::MotorResponse),
            "{fault} braked: {:?}",
            run.outcome
        );
    }
}
