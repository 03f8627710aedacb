//! The model's work between ticks (`gait_control::feedforward`, the
//! transfer's IK and the swing's share of `gait_control::ahead`, the
//! supervisor's windowed checks): a controller whose model task answers
//! through a slot, as on the board, drives the device exactly as one that
//! works the answers out itself, faults included; each tick applies the
//! feed-forward answered to the tick before's request; a task that leaves
//! the checks unanswered holds the device.

use gait_control::controller::TickReport;
use gait_control::faults::{FaultCode, Reaction};
use gait_control::feedforward::{ModelSlot, ModelTask, feedforward};
use gait_control::sequencer::Phase;
use host_tests::{standing_rig, strong_pilot};
use sim::closed_loop::Rig;
use sim::inject::{Injection, Kind, Target};

/// Ticks of a walk from standing: GO, the weight transfer, two swings.
const TICKS: usize = 6_000;

fn walk(slot: Option<&'static ModelSlot>) -> Vec<TickReport> {
    walk_with(slot, None)
}

/// [`walk`], `fault` injected.
fn walk_with(slot: Option<&'static ModelSlot>, fault: Option<Injection>) -> Vec<TickReport> {
    let mut rig = standing_rig(strong_pilot()).unwrap();
    let healthy = fault.is_none();
    if let Some(f) = fault {
        rig.schedule(f);
    }
    let mut task = slot.map(|s| {
        let checks = rig.controller.set_model_task(s);
        ModelTask::new(rig.controller.config().model, s)
            .with_checks(checks)
            .with_steps(rig.controller.steps())
    });
    Rig::press(&rig.go, sim::scenario::GO_AT_TICK, sim::scenario::GO_TICKS);
    let mut requests = Vec::new();
    let mut reports = Vec::new();
    for _ in 0..TICKS {
        // A pilot who stops balancing may fall: the run ends there.
        let report = match rig.tick() {
            Ok(sample) => sample.report,
            Err(e) => {
                assert!(!healthy, "{e:?}");
                break;
            }
        };
        if let (Some(task), Some(s)) = (&mut task, slot) {
            requests.push(s.newest_request().map(|(_, r)| r));
            task.serve();
        }
        reports.push(report);
    }
    // Each tick applied the model's answer to the request before it: in
    // single support the feed-forward is that answer's torques alone.
    let model = rig.controller.config().model;
    let mut swing_ticks = 0;
    for (n, r) in reports.iter().enumerate().skip(1) {
        let (Phase::Swing { .. }, Some(Some(req))) = (r.phase, requests.get(n - 1)) else {
            continue;
        };
        if req.other_load_n == 0.0 {
            swing_ticks += 1;
            assert_eq!(
                r.feedforward_nm,
                feedforward(&model, req).torques_nm,
                "tick {n}"
            );
        }
    }
    assert!(
        slot.is_none() || !healthy || swing_ticks > 1_000,
        "{swing_ticks} swing ticks"
    );
    // Every healthy swing tick but each swing's first (asked by the tick
    // that starts it, answered before it) takes its table work from the
    // task.
    let swing_reports = reports
        .iter()
        .filter(|r| matches!(r.phase, Phase::Swing { .. }))
        .count();
    if let (Some(s), true) = (slot, healthy) {
        let taken = s.ahead().taken() as usize;
        assert!(
            taken + 10 >= swing_reports && taken <= swing_reports,
            "{taken} of {swing_reports} swing ticks"
        );
    }
    reports
}

#[test]
fn a_model_task_between_ticks_drives_the_device_as_the_tick_alone_does() {
    static SLOT: ModelSlot = ModelSlot::new();
    let alone = walk(None);
    let with_task = walk(Some(&SLOT));
    assert!(alone.iter().any(|r| matches!(r.phase, Phase::Swing { .. })));
    for (n, (a, b)) in alone.iter().zip(&with_task).enumerate() {
        let bits = |r: &TickReport| r.command_nm.map(f32::to_bits);
        assert_eq!(bits(a), bits(b), "tick {n}");
        assert_eq!(a.feedforward_nm, b.feedforward_nm, "tick {n}");
    }
}

/// Faults that only the windowed checks find (the torque residual, a
/// frozen encoder, a force sensor's debounce, the crutches left at rest
/// through a swing): found in the task's time,
/// they latch on the same tick, with the same reaction, as the tick's own
/// run of the checks finds them.
#[test]
fn the_windowed_checks_in_the_task_find_what_the_tick_finds_on_the_same_tick() {
    // A slot each: one serves one controller from its first tick.
    static SLOTS: [ModelSlot; 4] = [const { ModelSlot::new() }; 4];
    for ((kind, target, code), slot) in [
        (
            Kind::MotorStuck,
            Some(Target::Joint(3)),
            FaultCode::MotorResponse,
        ),
        (
            Kind::EncoderStuck,
            Some(Target::Joint(1)),
            FaultCode::EncoderFrozen,
        ),
        (Kind::FsrOpen, Some(Target::Force(2)), FaultCode::ForceOpen),
        (
            Kind::PilotStopsBalancing,
            None,
            FaultCode::PilotNotBalancing,
        ),
    ]
    .into_iter()
    .zip(&SLOTS)
    {
        let fault = Injection {
            kind,
            target,
            at_s: 2.6,
        };
        let alone = walk_with(None, Some(fault));
        let with_task = walk_with(Some(slot), Some(fault));
        let first = alone.iter().position(|r| r.faults.contains(code));
        assert!(first.is_some(), "{kind:?}: {code:?} not found");
        assert_eq!(alone.len(), with_task.len(), "{kind:?}");
        for (n, (a, b)) in alone.iter().zip(&with_task).enumerate() {
            let bits = |r: &TickReport| r.command_nm.map(f32::to_bits);
            assert_eq!(bits(a), bits(b), "{kind:?}: tick {n}");
            assert_eq!(a.faults, b.faults, "{kind:?}: tick {n}");
            assert_eq!(a.reaction, b.reaction, "{kind:?}: tick {n}");
        }
    }
}

/// A model task that does not run the windowed checks (given none) leaves
/// each tick's facts unanswered: every later tick counts a missed deadline,
/// and the third within 1 s latches 0x0601 and holds.
#[test]
fn unanswered_windowed_checks_are_missed_deadlines() {
    static SLOT: ModelSlot = ModelSlot::new();
    let mut rig = standing_rig(strong_pilot()).unwrap();
    let _unused = rig.controller.set_model_task(&SLOT);
    let mut task = ModelTask::new(rig.controller.config().model, &SLOT);
    for n in 1..=4u32 {
        let report = rig.tick().unwrap().report;
        task.serve();
        assert_eq!(rig.controller.supervisor().deadline_misses(), n - 1);
        let latched = report.faults.contains(FaultCode::DeadlineMissed);
        assert_eq!(latched, n == 4, "tick {n}");
    }
    assert_eq!(rig.tick().unwrap().report.reaction, Reaction::SafeHold);
}

/// A tick that leaves the task no time (an overrun) costs one missed
/// deadline and that tick's facts, and nothing else: the task checks the
/// next tick's facts and the device goes on as before.
#[test]
fn one_tick_without_the_task_is_one_missed_deadline() {
    static SLOT: ModelSlot = ModelSlot::new();
    let mut rig = standing_rig(strong_pilot()).unwrap();
    let checks = rig.controller.set_model_task(&SLOT);
    let mut task = ModelTask::new(rig.controller.config().model, &SLOT).with_checks(checks);
    for n in 0..100 {
        let report = rig.tick().unwrap().report;
        assert!(report.faults.is_empty(), "tick {n}: {:?}", report.faults);
        if n != 50 {
            task.serve();
        }
    }
    assert_eq!(rig.controller.supervisor().deadline_misses(), 1);
}
