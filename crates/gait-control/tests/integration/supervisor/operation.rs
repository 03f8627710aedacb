//! Safety supervisor: healthy runs, the configuration, latching and reset,
//! severity and the log. The fault table's rows: `rows/`; NaN handling:
//! `nan.rs`.

use super::support::*;

// ------------------------------------------------------ healthy operation

#[test]
fn healthy_standing_never_faults() {
    let mut sup = supervisor();
    for tick in 0..30_000 {
        let v = sup.check(&healthy_input(tick));
        assert_eq!(v.reaction, Reaction::None, "tick {tick}: {v:?}");
    }
    assert!(sup.log().next().is_none());
}

#[test]
fn healthy_motion_never_faults() {
    let mut sup = supervisor();
    for tick in 0..30_000 {
        let v = sup.check(&moving_input(tick));
        assert_eq!(v.reaction, Reaction::None, "tick {tick}: {v:?}");
    }
    assert!(sup.latched().is_empty());
}

#[test]
fn envelope_is_table_i_with_margins() {
    let cfg = SupervisorConfig::paper();
    let close = |a: f32, b_deg: f32| (a - b_deg * DEG).abs() < 1e-5;
    let hip = cfg.joint_range[0];
    let knee = cfg.joint_range[1];
    let ankle = cfg.ankle_range[0];
    assert!(
        close(hip.min_rad, -75.0) && close(hip.max_rad, 95.0),
        "{hip:?}"
    );
    assert!(
        close(knee.min_rad, -3.0) && close(knee.max_rad, 95.0),
        "{knee:?}"
    );
    assert!(
        close(ankle.min_rad, -3.0) && close(ankle.max_rad, 22.0),
        "{ankle:?}"
    );
    assert_eq!(cfg.joint_range[2], hip);
    assert_eq!(cfg.joint_range[3], knee);
}

#[test]
fn bad_configurations_are_refused() {
    let good = SupervisorConfig::paper();
    assert!(Supervisor::new(good).is_ok());
    let mut c = good;
    c.velocity_filter_alpha = 0.0;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::NotPositive));
    let mut c = good;
    c.velocity_limit_rad_s[2] = f32::NAN;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::NotPositive));
    let mut c = good;
    c.joint_range[1].min_rad = c.joint_range[1].max_rad;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::BadRange));
    let mut c = good;
    c.force_max_n = f32::INFINITY;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::BadRange));
    let mut c = good;
    c.encoder_debounce.window_ticks = 129;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::BadWindow));
    let mut c = good;
    c.force_debounce.count = 0;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::BadWindow));
    let mut c = good;
    c.deadline_miss_count = 9;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::BadWindow));
    // A still stretch of 0 ticks would restart the frozen count on every
    // still tick: the rule that missed a frozen hip.
    let mut c = good;
    c.frozen_still_reset_ticks = 0;
    assert_eq!(Supervisor::new(c).err(), Some(ConfigError::BadWindow));
}

// -------------------------------------------------- latching and reset

#[test]
fn faults_latch_until_reset_in_a_safe_posture() {
    let mut sup = supervisor();
    let mut input = healthy_input(0);
    input.e_stop_pressed = true;
    let v = sup.check(&input);
    assert_eq!(v.reaction, Reaction::DisableMotors);
    // Still pressed: refused, even in a safe posture.
    assert_eq!(
        sup.request_reset(true),
        Err(ResetRefused::ConditionPresent(only(
            FaultCode::EStopPressed
        )))
    );
    // Released: still latched.
    let v = sup.check(&healthy_input(1));
    assert_eq!(v.reaction, Reaction::DisableMotors);
    assert!(v.new.is_empty());
    // Not in a safe posture: refused.
    assert_eq!(sup.request_reset(false), Err(ResetRefused::NotSafePosture));
    assert_eq!(
        sup.check(&healthy_input(2)).reaction,
        Reaction::DisableMotors
    );
    // Safe and gone: accepted, and the next verdict is clear.
    assert_eq!(sup.request_reset(true), Ok(()));
    assert!(sup.latched().is_empty());
    let v = sup.check(&healthy_input(3));
    assert_eq!(v.reaction, Reaction::None);
    assert!(v.latched.is_empty());
}

#[test]
fn debounced_fault_resets_only_after_its_window_clears() {
    let (mut sup, _) = inject(3, |_, input| {
        input.joints[1].status = EncoderStatus::BusError
    });
    assert!(sup.latched().contains(FaultCode::EncoderBusError));
    let start = WARMUP + 3;
    // Three bad frames stay in the 100-tick window for 97 more ticks.
    for k in 0..96 {
        sup.check(&healthy_input(start + k));
        assert!(matches!(
            sup.request_reset(true),
            Err(ResetRefused::ConditionPresent(_))
        ));
    }
    sup.check(&healthy_input(start + 96));
    sup.check(&healthy_input(start + 97));
    assert_eq!(sup.request_reset(true), Ok(()));
    assert_eq!(
        sup.check(&healthy_input(start + 98)).reaction,
        Reaction::None
    );
}

#[test]
fn a_fault_that_returns_latches_again() {
    let mut sup = supervisor();
    let mut input = healthy_input(0);
    input.button_input_fault = true;
    sup.check(&input);
    sup.check(&healthy_input(1));
    assert_eq!(sup.request_reset(true), Ok(()));
    let v = sup.check(&input);
    assert_eq!(v.new, only(FaultCode::ButtonInputFault));
    assert_eq!(v.reaction, Reaction::FinishStepThenHold);
}

#[test]
fn reset_with_nothing_latched_is_accepted() {
    let mut sup = supervisor();
    sup.check(&healthy_input(0));
    assert_eq!(sup.request_reset(true), Ok(()));
}

// ------------------------------------------------------------- severity

#[test]
fn the_most_severe_reaction_wins() {
    assert!(Reaction::None < Reaction::FinishStepThenHold);
    assert!(Reaction::FinishStepThenHold < Reaction::SafeHold);
    assert!(Reaction::SafeHold < Reaction::DisableMotors);

    let (_, v) = inject(2, |k, input| {
        input.button_input_fault = true;
        if k == 2 {
            input.motors[0].thermal_fault = true;
        }
    });
    assert_eq!(v[0].reaction, Reaction::FinishStepThenHold);
    assert_eq!(v[1].reaction, Reaction::SafeHold);
    assert_eq!(v[1].new, only(FaultCode::MotorThermal));

    // A warning after a fatal fault does not lower the reaction.
    let (_, v) = inject(2, |k, input| {
        input.e_stop_pressed = k == 1;
        input.button_input_fault = k == 2;
    });
    assert_eq!(v[0].reaction, Reaction::DisableMotors);
    assert_eq!(v[1].reaction, Reaction::DisableMotors);
    assert_eq!(v[1].latched.len(), 2);
}

// ------------------------------------------------------------------ log

#[test]
fn the_log_keeps_the_newest_records() {
    let mut sup = supervisor();
    let mut tick = 0;
    let cycles = LOG_LEN as u32 + 8;
    for _ in 0..cycles {
        let mut input = healthy_input(tick);
        input.e_stop_pressed = true;
        sup.check(&input);
        tick += 1;
        sup.check(&healthy_input(tick));
        tick += 1;
        assert_eq!(sup.request_reset(true), Ok(()));
    }
    let records: Vec<_> = sup.log().copied().collect();
    assert_eq!(records.len(), LOG_LEN);
    // Oldest first, and the 8 oldest cycles are gone.
    let ticks: Vec<u32> = records.iter().map(|r| r.tick).collect();
    let expected: Vec<u32> = (8..cycles).map(|c| 2 * c).collect();
    assert_eq!(ticks, expected);
    assert!(records.iter().all(|r| r.code == FaultCode::EStopPressed));
    assert!(records.iter().all(|r| r.channel == NO_CHANNEL));
}

#[test]
fn the_log_records_each_channel_once_while_latched() {
    let (sup, _) = inject(20, |k, input| {
        input.motors[0].thermal_fault = true;
        if k > 10 {
            input.motors[3].thermal_fault = true;
        }
    });
    let records: Vec<_> = sup.log().copied().collect();
    assert_eq!(records.len(), 2, "{records:?}");
    assert_eq!(records[0].channel, 0);
    assert_eq!(records[1].channel, 3);
    assert_eq!(records[1].tick, WARMUP + 10);
    assert!(records.iter().all(|r| r.code == FaultCode::MotorThermal));
}

#[test]
fn sizes_are_small() {
    // The supervisor lives in a static on the board: keep it small.
    assert!(core::mem::size_of::<Supervisor>() < 2048);
    assert_eq!(FORCES, 4);
}

#[test]
fn the_physical_jump_bound_is_the_fastest_velocity_limit_over_one_tick() {
    let mut cfg = SupervisorConfig::paper();
    cfg.dt_s = 0.001;
    cfg.velocity_limit_rad_s = [6.0, 8.0, 6.0, 8.0];
    // 8 rad/s × 1 ms = 20.9 counts of 16,384 per turn.
    assert_eq!(cfg.physical_jump_counts(), 21);
    cfg.velocity_limit_rad_s = [6.0, 12.0, 6.0, 8.0];
    assert_eq!(cfg.physical_jump_counts(), 32);
    // Unusable limits leave the configured bound.
    cfg.velocity_limit_rad_s = [f32::NAN; JOINTS];
    assert_eq!(cfg.physical_jump_counts(), cfg.max_jump_counts_per_tick);
}

// ------------------------------------------------------ faults found at boot

#[test]
fn a_boot_fault_latches_before_the_first_tick_and_no_reset_clears_it() {
    for (code, reaction) in [
        (FaultCode::BundleRefused, Reaction::SafeHold),
        (FaultCode::CalibrationRefused, Reaction::DisableMotors),
    ] {
        let mut sup = supervisor();
        sup.report_boot_fault(code);
        assert!(sup.latched().contains(code));
        // Whatever the sensors say, the condition stays present.
        for tick in 0..2_000 {
            let v = sup.check(&healthy_input(tick));
            assert_eq!(v.reaction, reaction, "{code:?} tick {tick}");
            assert!(v.latched.contains(code));
        }
        assert!(sup.present().contains(code));
        assert!(sup.request_reset(true).is_err(), "{code:?} was reset");
        assert!(sup.latched().contains(code));
        assert_eq!(sup.log().filter(|r| r.code == code).count(), 1);
    }
}

#[test]
fn the_replanners_faults_are_logged_once_a_reset_and_never_latched() {
    let mut sup = supervisor();
    sup.log_played_table(10, FaultCode::ReplanLate);
    sup.log_played_table(500, FaultCode::ReplanRefused);
    sup.log_played_table(900, FaultCode::ReplanLate);
    let v = sup.check(&healthy_input(901));
    assert_eq!(v.reaction, Reaction::None);
    assert!(v.latched.is_empty() && sup.latched().is_empty());
    // Each code's first occurrence is a record (a run of late answers
    // keeps the older records).
    let logged: Vec<_> = sup.log().map(|r| (r.tick, r.code)).collect();
    assert_eq!(
        logged,
        [(10, FaultCode::ReplanLate), (500, FaultCode::ReplanRefused)]
    );
    // After a reset the next one is recorded again.
    assert_eq!(sup.request_reset(true), Ok(()));
    sup.log_played_table(1200, FaultCode::ReplanLate);
    assert_eq!(sup.log().count(), 3);
    // Their reaction sits between none and finishing the step.
    let mut set = FaultSet::EMPTY;
    set.insert(FaultCode::ReplanLate);
    assert_eq!(set.reaction(), Reaction::PlayTable);
    set.insert(FaultCode::AnklePositionLimit);
    assert_eq!(set.reaction(), Reaction::FinishStepThenHold);
}

#[test]
fn a_fault_of_another_reaction_given_as_played_latches() {
    let mut sup = supervisor();
    sup.log_played_table(7, FaultCode::TrackingError);
    assert!(sup.latched().contains(FaultCode::TrackingError));
    assert_eq!(sup.log().count(), 1);
}
