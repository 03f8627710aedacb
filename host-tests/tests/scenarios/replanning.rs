//! The board's idle-time re-planner in the closed loop: the answer reaches
//! the sequencer on the tick the board would have it, the swing starts
//! exactly the latency after the request, and a pilot who stands leaning
//! forward on a stair descent has each step land where it is planned, as
//! does one leaning back on the walk without more crutch load and one
//! climbing leaning forward with less; one leaning further than the
//! re-planner takes on straightens to it first and climbs on; a late or
//! refused answer is logged (0x0606, 0x0607) and the table played.

use exogait_device::DeviceConfig;
use exogait_device::replan::REPLAN;
use gait_control::faults::{FaultCode, Reaction};
use gait_control::replan::{ReplanOutcome, ReplanSlot};
use gait_control::supervisor::FaultRecord;
use gait_core::flash_tables;
use sim::compare::{GaitRun, play};
use sim::pilot::PilotConfig;
use sim::scenario::strong_pilot;

/// One re-plan as the run saw it: its answer, the tick it was asked at,
/// the tick its answer was in the slot after (never for a timed-out one),
/// and the first tick of the swing that followed the request.
#[derive(Clone, Copy, Debug)]
struct Seen {
    outcome: ReplanOutcome,
    asked: u64,
    ready: u64,
    next_swing: u64,
}

/// Four descent steps of a pilot leaning 2° forward, the board
/// re-planning or not, `fault` injected (before the first request); the
/// run, its re-plans and the controller's fault log.
fn descent_run(replan: bool, fault: Option<&str>) -> (GaitRun, Vec<Seen>, Vec<FaultRecord>) {
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
        if let Some(f) = fault {
            rig.schedule(f.parse().unwrap());
        }
    })
    .unwrap();
    let swing = |s: &sim::closed_loop::Sample| {
        matches!(s.report.phase, gait_control::sequencer::Phase::Swing { .. })
    };
    let swings: Vec<u64> = rig
        .trace
        .windows(2)
        .filter(|w| swing(&w[1]) && !swing(&w[0]))
        .map(|w| u64::from(w[1].report.tick))
        .collect();
    let seen = rig
        .replans()
        .iter()
        .map(|r| Seen {
            outcome: r.answer.outcome,
            asked: r.asked_at,
            ready: r.ready_at,
            next_swing: swings
                .iter()
                .copied()
                .find(|&t| t > r.asked_at)
                .unwrap_or(0),
        })
        .collect();
    let log = rig.controller.supervisor().log().copied().collect();
    (run, seen, log)
}

fn descent(replan: bool) -> (GaitRun, Vec<Seen>) {
    let (run, seen, _) = descent_run(replan, None);
    (run, seen)
}

/// Asserts that the balance part of the crutch impulse per step of the
/// `replanned` run is at most `factor` times that of the `plain` one.
fn assert_balance_within(plain: &GaitRun, replanned: &GaitRun, factor: f64) {
    let balance = |r: &GaitRun| r.mean(|s| s.balance_ns).unwrap();
    let (before, after) = (balance(plain), balance(replanned));
    assert!(
        after <= factor * before,
        "balance {after:.1} N·s a step re-planned against {before:.1} N·s"
    );
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
        .filter(|r| r.outcome == ReplanOutcome::Replanned)
        .collect();
    assert!(used.len() >= 4, "{answers:?}");
    for r in used.iter().take(4) {
        assert_eq!(
            r.next_swing,
            r.asked + 1 + u64::from(REPLAN.latency_ticks),
            "{answers:?}"
        );
    }
}

/// Four walking steps of a pilot leaning 2° back, the encoders and ADC
/// noisy as the device's (±3 and ±10 counts, `compare`'s default seed),
/// the board re-planning or not.
fn back_leaning_walk(replan: bool) -> GaitRun {
    leaning(flash_tables::walk().unwrap(), -2.0, replan).0
}

/// Four steps of `table` by a pilot leaning `deg` (forward positive), the
/// sensors noisy as in [`back_leaning_walk`], re-planned or not; the run
/// and how many re-plans were answered with a step.
fn leaning(
    table: gait_core::tables::GaitTable<'static>,
    deg: f64,
    replan: bool,
) -> (GaitRun, usize) {
    let device = DeviceConfig::exogait().unwrap();
    let pilot = PilotConfig {
        habit_lean_rad: deg.to_radians(),
        ..strong_pilot()
    };
    let slot = ReplanSlot::new();
    let (run, rig) = play(&device, table, pilot, 4, 40.0, |rig| {
        rig.set_sensor_noise(3, 10, 2026);
        if replan {
            rig.replan_with(&slot);
        }
    })
    .unwrap();
    let replanned = rig
        .replans()
        .iter()
        .filter(|r| r.answer.outcome == ReplanOutcome::Replanned)
        .count();
    (run, replanned)
}

/// The walking pilot leaning back stands inside the soft margin of the
/// ankle's plantarflexion stop. The re-planner keeps that ankle where the
/// pilot has it (no soft margin on an ankle without a drive): the steps
/// land on their footholds and the crutches carry what they carry on the
/// table. With the margin, the steps landed as well but the balance part
/// of the crutch load rose by a third.
#[test]
fn a_back_leaning_walkers_steps_land_where_planned_without_more_crutch_load() {
    let (plain, replanned) = (back_leaning_walk(false), back_leaning_walk(true));
    assert!(plain.faults.is_empty() && replanned.faults.is_empty());
    let (before, after) = (mean_step_error_mm(&plain), mean_step_error_mm(&replanned));
    assert!(
        after <= 0.5 * before,
        "step error {after:.1} mm re-planned against {before:.1} mm"
    );
    assert_balance_within(&plain, &replanned, 1.03);
}

/// A pilot climbing with a 2° forward lean: played turned, the table's
/// foot meets the upper tread early and some 14 mm long; re-planned, the
/// approach is aimed under the tread and 8 mm short (`ReplanConfig`'s
/// `landing_aim_m`), so the foot meets it on time where planned, and the
/// crutches carry less.
#[test]
fn a_forward_leaning_climbers_steps_land_where_planned_with_less_crutch_load() {
    let table = flash_tables::stair_up().unwrap();
    let (plain, replanned) = (leaning(table, 2.0, false).0, leaning(table, 2.0, true).0);
    assert!(plain.faults.is_empty() && replanned.faults.is_empty());
    let (before, after) = (mean_step_error_mm(&plain), mean_step_error_mm(&replanned));
    assert!(before > 10.0, "the table's step error is {before:.1} mm");
    assert!(
        after <= 0.25 * before,
        "step error {after:.1} mm re-planned against {before:.1} mm"
    );
    assert_balance_within(&plain, &replanned, 1.0);
}

#[test]
fn a_late_or_refused_answer_plays_the_table_and_the_steps_go_on() {
    let (plain, _) = descent(false);
    for fault in ["replan-timeout@1.0", "replan-refused@1.0"] {
        let (run, replans, log) = descent_run(true, Some(fault));
        let first = replans[0];
        let code = match fault {
            "replan-timeout@1.0" => {
                assert_eq!(first.ready, u64::MAX, "never answered");
                FaultCode::ReplanLate
            }
            _ => {
                assert_eq!(first.outcome, ReplanOutcome::Refused);
                FaultCode::ReplanRefused
            }
        };
        // Logged once, on the tick the swing starts on the table; not
        // latched (the steps go on, nothing to reset).
        let logged: Vec<_> = log.iter().filter(|r| r.code.code() >= 0x0606).collect();
        assert_eq!(logged.len(), 1, "{fault}: {log:?}");
        assert_eq!(logged[0].code, code);
        assert_eq!(u64::from(logged[0].tick), first.next_swing, "{fault}");
        assert_eq!(code.reaction(), Reaction::PlayTable);
        // The pilot's 2° is within the table's tolerance: the first step
        // plays the table at the latency, the next ones are re-planned.
        assert_eq!(
            first.next_swing,
            first.asked + 1 + u64::from(REPLAN.latency_ticks)
        );
        assert!(
            replans[1..]
                .iter()
                .all(|r| r.outcome == ReplanOutcome::Replanned)
        );
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

/// A pilot leaning 4° forward on the ascent stands with the stance ankle
/// beyond what the re-planner takes on (`ReplanConfig`'s
/// `ankle_tolerance_rad`): the step waits until the ankle comes within it,
/// not within the table's 0.05 rad, and is re-planned from there. The
/// climb goes on without a fault, its steps re-planned, the pilot waits
/// less than for the table, and the crutches carry no more than 5 % over
/// it.
#[test]
fn a_climber_leaning_4_degrees_forward_waits_less_than_for_the_table_and_climbs_on() {
    let table = flash_tables::stair_up().unwrap();
    let ((plain, _), (replanned, used)) = (leaning(table, 4.0, false), leaning(table, 4.0, true));
    assert!(plain.faults.is_empty(), "{:?}", plain.faults);
    assert!(replanned.faults.is_empty(), "{:?}", replanned.faults);
    assert_eq!(replanned.landed(), 4);
    assert!(used >= 4, "{used} re-plans answered with a step");
    let wait = |r: &GaitRun| r.steps.iter().map(|s| s.waited_s).sum::<f64>() / r.steps.len() as f64;
    let (before, after) = (wait(&plain), wait(&replanned));
    assert!(
        after <= 0.8 * before,
        "waited {after:.2} s a step re-planned against {before:.2} s"
    );
    assert_balance_within(&plain, &replanned, 1.05);
}
