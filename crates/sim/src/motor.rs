//! A simulated sign-magnitude H-bridge driving one joint motor: a PWM
//! channel (magnitude), a direction pin and an enable pin.
//!
//! The joint torque it produces is
//! `enable · (direction high ? +1 : −1) · duty / max_duty · full_scale_torque_nm`
//! (N·m at the joint, anatomical flexion positive), the meaning of
//! gait-control's `MotorConfig::full_scale_torque_nm` and of its direction
//! pin (high = positive torque). Electrical and mechanical dynamics of the
//! motor (current loop, back-EMF, friction) are not modelled: the bridge is
//! an ideal torque source, updated as soon as a pin or duty changes.
//!
//! The three parts are separate values (the driver owns them) that share
//! one bridge state; the harness keeps a [`SimMotor`] handle to read the
//! torque and inject faults.

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::digital::{self, OutputPin};
use embedded_hal::pwm::{self, SetDutyCycle};

/// A simulated PWM failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimPwmError {
    /// Injected failure.
    Injected,
    /// The duty asked for is above the maximum.
    DutyAboveMax {
        /// The duty asked for.
        duty: u16,
    },
}

impl pwm::Error for SimPwmError {
    fn kind(&self) -> pwm::ErrorKind {
        pwm::ErrorKind::Other
    }
}

impl core::fmt::Display for SimPwmError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Injected => f.write_str("simulated PWM failure"),
            Self::DutyAboveMax { duty } => write!(f, "duty {duty} above the maximum"),
        }
    }
}

impl std::error::Error for SimPwmError {}

/// A simulated GPIO failure (injected).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SimPinError;

impl digital::Error for SimPinError {
    fn kind(&self) -> digital::ErrorKind {
        digital::ErrorKind::Other
    }
}

impl core::fmt::Display for SimPinError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("simulated pin failure")
    }
}

impl std::error::Error for SimPinError {}

#[derive(Debug)]
struct Bridge {
    full_scale_torque_nm: f64,
    max_duty: u16,
    duty: u16,
    dir_high: bool,
    enable_high: bool,
    pwm_errors: u32,
    dir_errors: u32,
    enable_errors: u32,
    reversals_under_duty: u32,
    writes: u64,
}

impl Bridge {
    fn torque_nm(&self) -> f64 {
        if !self.enable_high {
            return 0.0;
        }
        let sign = if self.dir_high { 1.0 } else { -1.0 };
        sign * f64::from(self.duty) / f64::from(self.max_duty) * self.full_scale_torque_nm
    }
}

/// The harness's handle on one motor bridge.
#[derive(Clone, Debug)]
pub struct SimMotor(Rc<RefCell<Bridge>>);

/// The bridge's PWM input ([`SetDutyCycle`]).
#[derive(Debug)]
pub struct SimPwm(Rc<RefCell<Bridge>>);

/// Which pin of the bridge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BridgePin {
    /// Direction: high = positive (flexion) torque.
    Direction,
    /// Enable: high = bridge on.
    Enable,
}

/// A bridge input pin ([`OutputPin`]).
#[derive(Debug)]
pub struct SimBridgePin {
    bridge: Rc<RefCell<Bridge>>,
    which: BridgePin,
}

impl SimMotor {
    /// A bridge with `max_duty` PWM steps and `full_scale_torque_nm` at
    /// 100 % duty; powers up disabled, duty 0, direction low.
    pub fn new(max_duty: u16, full_scale_torque_nm: f64) -> Self {
        Self(Rc::new(RefCell::new(Bridge {
            full_scale_torque_nm,
            max_duty: max_duty.max(1),
            duty: 0,
            dir_high: false,
            enable_high: false,
            pwm_errors: 0,
            dir_errors: 0,
            enable_errors: 0,
            reversals_under_duty: 0,
            writes: 0,
        })))
    }

    /// The PWM channel to give the driver.
    pub fn pwm(&self) -> SimPwm {
        SimPwm(Rc::clone(&self.0))
    }

    /// The direction pin to give the driver.
    pub fn direction_pin(&self) -> SimBridgePin {
        SimBridgePin {
            bridge: Rc::clone(&self.0),
            which: BridgePin::Direction,
        }
    }

    /// The enable pin to give the driver.
    pub fn enable_pin(&self) -> SimBridgePin {
        SimBridgePin {
            bridge: Rc::clone(&self.0),
            which: BridgePin::Enable,
        }
    }

    /// The joint torque the bridge produces now, N·m.
    pub fn torque_nm(&self) -> f64 {
        self.0.borrow().torque_nm()
    }

    /// (duty, direction high, enable high).
    pub fn outputs(&self) -> (u16, bool, bool) {
        let b = self.0.borrow();
        (b.duty, b.dir_high, b.enable_high)
    }

    /// Times the direction flipped while enabled with a non-zero duty (a
    /// driver should reverse through zero duty).
    pub fn reversals_under_duty(&self) -> u32 {
        self.0.borrow().reversals_under_duty
    }

    /// Successful writes to the PWM and pins.
    pub fn writes(&self) -> u64 {
        self.0.borrow().writes
    }

    /// Fault: the next `n` duty writes fail.
    pub fn fail_pwm_writes(&self, n: u32) {
        self.0.borrow_mut().pwm_errors = n;
    }

    /// Fault: the next `n` writes to `pin` fail (the pin keeps its level).
    pub fn fail_pin_writes(&self, pin: BridgePin, n: u32) {
        let mut b = self.0.borrow_mut();
        match pin {
            BridgePin::Direction => b.dir_errors = n,
            BridgePin::Enable => b.enable_errors = n,
        }
    }
}

impl pwm::ErrorType for SimPwm {
    type Error = SimPwmError;
}

impl SetDutyCycle for SimPwm {
    fn max_duty_cycle(&self) -> u16 {
        self.0.borrow().max_duty
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), SimPwmError> {
        let mut b = self.0.borrow_mut();
        if b.pwm_errors > 0 {
            b.pwm_errors -= 1;
            return Err(SimPwmError::Injected);
        }
        if duty > b.max_duty {
            return Err(SimPwmError::DutyAboveMax { duty });
        }
        b.duty = duty;
        b.writes += 1;
        Ok(())
    }
}

impl digital::ErrorType for SimBridgePin {
    type Error = SimPinError;
}

impl SimBridgePin {
    fn write(&mut self, high: bool) -> Result<(), SimPinError> {
        let mut b = self.bridge.borrow_mut();
        let errors = match self.which {
            BridgePin::Direction => &mut b.dir_errors,
            BridgePin::Enable => &mut b.enable_errors,
        };
        if *errors > 0 {
            *errors -= 1;
            return Err(SimPinError);
        }
        match self.which {
            BridgePin::Direction => {
                if b.dir_high != high && b.enable_high && b.duty != 0 {
                    b.reversals_under_duty += 1;
                }
                b.dir_high = high;
            }
            BridgePin::Enable => b.enable_high = high,
        }
        b.writes += 1;
        Ok(())
    }
}

impl OutputPin for SimBridgePin {
    fn set_low(&mut self) -> Result<(), SimPinError> {
        self.write(false)
    }

    fn set_high(&mut self) -> Result<(), SimPinError> {
        self.write(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torque_follows_pins_and_duty() {
        let m = SimMotor::new(1000, 80.0);
        let mut pwm = m.pwm();
        let mut dir = m.direction_pin();
        let mut en = m.enable_pin();
        pwm.set_duty_cycle(500).unwrap_or_else(|_| unreachable!());
        assert_eq!(m.torque_nm(), 0.0); // disabled
        en.set_high().unwrap_or_else(|_| unreachable!());
        assert!((m.torque_nm() + 40.0).abs() < 1e-12); // dir low = negative
        dir.set_high().unwrap_or_else(|_| unreachable!());
        assert!((m.torque_nm() - 40.0).abs() < 1e-12);
        assert_eq!(m.reversals_under_duty(), 1);
        assert!(pwm.set_duty_cycle(1001).is_err());
    }
}
