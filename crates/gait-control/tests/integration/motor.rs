//! Motor output: exact pin/PWM sequences, limits, thermal model, faults.

use std::io::ErrorKind;

use crate::common::{RecordingPin, RecordingPwm};
use embedded_hal_mock::eh1::MockError;
use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as PinT};
use embedded_hal_mock::eh1::pwm::{Mock as PwmMock, Transaction as PwmT};
use gait_control::drivers::motor::{ConfigError, Error, Fault, Motor, MotorConfig};
use proptest::prelude::*;

/// I = τ / 10 A; continuous 2 A ↔ 20 N·m.
const CFG: MotorConfig = MotorConfig {
    torque_limit_nm: 40.0,
    full_scale_torque_nm: 50.0,
    torque_constant_nm_per_a: 0.1,
    gear_ratio: 100.0,
    continuous_current_a: 2.0,
    i2t_warning_a2s: 5.0,
    i2t_fault_a2s: 10.0,
    derated_limit_nm: 25.0,
    slew_nm_per_tick: 5.0,
    soft_start_ticks: 4,
    dt_s: 0.001,
};

type MockMotor = Motor<PwmMock, PinMock, PinMock>;

fn err() -> MockError {
    MockError::Io(ErrorKind::NotConnected)
}

fn new_motor(pwm: &[PwmT], dir: &[PinT], en: &[PinT]) -> MockMotor {
    let mut p = vec![PwmT::max_duty_cycle(1000)];
    p.extend_from_slice(pwm);
    Motor::new(PwmMock::new(&p), PinMock::new(dir), PinMock::new(en), CFG).unwrap()
}

fn destroy_motor(m: MockMotor) {
    let (mut p, mut d, mut e) = m.destroy();
    p.done();
    d.done();
    e.done();
}

#[test]
fn enable_writes_zero_then_direction_then_enable() {
    let mut m = new_motor(
        &[PwmT::set_duty_cycle(0)],
        &[PinT::set(State::High)],
        &[PinT::set(State::High)],
    );
    m.enable().unwrap();
    assert!(m.is_enabled());
    destroy_motor(m);
}

#[test]
fn soft_start_slew_reversal_and_nan() {
    let duties = [0, 100, 200, 100, 0, 0, 100, 0];
    let mut m = new_motor(
        &[
            PwmT::set_duty_cycle(0), // enable
            PwmT::set_duty_cycle(duties[0]),
            PwmT::set_duty_cycle(duties[1]),
            PwmT::set_duty_cycle(duties[2]),
            PwmT::set_duty_cycle(duties[3]),
            PwmT::set_duty_cycle(duties[4]),
            // reversal: zero, direction, new duty
            PwmT::set_duty_cycle(duties[5]),
            PwmT::set_duty_cycle(duties[6]),
            PwmT::set_duty_cycle(duties[7]),
        ],
        &[PinT::set(State::High), PinT::set(State::Low)],
        &[PinT::set(State::High)],
    );
    m.enable().unwrap();
    // First tick after enable: exactly zero whatever the command.
    let r = m.update(40.0).unwrap();
    assert_eq!((r.applied_nm, r.duty, r.limited), (0.0, 0, true));
    // Soft start 1/4 of 40 = 10, slew 5 per tick.
    assert_eq!(m.update(40.0).unwrap().applied_nm, 5.0);
    assert_eq!(m.update(40.0).unwrap().applied_nm, 10.0);
    // Slew limits the way down too.
    assert_eq!(m.update(-40.0).unwrap().applied_nm, 5.0);
    assert_eq!(m.update(-40.0).unwrap().applied_nm, 0.0);
    let r = m.update(-40.0).unwrap();
    assert_eq!((r.applied_nm, r.duty), (-5.0, 100));
    // NaN: treated as zero and reported.
    let r = m.update(f32::NAN).unwrap();
    assert!(r.rejected_non_finite);
    assert_eq!((r.applied_nm, r.duty), (0.0, 0));
    destroy_motor(m);
}

#[test]
fn disable_drives_enable_low_even_if_pwm_fails() {
    let mut m = new_motor(
        &[PwmT::set_duty_cycle(0).with_error(err())],
        &[],
        &[PinT::set(State::Low)],
    );
    assert!(matches!(m.disable(), Err(Error::Pwm(_))));
    destroy_motor(m);
}

#[test]
fn disable_still_zeroes_pwm_if_enable_pin_fails() {
    let mut m = new_motor(
        &[PwmT::set_duty_cycle(0)],
        &[],
        &[PinT::set(State::Low).with_error(err())],
    );
    assert!(matches!(m.disable(), Err(Error::Pin(_))));
    destroy_motor(m);
}

#[test]
fn pwm_error_in_update_disables_and_latches() {
    let mut m = new_motor(
        &[
            PwmT::set_duty_cycle(0),                   // enable
            PwmT::set_duty_cycle(0).with_error(err()), // tick
            PwmT::set_duty_cycle(0),                   // disable
        ],
        &[PinT::set(State::High)],
        &[PinT::set(State::High), PinT::set(State::Low)],
    );
    m.enable().unwrap();
    assert!(matches!(m.update(1.0), Err(Error::Pwm(_))));
    assert_eq!(m.fault(), Some(Fault::Output));
    assert!(!m.is_enabled());
    // Latched: nothing more is written.
    assert!(matches!(m.update(1.0), Err(Error::OutputFault)));
    assert!(matches!(m.enable(), Err(Error::OutputFault)));
    destroy_motor(m);
}

#[test]
fn direction_pin_error_in_update_disables() {
    let mut m = new_motor(
        &[
            PwmT::set_duty_cycle(0), // enable
            PwmT::set_duty_cycle(0), // tick 1
            PwmT::set_duty_cycle(0), // tick 2: reversal zero
            PwmT::set_duty_cycle(0), // disable
        ],
        &[
            PinT::set(State::High),
            PinT::set(State::Low).with_error(err()),
        ],
        &[PinT::set(State::High), PinT::set(State::Low)],
    );
    m.enable().unwrap();
    m.update(-40.0).unwrap();
    assert!(matches!(m.update(-40.0), Err(Error::Pin(_))));
    assert_eq!(m.fault(), Some(Fault::Output));
    destroy_motor(m);
}

#[test]
fn enable_pin_error_on_enable_disables() {
    let mut m = new_motor(
        &[PwmT::set_duty_cycle(0), PwmT::set_duty_cycle(0)],
        &[PinT::set(State::High)],
        &[
            PinT::set(State::High).with_error(err()),
            PinT::set(State::Low),
        ],
    );
    assert!(matches!(m.enable(), Err(Error::Pin(_))));
    assert!(!m.is_enabled());
    destroy_motor(m);
}

#[test]
fn zero_length_soft_start_still_starts_from_zero() {
    let cfg = MotorConfig {
        soft_start_ticks: 0,
        ..CFG
    };
    let mut m = Motor::new(
        RecordingPwm::new(1000),
        RecordingPin::default(),
        RecordingPin::default(),
        cfg,
    )
    .unwrap();
    m.enable().unwrap();
    assert_eq!(m.update(40.0).unwrap().applied_nm, 0.0);
    assert_eq!(m.update(40.0).unwrap().applied_nm, 5.0);
}

#[test]
fn update_while_disabled_writes_nothing() {
    let mut m = new_motor(&[], &[], &[]);
    let r = m.update(30.0).unwrap();
    assert_eq!((r.applied_nm, r.duty, r.limited), (0.0, 0, true));
    destroy_motor(m);
}

#[test]
fn bad_configs_are_refused() {
    let pwm = RecordingPwm::new(1000);
    let bad = |cfg: MotorConfig| {
        Motor::new(
            pwm.clone(),
            RecordingPin::default(),
            RecordingPin::default(),
            cfg,
        )
        .err()
    };
    assert_eq!(
        bad(MotorConfig {
            torque_limit_nm: f32::NAN,
            ..CFG
        }),
        Some(ConfigError::NotPositive)
    );
    assert_eq!(
        bad(MotorConfig { dt_s: 0.0, ..CFG }),
        Some(ConfigError::NotPositive)
    );
    assert_eq!(
        bad(MotorConfig {
            i2t_warning_a2s: 10.0,
            ..CFG
        }),
        Some(ConfigError::BadThermalLimits)
    );
    assert_eq!(
        bad(MotorConfig {
            derated_limit_nm: 41.0,
            ..CFG
        }),
        Some(ConfigError::BadThermalLimits)
    );
}

#[test]
fn thermal_model_derates_then_faults_then_cools() {
    let pwm = RecordingPwm::new(1000);
    let en = RecordingPin::default();
    let mut m = Motor::new(pwm.clone(), RecordingPin::default(), en.clone(), CFG).unwrap();
    m.enable().unwrap();
    let mut saw_derating = false;
    let mut last_limit = f32::INFINITY;
    let mut faulted_at = None;
    for t in 0..20_000 {
        match m.update(40.0) {
            Ok(r) => {
                let limit = m.thermal_limit_nm();
                assert!(
                    limit <= last_limit + 1e-6,
                    "derating must not recover under load"
                );
                last_limit = limit;
                assert!(r.applied_nm <= CFG.torque_limit_nm);
                if r.derating {
                    saw_derating = true;
                    assert!(r.applied_nm < CFG.torque_limit_nm);
                }
            }
            Err(Error::Thermal) => {
                faulted_at = Some(t);
                break;
            }
            Err(e) => panic!("{e:?}"),
        }
    }
    assert!(saw_derating, "derating must come before the fault");
    let t = faulted_at.expect("sustained overload must fault");
    assert!(t > 400, "not before the warning level: {t}");
    assert_eq!(m.fault(), Some(Fault::Thermal));
    assert!(
        !*en.high.borrow(),
        "enable must be low after a thermal fault"
    );
    assert_eq!(*pwm.log.borrow().last().unwrap(), 0);
    assert!(matches!(m.enable(), Err(Error::Thermal)));
    assert!(matches!(m.reset_fault(), Err(Error::StillHot)));
    // Cools at (0 − 4) A²·s per s: 10 → 5 A²·s takes 1250 ticks.
    let writes = pwm.log.borrow().len();
    for _ in 0..1300 {
        assert!(matches!(m.update(40.0), Err(Error::Thermal)));
    }
    assert_eq!(pwm.log.borrow().len(), writes, "no writes while faulted");
    m.reset_fault().unwrap();
    m.enable().unwrap();
    assert_eq!(m.update(40.0).unwrap().applied_nm, 0.0);
}

fn command() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -100.0f32..100.0,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => any::<f32>(),
    ]
}

proptest! {
    #[test]
    fn output_never_exceeds_limits(cmds in prop::collection::vec(command(), 1..400)) {
        // Low thermal levels so derating and the fault are exercised too.
        let cfg = MotorConfig { i2t_warning_a2s: 0.3, i2t_fault_a2s: 0.6, ..CFG };
        let pwm = RecordingPwm::new(1000);
        let dir = RecordingPin::default();
        let en = RecordingPin::default();
        let mut m = Motor::new(pwm.clone(), dir.clone(), en.clone(), cfg).unwrap();
        m.enable().unwrap();
        let mut prev = 0.0f32;
        let mut first = true;
        let mut faulted = false;
        for c in cmds {
            let limit_before = m.thermal_limit_nm();
            let writes = pwm.log.borrow().len();
            match m.update(c) {
                Ok(r) => {
                    prop_assert!(!faulted);
                    prop_assert!(r.applied_nm.is_finite());
                    prop_assert!(r.applied_nm.abs() <= cfg.torque_limit_nm);
                    prop_assert!(r.applied_nm.abs() <= limit_before + 1e-4);
                    prop_assert!((r.applied_nm - prev).abs() <= cfg.slew_nm_per_tick + 1e-4);
                    prop_assert!(r.duty <= 1000);
                    prop_assert_eq!(r.rejected_non_finite, !c.is_finite());
                    if first {
                        prop_assert_eq!(r.applied_nm, 0.0);
                        prop_assert_eq!(r.duty, 0);
                    }
                    if r.duty > 0 {
                        prop_assert_eq!(*dir.high.borrow(), r.applied_nm > 0.0);
                    }
                    prop_assert_eq!(*pwm.log.borrow().last().unwrap(), r.duty);
                    prev = r.applied_nm;
                }
                Err(Error::Thermal) => {
                    if faulted {
                        prop_assert_eq!(pwm.log.borrow().len(), writes);
                    }
                    faulted = true;
                    prop_assert!(!*en.high.borrow());
                    prop_assert_eq!(*pwm.log.borrow().last().unwrap(), 0);
                }
                Err(e) => prop_assert!(false, "{:?}", e),
            }
            first = false;
        }
    }
}
