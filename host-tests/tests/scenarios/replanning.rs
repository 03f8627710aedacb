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
