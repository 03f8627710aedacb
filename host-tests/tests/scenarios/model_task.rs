//! The model's work between ticks (`gait_control::feedforward`, and the
//! transfer's IK and the swing's share of `gait_control::ahead`): a controller whose model
//! task answers through a slot, as on the board, drives the device exactly
//! as one that works the answers out itself, and each tick applies the
//! feed-forward answered to the tick before's request.

use gait_control::controller::TickReport;
use gait_control::feedforward::{ModelSlot, ModelTask, feedforward};
use gait_control::sequencer::Phase;
use host_tests::{standing_rig, strong_pilot};
use sim::closed_loop::Rig;

/// Ticks of a walk from standing: GO, the weight transfer, two swings.
const TICKS: usize = 6_000;

fn walk(slot: Option<&'static ModelSlot>) -> Vec<TickReport> {
    let mut rig = standing_rig(strong_pilot()).unwrap();
    let task = slot.map(|s| {
        rig.controller.set_model_task(s);
        ModelTask::new(rig.controller.config().model, s)
    });
    Rig::press(&rig.go, sim::scenario::GO_AT_TICK, sim::scenario::GO_TICKS);
    let mut requests = Vec::new();
    let mut reports = Vec::new();
    for _ in 0..TICKS {
        let report = rig.tick().unwrap().report;
        if let (Some(task), Some(s)) = (&task, slot) {
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
        slot.is_none() || swing_ticks > 1_000,
        "{swing_ticks} swing ticks"
    );
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
