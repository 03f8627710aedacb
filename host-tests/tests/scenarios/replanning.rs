//! The board's idle-time re-planner in the closed loop: the answer reaches
//! the sequencer on the tick the board would have it, the swing starts
//! exactly the latency after the request, and a pilot who stands leaning
//! forward on a stair descent has each step land where it is planned.

use exogait_device::DeviceConfig;
use exogait_device::replan::REPLAN;
use gait_control::replan::{ReplanOutcome, ReplanSlot};
use gait_core::flash_tables;
use sim::compare::{GaitRun, play};
use sim::pilot::PilotConfig;
use sim::scenario::strong_pilot;

/// Four descent steps of a pilot leaning 2° forward, the board
/// re-planning or not; the run and the re-plans' answers with the tick
/// each was asked at and the next swing's first tick.
fn descent(replan: bool) -> (GaitRun, Vec<(ReplanOutcome, u64, u64)>) {
    let device = DeviceConfig::exogait().unwrap();
    let table = flash_tables::stair_down().unwrap();
    let pilot = PilotConfig {
        habit_lean_rad: 2.0f64.to_radians(),
        ..strong_pilot()
    };
    let slot = ReplanSlot::new();
    let (run, rig) = play(&device, table, pilot, 4, 40.0, |rig| {
        if replan {
            rig.replan_with(&slot);
        }
    })
    .unwrap();
    let swings: Vec<u64> = rig
        .trace
        .windows(2)
        .filter(|w| {
            matches!(
                w[1].report.phase,
                gait_control::sequencer::Phase::Swing { .. }
            ) && !matches!(
                w[0].report.phase,
                gait_control::sequencer::Phase::Swing { .. }
            )
        })
        .map(|w| u64::from(w[1].report.tick))
        .collect();
    let replans = rig
        .replans()
        .iter()
        .map(|r| {
            let next = swings
                .iter()
                .copied()
                .find(|&t| t > r.asked_at)
                .unwrap_or(0);
            (r.answer.outcome, r.asked_at, next)
        })
        .collect();
    (run, replans)
}

fn mean_step_error_mm(run: &GaitRun) -> f64 {
    let e: Vec<f64> = run
        .steps
        .iter()
        .filter_map(|s| s.step_error_m)
        .map(f64::abs)
        .collect();
    assert_eq!(e.len(), 4);
    e.iter().sum::<f64>() / e.len() as f64 * 1e3
}

#[test]
fn a_forward_leaning_pilots_descent_steps_land_where_planned_when_replanned() {
    let (plain, none) = descent(false);
    let (replanned, answers) = descent(true);
    assert!(none.is_empty());
    assert!(plain.faults.is_empty() && replanned.faults.is_empty());
    let (before, after) = (mean_step_error_mm(&plain), mean_step_error_mm(&replanned));
    assert!(
        after <= 0.5 * before,
        "step error {after:.1} mm re-planned against {before:.1} mm"
    );
    // Every step re-planned, each swing starting exactly the latency after
    // its request (the sequencer's tick counts from 1, the clock from 0).
    let used: Vec<_> = answers
        .iter()
        .filter(|(o, ..)| *o == ReplanOutcome::Replanned)
        .collect();
    assert!(used.len() >= 4, "{answers:?}");
    for (_, asked, swing) in used.iter().take(4) {
        assert_eq!(
            *swing,
            asked + 1 + u64::from(REPLAN.latency_ticks),
            "{answers:?}"
        );
    }
}

/// The descent of [`descent`] re-planned, with `fault` injected before the
/// first request: its run, the first swing's first tick, and each re-plan
/// (its answer, the tick it was asked at, the tick it is in the slot
/// after: never for a timed-out one).
fn descent_with(fault: &str) -> (GaitRun, u64, Vec<(ReplanOutcome, u64, u64)>) {
    let device = DeviceConfig::exogait().unwrap();
    let table = flash_tables::stair_down().unwrap();
    let pilot = PilotConfig {
        habit_lean_rad: 2.0f64.to_radians(),
        ..strong_pilot()
    };
    let slot = ReplanSlot::new();
    let (run, rig) = play(&device, table, pilot, 4, 40.0, |rig| {
        rig.replan_with(&slot);
        rig.schedule(fault.parse().unwrap());
    })
    .unwrap();
    let first_swing = rig
        .trace
        .iter()
        .find(|s| matches!(s.report.phase, gait_control::sequencer::Phase::Swing { .. }))
        .map_or(0, |s| u64::from(s.report.tick));
    let replans = rig
        .replans()
        .iter()
        .map(|r| (r.answer.outcome, r.asked_at, r.ready_at))
        .collect();
    (run, first_swing, replans)
}

#[test]
fn a_late_or_refused_answer_plays_the_table_and_the_steps_go_on() {
    let (plain, _) = descent(false);
    for fault in ["replan-timeout@1.0", "replan-refused@1.0"] {
        let (run, first_swing, replans) = descent_with(fault);
        let (outcome, asked, ready) = replans[0];
        match fault {
            "replan-timeout@1.0" => assert_eq!(ready, u64::MAX, "never answered"),
            _ => assert_eq!(outcome, ReplanOutcome::Refused),
        }
        // The pilot's 2° is within the table's tolerance: the first step
        // plays the table at the latency, the next ones are re-planned.
        assert_eq!(first_swing, asked + 1 + u64::from(REPLAN.latency_ticks));
        assert!(replans[1..].iter().all(|r| r.0 == ReplanOutcome::Replanned));
        assert!(run.faults.is_empty(), "{fault}: {:?}", run.faults);
        assert_eq!(run.landed(), 4, "{fault}");
        // That first step is the table's: it lands as the plain run's does.
        let err = |r: &GaitRun| r.steps[0].step_error_m.unwrap();
        assert!(
            (err(&run) - err(&plain)).abs() < 2e-3,
            "{fault}: {} against {}",
            err(&run),
            err(&plain)
        );
    }
}
