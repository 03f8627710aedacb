//! A step in the air when a fault comes: it lands first (on its sensor, or
//! on the table's timing when the sensor is lost) and only then holds.

use exogait_device::DeviceConfig;
use gait_control::faults::FaultCode;
use gait_control::operator::Gait;
use sim::outcome::outcome;

use super::{run, run_faulted, stands_clear_of_the_stops};
use crate::common::campaign_run;

#[test]
fn a_step_whose_landing_cannot_be_sensed_ends_on_the_tables_timing_plus_its_settling() {
    use gait_control::sequencer::Phase;
    let duration = f64::from(gait_core::flash_tables::walk().unwrap().duration_s());
    // The first swing's foot is the right one; its sensor (or the whole
    // ADC) fails in the swing.
    for fault in ["fsr-open:right-foot@2.6", "adc-bus@2.6"] {
        let device = DeviceConfig::exogait().unwrap();
        let run = run_faulted(&device, Gait::Walk, 8.0, 2, None, &[fault]);
        let trace = &run.rig.trace;
        let start = trace
            .iter()
            .find(|s| matches!(s.report.phase, Phase::Swing { .. }))
            .unwrap()
            .state
            .time_s;
        let end = trace
            .iter()
            .find(|s| s.state.time_s > start && !matches!(s.report.phase, Phase::Swing { .. }))
            .unwrap_or_else(|| panic!("{fault}: the swing never ended"))
            .state
            .time_s;
        let settle = f64::from(device.controller.sequencer.blind_landing_settle_s);
        assert!(
            (end - start - (duration + settle)).abs() <= 0.01,
            "{fault}: the swing lasted {:.3} s, the table {duration:.3} s + {settle} s",
            end - start
        );
        let o = outcome(&run.rig, run.ended_by.as_ref());
        assert!(
            o.fell.is_none() && o.worst_limit_margin_rad > 0.0,
            "{fault}: {o:?}"
        );
    }
}

#[test]
fn missed_deadlines_in_a_swing_land_the_step_before_holding() {
    // 0x0601 is marked "land first": the step in the air plays on to its
    // landing, then the hold begins (docs/safety.md, "Reactions").
    for gait in [Gait::Walk, Gait::StairUp, Gait::StairDown] {
        let o = run(gait, 2, 8.0, None, &["overrun=5@2.4"]);
        let f = o
            .faults
            .iter()
            .find(|f| f.code == FaultCode::DeadlineMissed)
            .unwrap_or_else(|| panic!("{gait:?}: no 0x0601: {o:?}"));
        assert!(o.fell.is_none(), "{gait:?}: {o:?}");
        assert!(o.landings >= 1, "{gait:?}: the step did not land: {o:?}");
        let held_after = f.safe_state_s.unwrap() - f.detected_s;
        assert!(
            held_after > 0.35,
            "{gait:?}: held {held_after} s after detection, before landing"
        );
    }
}

#[test]
fn a_blind_landing_waits_for_the_foot_to_reach_the_tread() {
    // Seed 1's campaign: the ADC (or the landing foot's sensor) lost as an
    // ascent's first swing ends. Landed on the table's end, the transfer
    // would begin with the foot still above the upper tread and put the
    // body on the leading leg, whose hip would sink 0.6° past its flexion
    // stop; landed 0.3 s later (`blind_landing_settle_s`), the foot is on
    // the tread first.
    for (fault, seed) in [
        ("adc-bus@3.712", 515_577),
        ("adc-bus@3.758", 36_852),
        ("fsr-over-range:right-foot@3.724", 307_044),
    ] {
        let r = campaign_run(Gait::StairUp, fault, seed);
        let o = &r.outcome;
        assert!(o.fell.is_none(), "{fault}: {o:?}");
        assert!(o.worst_limit_margin_rad > 0.0, "{fault}: {o:?}");
        assert!(!o.faults.is_empty(), "{fault}: not detected");
    }
}

#[test]
fn a_persistent_encoder_jump_is_taken_out_and_the_step_lands_before_the_hold() {
    // Stair descents of seed 1's campaign whose jump drops the pilot if
    // the reading stays offset (the first three: control then works on a
    // wrong angle) or if the offset is taken out but the hold sets the foot
    // down at once (the last four). With the offset taken out, sensors,
    // table and motors are good, so the step lands first (0x0205 is marked
    // "land first"): each stands with no joint past a stop, and its hold
    // begins only after the landing.
    for (fault, seed) in [
        ("encoder-jump=315:right-knee@1.908", 456_424),
        ("encoder-jump=-336:left-knee@4.575", 817_201),
        ("encoder-jump=-287:left-hip@4.689", 231_619),
        ("encoder-jump=370:right-hip@2.699", 910_021),
        ("encoder-jump=198:left-knee@2.685", 367_922),
        ("encoder-jump=-182:left-hip@2.678", 569),
        ("encoder-jump=-298:right-hip@2.684", 994_257),
    ] {
        let r = campaign_run(Gait::StairDown, fault, seed);
        let o = &r.outcome;
        assert!(o.fell.is_none(), "{fault}: {o:?}");
        assert!(o.worst_limit_margin_rad >= 0.0, "{fault}: {o:?}");
        let f = o
            .faults
            .iter()
            .find(|f| f.code == FaultCode::EncoderJump)
            .unwrap_or_else(|| panic!("{fault}: no 0x0205: {o:?}"));
        assert!(f.latency_ticks.unwrap() <= 3, "{fault}: {f:?}");
        assert!(o.landings >= 1, "{fault}: {o:?}");
        // The swing played on to its landing (1.1–2.2 s here) before the
        // hold stood still; a hold at once stands within a few tenths.
        let held_after = f.safe_state_s.unwrap() - f.detected_s;
        assert!(
            held_after > 0.5,
            "{fault}: held {held_after} s after detection"
        );
    }
}

#[test]
fn late_in_a_descent_s_swing_a_hold_lands_the_step_first() {
    // Seed 1's campaign, stair descents, the hold 0.27–0.55 s before the
    // table's landing: the stance hip's drive or encoder lost, the swing
    // knee's encoder or drive lost. Played on to its landing, none falls
    // or crosses a stop. (Set down at once, these stand too: the simulated
    // pilot's push restarts from the set-down foot's shank when it lands,
    // `the_pilot_does_not_shove_the_body_when_the_set_down_foot_lands`.)
    stands_clear_of_the_stops(
        Gait::StairDown,
        &[
            ("pwm-fail:left-hip@3.021", 55_537),
            ("encoder-bus:left-hip@3.111", 791_362),
            ("encoder-error-flag:right-knee@3.286", 635_979),
            ("dir-fail:right-knee@3.253", 151_192),
        ],
    );
    let device = DeviceConfig::exogait().unwrap();
    // What landing first buys over setting the foot down (on seed 1's
    // 3,303 descents: 154 falls and 62 stops crossed, none the device's,
    // against 158 and 63 with one the device's): a weak stance hip late in
    // the swing, set down at once, lets the swing knee past its extension
    // stop; played on, the step lands clear of it.
    let mut set_down = device;
    set_down.controller.sequencer.lands_after = [1.0; 3];
    let run = sim::campaign::CampaignRun {
        gait: Gait::StairDown,
        slot: sim::campaign::built_in_slot(Gait::StairDown),
        fault: "motor-weak=0.4486806780323994:left-hip@3.32"
            .parse()
            .unwrap(),
        noise_seed: 373_657,
    };
    let landed = sim::campaign::play(&run, &device).outcome;
    assert!(
        landed.fell.is_none() && landed.worst_limit_margin_rad > 0.0,
        "{landed:?}"
    );
    let held = sim::campaign::play(&run, &set_down).outcome;
    assert!(held.worst_limit_margin_rad < 0.0, "{held:?}");
}
