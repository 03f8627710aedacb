//! A simulated sign-magnitude H-bridge driving one joint motor: a PWM
//! channel (magnitude), a direction pin and an enable pin.
//!
//! The joint torque it is asked for is
//! `enable · (direction high ? +1 : −1) · duty / max_duty · full_scale_torque_nm`
//! (N·m at the joint, anatomical flexion positive), the meaning of
//! gait-control's `MotorConfig::full_scale_torque_nm` and of its direction
//! pin (high = positive torque).
//!
//! With a drive ([`SimMotor::with_drive`], the device's
//! `exogait_device::drive::DriveSpec`) the torque it puts out is what that
//! drive can: at most the peak torque; while driving, no more than the
//! supply can push through the winding against the back-EMF at the joint's
//! speed (the torque–speed line); and, like the amplifier's own I²t
//! protection, derated linearly from the device's warning level to its
//! fault level, where the current is held at the derated limit. The current
//! loop's own dynamics, friction and the rotor's reflected inertia are not
//! modelled (docs/device.md).
//!
//! The three parts are separate values (the driver owns them) that share
//! one bridge state; the harness keeps a [`SimMotor`] handle to read the
//! torque and inject faults.

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::digital::{self, OutputPin};
use embedded_hal::pwm::{self, SetDutyCycle};
use exogait_device::drive::DriveSpec;
use gait_control::drivers::motor::MotorConfig;

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
    drive: Option<Drive>,
    /// Fault: share of the current asked the amplifier still gives (1
    /// healthy): its monitor reads it.
    strength: f64,
    /// Fault: share of the motor's torque the gearbox passes to the joint
    /// (1 healthy): a slipping gear; the current stays what was asked.
    gear_share: f64,
    /// Fault: the set value stuck at this torque whatever is commanded
    /// (while enabled).
    stuck_nm: Option<f64>,
}

/// The drive behind a bridge and its thermal state.
#[derive(Clone, Copy, Debug)]
struct Drive {
    spec: DriveSpec,
    /// The device's I²t levels and derated limit (the motor driver's).
    limits: MotorConfig,
    /// ∫(I² − I_nom²) dt, clamped at 0, A²·s.
    i2t_a2s: f64,
    /// The joint's speed, rad/s (flexion positive).
    joint_speed_rad_s: f64,
}

impl Drive {
    /// The torque magnitude the drive allows now in direction `sign`, N·m.
    fn limit_nm(&self, sign: f64) -> f64 {
        let speed = f64::from(
            self.spec
                .available_torque_nm(self.joint_speed_rad_s as f32, sign as f32),
        );
        let l = &self.limits;
        let (warn, fault) = (f64::from(l.i2t_warning_a2s), f64::from(l.i2t_fault_a2s));
        let peak = f64::from(l.torque_limit_nm);
        let derated = f64::from(l.derated_limit_nm);
        let thermal = if self.i2t_a2s <= warn {
            peak
        } else if self.i2t_a2s >= fault {
            derated
        } else {
            peak - (peak - derated) * (self.i2t_a2s - warn) / (fault - warn)
        };
        speed.min(thermal)
    }
}

impl Bridge {
    /// The torque the bridge is asked for, N·m.
    fn commanded_nm(&self) -> f64 {
        if !self.enable_high {
            return 0.0;
        }
        let sign = if self.dir_high { 1.0 } else { -1.0 };
        sign * f64::from(self.duty) / f64::from(self.max_duty) * self.full_scale_torque_nm
    }

    /// The torque it puts out at the joint's last published speed, N·m:
    /// the driven torque, or the brake's.
    fn torque_nm(&self) -> f64 {
        let speed = self.drive.map_or(0.0, |d| d.joint_speed_rad_s);
        self.driven_nm() - self.brake_damping() * speed
    }

    /// The torque the power stage drives, N·m: none while disabled (the
    /// enable line switches it off whatever the set value, a stuck one
    /// included: the ESCON's enable input).
    fn driven_nm(&self) -> f64 {
        if !self.enable_high {
            return 0.0;
        }
        self.amplifier_nm() * self.gear_share
    }

    /// The dynamic brake's damping now, N·m·s/rad: the drive's while the
    /// bridge is disabled (its contactor closes), none while enabled.
    fn brake_damping(&self) -> f64 {
        match self.drive {
            Some(d) if !self.enable_high => f64::from(d.spec.brake_damping_nm_s_per_rad()),
            _ => 0.0,
        }
    }

    /// The joint torque the amplifier's current gives while enabled, N·m
    /// (before the gearbox's share).
    fn amplifier_nm(&self) -> f64 {
        if let Some(t) = self.stuck_nm {
            return t;
        }
        let asked = self.commanded_nm();
        let out = match &self.drive {
            Some(d) => {
                let limit = d.limit_nm(asked.signum());
                asked.clamp(-limit, limit)
            }
            None => asked,
        };
        out * self.strength
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
            drive: None,
            strength: 1.0,
            gear_share: 1.0,
            stuck_nm: None,
        })))
    }

    /// A bridge in front of `spec`, with the device's motor-driver settings
    /// `limits` (full scale, I²t levels, derated limit).
    pub fn with_drive(max_duty: u16, spec: DriveSpec, limits: MotorConfig) -> Self {
        let m = Self::new(max_duty, f64::from(limits.full_scale_torque_nm));
        m.0.borrow_mut().drive = Some(Drive {
            spec,
            limits,
            i2t_a2s: 0.0,
            joint_speed_rad_s: 0.0,
        });
        m
    }

    /// The joint's speed now, rad/s (the torque–speed line uses it).
    pub fn set_joint_speed(&self, rad_s: f64) {
        if let Some(d) = self.0.borrow_mut().drive.as_mut() {
            d.joint_speed_rad_s = if rad_s.is_finite() { rad_s } else { 0.0 };
        }
    }

    /// Advances the drive's winding model by `dt_s` at the present output.
    pub fn integrate_thermal(&self, dt_s: f64) {
        // The amplifier's own I²t counts the current it drives; the
        // brake's flows through the contactor, which it does not see.
        let out = self.driven_torque_nm();
        let mut b = self.0.borrow_mut();
        if let Some(d) = b.drive.as_mut() {
            let i = out / f64::from(d.spec.joint_torque_per_amp());
            let nominal = f64::from(d.spec.continuous_current_a());
            d.i2t_a2s = (d.i2t_a2s + (i * i - nominal * nominal) * dt_s).max(0.0);
        }
    }

    /// The winding model's ∫(I² − I_nom²) dt now, A²·s (0 without a drive).
    pub fn i2t_a2s(&self) -> f64 {
        self.0.borrow().drive.map_or(0.0, |d| d.i2t_a2s)
    }

    /// The drive behind the bridge, if it models one.
    pub fn drive_spec(&self) -> Option<DriveSpec> {
        self.0.borrow().drive.map(|d| d.spec)
    }

    /// The torque asked for (before the drive's limits), N·m.
    pub fn commanded_nm(&self) -> f64 {
        self.0.borrow().commanded_nm()
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

    /// The joint torque the bridge produces now, N·m: what it drives, or
    /// while disabled its brake's at the joint's last published speed.
    pub fn torque_nm(&self) -> f64 {
        self.0.borrow().torque_nm()
    }

    /// The torque the power stage drives now, N·m (none while disabled);
    /// the plant takes it with [`SimMotor::brake_damping_nm_s_per_rad`].
    pub fn driven_torque_nm(&self) -> f64 {
        self.0.borrow().driven_nm()
    }

    /// The dynamic brake's damping now, N·m·s/rad: the drive's full
    /// damping while the bridge is disabled, none while enabled or without
    /// a drive. The plant applies it at every stage of its integration
    /// ([`crate::plant::Plant::set_brakes`]), as the contactor does
    /// continuously.
    pub fn brake_damping_nm_s_per_rad(&self) -> f64 {
        self.0.borrow().brake_damping()
    }

    /// The joint torque the amplifier's own current gives now, N·m: what
    /// its current monitor reports. While disabled, none (the brake's
    /// current flows through the contactor, not the amplifier).
    pub fn amplifier_torque_nm(&self) -> f64 {
        let b = self.0.borrow();
        if b.enable_high { b.amplifier_nm() } else { 0.0 }
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

    /// Fault: the amplifier gives only `fraction` (0 … 1) of the current
    /// asked (a failing power stage, a lost phase, a current limit set
    /// low): the joint gets that share of its torque, and the current
    /// monitor reads it.
    pub fn weaken(&self, fraction: f64) {
        self.0.borrow_mut().strength = if fraction.is_finite() {
            fraction.clamp(0.0, 1.0)
        } else {
            0.0
        };
    }

    /// Fault: the gearbox passes only `fraction` (0 … 1) of the motor's
    /// torque (a strain-wave gear ratcheting, a slipping coupling): the
    /// current, and so the current monitor, stay what was asked.
    pub fn slip_gear(&self, fraction: f64) {
        self.0.borrow_mut().gear_share = if fraction.is_finite() {
            fraction.clamp(0.0, 1.0)
        } else {
            0.0
        };
    }

    /// Fault: the drive's set value sticks at the torque it gives now
    /// (its PWM input or its own controller frozen), whatever is commanded.
    /// The enable line still switches its power stage off (the ESCON's
    /// enable is a separate input): disabled, the brake holds the joint.
    pub fn stick(&self) {
        let now = if self.0.borrow().enable_high {
            self.torque_nm()
        } else {
            0.0
        };
        self.0.borrow_mut().stuck_nm = Some(now);
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
