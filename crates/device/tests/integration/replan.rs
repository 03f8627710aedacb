//! The device's re-plan: what the board runs in its idle time, within the
//! sequencer's latency, and what it offers the sequencer.

use exogait_device::DeviceConfig;
use exogait_device::replan::{
    IDLE_INSTRUCTIONS_PER_TICK, INSTRUCTIONS_PER_SAMPLE, REPLAN, evals_within, replan,
};
use gait_control::posture::{Side, joints_from_phi};
use gait_control::replan::{REPLAN_CAPACITY, ReplanOutcome, ReplanRequest};
use gait_control::sequencer::GaitTables;
use gait_core::flash_tables;

fn tables() -> GaitTables<'static> {
    GaitTables::by_kind(
        flash_tables::walk().ok(),
        flash_tables::stair_up().ok(),
        flash_tables::stair_down().ok(),
    )
}

/// A request for `slot`'s step, the pilot `deg` off its start with the
/// joints where the table starts.
fn request(slot: u8, deg: f32) -> ReplanRequest {
    let first = tables().slot(usize::from(slot)).unwrap().first();
    ReplanRequest {
        slot,
        stance: Side::Left,
        phi1_rad: first[0] + deg.to_radians(),
        joints_rad: joints_from_phi(&first, Side::Left),
        persist: REPLAN.persist,
    }
}

#[test]
fn the_evaluations_fit_in_the_latency() {
    for slot in 0..3u8 {
        let len = tables().slot(usize::from(slot)).unwrap().len();
        let n = evals_within(REPLAN.latency_ticks, len);
        assert!(n >= 16, "slot {slot}: only {n} evaluations");
        let cost = u64::from(n) * len as u64 * INSTRUCTIONS_PER_SAMPLE;
        let idle = u64::from(REPLAN.latency_ticks - 1) * IDLE_INSTRUCTIONS_PER_TICK;
        assert!(cost <= idle, "slot {slot}: {cost} > {idle}");
        assert!(u64::from(n + 1) * len as u64 * INSTRUCTIONS_PER_SAMPLE > idle || n == 48);
    }
}

#[test]
fn a_lean_is_replanned_admitted_and_answered_before_the_latency() {
    let device = DeviceConfig::exogait().unwrap();
    let mut out = vec![[0.0f32; 5]; REPLAN_CAPACITY];
    for slot in 0..3u8 {
        let len = tables().slot(usize::from(slot)).unwrap().len();
        let max = evals_within(REPLAN.latency_ticks, len);
        let a = replan(&device, &tables(), &request(slot, 3.0), &mut out, max);
        assert_eq!(a.outcome, ReplanOutcome::Replanned, "slot {slot}: {a:?}");
        assert!(a.refusal.is_none() && a.setup_error.is_none());
        assert!(a.evals <= max && a.samples == len);
        assert!(
            a.ticks() < u64::from(REPLAN.latency_ticks),
            "slot {slot}: {a:?}"
        );
        // The answer starts at the measured shank angle.
        assert!((out[0][0] - request(slot, 3.0).phi1_rad).abs() < 1e-5);
    }
}

#[test]
fn on_the_plan_or_without_a_table_the_table_is_played() {
    let device = DeviceConfig::exogait().unwrap();
    let mut out = vec![[0.0f32; 5]; REPLAN_CAPACITY];
    let a = replan(&device, &tables(), &request(0, 0.0), &mut out, 24);
    assert_eq!(a.outcome, ReplanOutcome::Declined);
    let mut none = request(0, 3.0);
    none.slot = 7;
    let a = replan(&device, &tables(), &none, &mut out, 24);
    assert_eq!(a.outcome, ReplanOutcome::Declined);
    assert_eq!(a.evals, 0);
    // Too far off for any re-plan (20°): refused at set-up, the table.
    let a = replan(&device, &tables(), &request(0, 20.0), &mut out, 24);
    assert_eq!(a.outcome, ReplanOutcome::Declined);
    assert!(a.setup_error.is_some());
}
