//! Fault-table row of the pilot seen at the crutches: 0x0703, a pilot who
//! has stopped balancing.

use crate::supervisor::support::*;
use gait_control::faults::InSwing;
use gait_control::layout::{Side, force};

/// A right swing from the first injected tick, the crutches' sum `load(k)`
/// (split evenly), for `n` ticks; the verdicts.
fn swing_with_crutches(n: u32, load: impl Fn(u32) -> f32) -> Vec<Verdict> {
    inject(n, |k, input| {
        input.step_in_progress = true;
        input.swing_leg = Some(Side::Right);
        for i in force::CRUTCHES {
            input.forces[i].newtons = 0.5 * load(k);
        }
    })
    .1
}

#[test]
fn row_pilot_not_balancing() {
    // The standing rig rests 160 N on the crutches; through a swing they
    // stay there (within 10 N): the window's last tick trips it, and the swing
    // foot is set down where it is.
    let cfg = SupervisorConfig::paper().crutch_idle;
    let v = swing_with_crutches(cfg.ticks + 20, |_| 165.0);
    assert_row(
        &v,
        FaultCode::PilotNotBalancing,
        Reaction::SafeHold,
        cfg.ticks,
    );
    assert_eq!(FaultCode::PilotNotBalancing.in_swing(), InSwing::HoldNow);
}

#[test]
fn a_pilot_who_pushes_now_and_then_or_stands_at_rest_is_not_tripped() {
    let quiet = |v: &[Verdict]| v.iter().all(|x| x.reaction == Reaction::None);
    // A push of 40 N over the resting load every 0.2 s, 20 ms long: the
    // idle stretches last 180 ticks.
    let v = swing_with_crutches(3000, |k| if k % 200 < 20 { 200.0 } else { 160.0 });
    assert!(quiet(&v));
    // Standing or in a weight transfer, resting the crutches is allowed.
    let (_, v) = inject(3000, |_, input| input.step_in_progress = true);
    assert!(quiet(&v));
}

#[test]
fn a_crutch_sensor_failing_now_and_then_does_not_hide_a_stopped_pilot() {
    // One bus error every 400 ticks (under the force sensors' own
    // debounce, 0x0301): those ticks neither count nor restart the count,
    // and the row trips one tick later for each.
    let cfg = SupervisorConfig::paper().crutch_idle;
    let v = inject(2 * cfg.ticks, |k, input| {
        input.step_in_progress = true;
        input.swing_leg = Some(Side::Right);
        if k % 400 == 0 {
            input.forces[force::LEFT_CRUTCH].status = ForceStatus::BusError;
        }
    })
    .1;
    let glitches = (1..=cfg.ticks + 2).filter(|k| k % 400 == 0).count() as u32;
    assert_eq!(
        detected_at(&v, FaultCode::PilotNotBalancing),
        Some(cfg.ticks + glitches)
    );
}
