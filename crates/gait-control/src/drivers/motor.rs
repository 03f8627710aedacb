//! One joint motor output: torque command (N·m at the joint) → PWM duty, a
//! direction pin and an enable pin (a sign-magnitude H-bridge driver).
//!
//! Everything that limits the torque lives here, at the last point before
//! the hardware, so no upstream bug can bypass it:
//!
//! - non-finite commands (NaN, ±inf) are replaced by zero and reported;
//! - the first command after [`Motor::enable`] is exactly zero, then the
//!   allowed magnitude ramps up linearly over `soft_start_ticks`;
//! - the output changes by at most `slew_nm_per_tick` per tick;
//! - the magnitude saturates at the torque limit, derated by an I²t model.
//!
//! # Thermal model
//!
//! Current is estimated from the *applied* torque,
//! `I = τ / (gear_ratio · k_t)`, and each tick integrates
//! `(I² − I_cont²)·dt` into an accumulator clamped at 0 (A²·s). Above
//! `i2t_warning_a2s` the torque limit falls linearly to `derated_limit_nm`
//! at `i2t_fault_a2s`; the derated limit is above the continuous torque on
//! purpose, so sustained demand still reaches the fault level: the output is
//! then disabled and [`Error::Thermal`] latched. The model keeps cooling
//! while disabled, and [`Motor::reset_fault`] is refused until the
//! accumulator is back below the warning level.
//!
//! The model sees only the commanded torque: current from back-EMF, friction
//! compensation elsewhere, or a stalled joint is not in it, so the levels
//! must be set with margin from the motor's datasheet. With
//! `derated_limit_nm` at or below the continuous torque the accumulator
//! settles below the fault level instead of faulting (still safe).
//!
//! Any failed PWM or pin write also disables the output (best effort) and
//! latches [`Fault::Output`]: a motor whose duty we cannot set must not run.

use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;
use gait_core::scalar::clamp_f32;

/// Motor and drive parameters. Torques are at the joint (after the gear).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MotorConfig {
    /// Magnitude limit of the joint torque, N·m.
    pub torque_limit_nm: f32,
    /// Joint torque at 100 % duty, N·m (drive calibration).
    pub full_scale_torque_nm: f32,
    /// Motor torque constant k_t, N·m/A.
    pub torque_constant_nm_per_a: f32,
    /// Gear ratio (motor turns per joint turn), > 0.
    pub gear_ratio: f32,
    /// Rated continuous motor current, A.
    pub continuous_current_a: f32,
    /// I²t level (A²·s above continuous) at which derating starts.
    pub i2t_warning_a2s: f32,
    /// I²t level at which the output is disabled and the fault latched.
    pub i2t_fault_a2s: f32,
    /// Torque limit reached at the fault level (linear derating), N·m.
    pub derated_limit_nm: f32,
    /// Maximum change of the applied torque per tick, N·m.
    pub slew_nm_per_tick: f32,
    /// Ticks over which the allowed magnitude ramps from 0 after enable (the
    /// first tick after enable is always zero, even when this is 0).
    pub soft_start_ticks: u32,
    /// Tick period, s (0.001 at 1 kHz).
    pub dt_s: f32,
}

/// Why a configuration was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// A value is not finite or not strictly positive where it must be.
    NotPositive,
    /// Warning ≥ fault level, or derated limit outside (0, torque limit].
    BadThermalLimits,
}

impl MotorConfig {
    /// Checks the configuration once so the tick need not.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let positive = [
            self.torque_limit_nm,
            self.full_scale_torque_nm,
            self.torque_constant_nm_per_a,
            self.gear_ratio,
            self.continuous_current_a,
            self.i2t_fault_a2s,
            self.derated_limit_nm,
            self.slew_nm_per_tick,
            self.dt_s,
        ];
        let all_positive = positive.iter().all(|v| v.is_finite() && *v > 0.0);
        let warning_ok = self.i2t_warning_a2s.is_finite() && self.i2t_warning_a2s >= 0.0;
        if !(all_positive && warning_ok) {
            return Err(ConfigError::NotPositive);
        }
        if self.i2t_warning_a2s >= self.i2t_fault_a2s
            || self.derated_limit_nm > self.torque_limit_nm
        {
            return Err(ConfigError::BadThermalLimits);
        }
        Ok(())
    }
}

/// Latched faults; the output is disabled while one is set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Fault {
    /// The I²t accumulator reached the fault level.
    Thermal,
    /// A PWM or pin write failed.
    Output,
}

/// Driver errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<PwmE, PinE> {
    /// The PWM peripheral refused a duty.
    Pwm(PwmE),
    /// A direction or enable pin write failed.
    Pin(PinE),
    /// The thermal model latched a fault (this tick or earlier).
    Thermal,
    /// An output fault is latched (a write failed earlier); the output is
    /// disabled until `reset_fault` and `enable`.
    OutputFault,
    /// `reset_fault` refused: the winding model is still above warning.
    StillHot,
}

/// What one tick did, for logging and the supervisor.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TickReport {
    /// Joint torque actually commanded, N·m.
    pub applied_nm: f32,
    /// Duty written to the PWM.
    pub duty: u16,
    /// The command was NaN or infinite and was replaced by zero.
    pub rejected_non_finite: bool,
    /// The command was reduced by saturation, soft start or slew limit.
    pub limited: bool,
    /// The I²t model is above warning and derating the limit.
    pub derating: bool,
}

/// One motor output.
#[derive(Debug)]
pub struct Motor<PWM, DIR, EN> {
    pwm: PWM,
    dir: DIR,
    en: EN,
    cfg: MotorConfig,
    max_duty: u16,
    enabled: bool,
    fault: Option<Fault>,
    /// Direction pin state last written (`true` = high = positive torque).
    dir_positive: bool,
    applied_nm: f32,
    ticks_since_enable: u32,
    i2t_a2s: f32,
}

impl<PWM, DIR, EN, PwmE, PinE> Motor<PWM, DIR, EN>
where
    PWM: SetDutyCycle<Error = PwmE>,
    DIR: OutputPin<Error = PinE>,
    EN: OutputPin<Error = PinE>,
{
    /// The configuration it limits with.
    pub fn config(&self) -> &MotorConfig {
        &self.cfg
    }

    /// Takes the pins and checks the configuration. Reads the PWM's maximum
    /// duty once. Writes nothing: call [`Motor::disable`] first thing at
    /// boot (the board also holds enable low in hardware).
    pub fn new(pwm: PWM, dir: DIR, en: EN, cfg: MotorConfig) -> Result<Self, ConfigError> {
        cfg.validate()?;
        let max_duty = pwm.max_duty_cycle();
        Ok(Self {
            pwm,
            dir,
            en,
            cfg,
            max_duty,
            enabled: false,
            fault: None,
            dir_positive: true,
            applied_nm: 0.0,
            ticks_since_enable: 0,
            i2t_a2s: 0.0,
        })
    }

    /// Gives the peripherals back.
    pub fn destroy(self) -> (PWM, DIR, EN) {
        (self.pwm, self.dir, self.en)
    }

    /// Drives enable low, then tries to zero the duty. Enable is driven low
    /// even if the duty write fails; the first error is returned.
    pub fn disable(&mut self) -> Result<(), Error<PwmE, PinE>> {
        self.enabled = false;
        self.applied_nm = 0.0;
        let en = self.en.set_low().map_err(Error::Pin);
        let pwm = self.pwm.set_duty_cycle(0).map_err(Error::Pwm);
        en.and(pwm)
    }

    /// Enables the bridge with exactly zero duty, direction positive; starts
    /// the soft-start ramp. Refused while a fault is latched.
    pub fn enable(&mut self) -> Result<(), Error<PwmE, PinE>> {
        match self.fault {
            Some(Fault::Thermal) => return Err(Error::Thermal),
            Some(Fault::Output) => return Err(Error::OutputFault),
            None => {}
        }
        let result = self
            .pwm
            .set_duty_cycle(0)
            .map_err(Error::Pwm)
            .and_then(|()| self.dir.set_high().map_err(Error::Pin))
            .and_then(|()| self.en.set_high().map_err(Error::Pin));
        if let Err(e) = result {
            self.fault_output();
            return Err(e);
        }
        self.dir_positive = true;
        self.applied_nm = 0.0;
        self.ticks_since_enable = 0;
        self.enabled = true;
        Ok(())
    }

    /// Clears a latched fault once the thermal model has cooled below the
    /// warning level. The output stays disabled until [`Motor::enable`].
    pub fn reset_fault(&mut self) -> Result<(), Error<PwmE, PinE>> {
        if self.i2t_a2s > self.cfg.i2t_warning_a2s && self.fault.is_some() {
            return Err(Error::StillHot);
        }
        self.fault = None;
        Ok(())
    }

    /// The latched fault, if any.
    pub const fn fault(&self) -> Option<Fault> {
        self.fault
    }

    /// Whether the bridge is enabled.
    pub const fn is_enabled(&self) -> bool {
        self.enabled
    }

    /// Enabled and past the soft start: the drive gives the torque it is
    /// asked for (up to its limits).
    pub const fn at_full_authority(&self) -> bool {
        self.enabled && self.ticks_since_enable > self.cfg.soft_start_ticks
    }

    /// The I²t accumulator, A²·s above continuous.
    pub const fn i2t_a2s(&self) -> f32 {
        self.i2t_a2s
    }

    /// The torque applied at the last tick, N·m.
    pub const fn applied_nm(&self) -> f32 {
        self.applied_nm
    }

    /// The torque limit the thermal model currently allows, N·m.
    #[must_use]
    pub fn thermal_limit_nm(&self) -> f32 {
        let c = &self.cfg;
        if self.i2t_a2s <= c.i2t_warning_a2s {
            return c.torque_limit_nm;
        }
        let frac = ((self.i2t_a2s - c.i2t_warning_a2s) / (c.i2t_fault_a2s - c.i2t_warning_a2s))
            .clamp(0.0, 1.0);
        c.torque_limit_nm - frac * (c.torque_limit_nm - c.derated_limit_nm)
    }

    fn fault_output(&mut self) {
        self.fault = Some(Fault::Output);
        // Best effort: the caller reports the first error.
        let _ = self.disable();
    }

    /// Integrates the thermal model for one tick at `torque_nm`.
    fn integrate_thermal(&mut self, torque_nm: f32) {
        let c = &self.cfg;
        let current_a = torque_nm / (c.gear_ratio * c.torque_constant_nm_per_a);
        let rate = current_a * current_a - c.continuous_current_a * c.continuous_current_a;
        self.i2t_a2s = (self.i2t_a2s + rate * c.dt_s).max(0.0);
    }

    /// One control tick: limit `command_nm`, write direction and duty, and
    /// update the thermal model. Call it every tick, also while disabled:
    /// the model then cools and nothing is written; the report says zero
    /// torque, or the latched fault is returned as an error every tick.
    pub fn update(&mut self, command_nm: f32) -> Result<TickReport, Error<PwmE, PinE>> {
        if !self.enabled {
            self.integrate_thermal(0.0);
            return match self.fault {
                Some(Fault::Thermal) => Err(Error::Thermal),
                Some(Fault::Output) => Err(Error::OutputFault),
                None => Ok(TickReport {
                    applied_nm: 0.0,
                    duty: 0,
                    rejected_non_finite: !command_nm.is_finite(),
                    limited: command_nm != 0.0,
                    derating: self.i2t_a2s > self.cfg.i2t_warning_a2s,
                }),
            };
        }
        let rejected_non_finite = !command_nm.is_finite();
        let command = if rejected_non_finite { 0.0 } else { command_nm };

        let c = self.cfg;
        // Soft start: 0 at the first tick after enable, full after the ramp.
        // (A zero-length ramp still gives one zero tick.)
        let ramp_ticks = c.soft_start_ticks.max(1);
        let ramp = if self.ticks_since_enable >= ramp_ticks {
            1.0
        } else {
            (self.ticks_since_enable as f32 / ramp_ticks as f32).min(1.0)
        };
        self.ticks_since_enable = self.ticks_since_enable.saturating_add(1);
        let derating = self.i2t_a2s > c.i2t_warning_a2s;
        let limit = (self.thermal_limit_nm() * ramp).min(c.torque_limit_nm);
        let saturated = clamp_f32(command, -limit, limit);
        let slewed = clamp_f32(
            saturated,
            self.applied_nm - c.slew_nm_per_tick,
            self.applied_nm + c.slew_nm_per_tick,
        );
        // Slew may leave the (shrinking) soft-start or derating limit behind;
        // the limit wins.
        let applied = clamp_f32(slewed, -limit, limit);
        let limited = applied != command;

        // Rounded to the nearest count by adding a half and truncating (the
        // cast saturates, NaN gives 0): libm's `roundf` costs some 30
        // instructions a motor on the M4 for the same result, except where
        // x + 0.5 itself rounds up (x one ulp under a half).
        let duty_f = applied.abs() / c.full_scale_torque_nm * f32::from(self.max_duty);
        let duty = ((duty_f + 0.5) as u16).min(self.max_duty);
        let positive = applied >= 0.0;

        let write = if duty != 0 && positive != self.dir_positive {
            // Reverse through zero duty so the bridge never drives the old
            // direction with the new duty.
            self.pwm
                .set_duty_cycle(0)
                .map_err(Error::Pwm)
                .and_then(|()| {
                    if positive {
                        self.dir.set_high()
                    } else {
                        self.dir.set_low()
                    }
                    .map_err(Error::Pin)
                })
                .map(|()| self.dir_positive = positive)
                .and_then(|()| self.pwm.set_duty_cycle(duty).map_err(Error::Pwm))
        } else {
            self.pwm.set_duty_cycle(duty).map_err(Error::Pwm)
        };
        if let Err(e) = write {
            self.fault_output();
            return Err(e);
        }
        self.applied_nm = applied;
        self.integrate_thermal(applied);
        if self.i2t_a2s >= c.i2t_fault_a2s {
            self.fault = Some(Fault::Thermal);
            // Disable errors are moot: the thermal fault is the news.
            let _ = self.disable();
            return Err(Error::Thermal);
        }
        Ok(TickReport {
            applied_nm: applied,
            duty,
            rejected_non_finite,
            limited,
            derating,
        })
    }
}
