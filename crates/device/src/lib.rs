//! The one device configuration of exogait: what the motor board runs, what
//! the QEMU image benchmarks, what the simulator simulates and what the
//! table generator designs gaits for.
//!
//! - [`parts`]: the motor, gearbox, amplifier and load cells, with their
//!   datasheet figures; [`drive`] derives the joint-level limits from them.
//! - [`DeviceConfig`]: every number the controller and its drivers are
//!   built with (gains, sequencer thresholds, supervisor envelope, drive
//!   limits, sensor calibrations, the body model, the ankles' passive
//!   springs), built once by [`DeviceConfig::exogait`].
//! - [`build_controller`] and [`hardware`]: the controller and the drivers
//!   over any embedded-hal peripherals (the STM32's, QEMU's in-memory ones,
//!   the simulator's).
//! - [`DeviceConfig::fingerprint`]: a CRC-32 of the whole configuration, so
//!   that a test can tell when the firmware and the simulator would run
//!   different values.
//!
//! What only the simulation has (the pilot, its lean on the crutches, its
//! torque limit) is not here: it is the pilot's, in `sim::pilot`.
#![no_std]

pub mod admission;
pub mod boot;
pub mod calibration;
pub mod drive;
pub mod fitting;
pub mod parts;
pub mod replan;
pub mod sensors;
pub mod tick_record;

use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::pwm::SetDutyCycle;
use embedded_hal::spi::SpiDevice;
use gait_control::controller::{self, Controller, ControllerConfig, ENCODERS, Hardware};
use gait_control::drivers::as5048a::{As5048a, Calibration, Direction};
use gait_control::drivers::buttons::{Button, ButtonConfig};
use gait_control::drivers::mcp3208::{CalibrationError, Channel, ForceChannels, Mcp3208};
use gait_control::drivers::motor::{self, Motor, MotorConfig};
use gait_control::drivers::status::Indicator;
use gait_control::operator::{self, AllowedGaits, Gait, GaitChoice, OperatorConfig};
use gait_control::position_loop::JointGains;
use gait_control::posture::JOINTS;
use gait_control::sequencer::{GaitTables, SequencerConfig};
use gait_control::supervisor::{self, Supervisor, SupervisorConfig};
use gait_core::anthropometry::{self, AnthropometryError, ExoSegments, Pilot, SegmentLengths};
use gait_core::fingerprint::Fingerprint;
use gait_core::{BodyModel, JointLimits};

use crate::drive::DriveSpec;
use crate::parts::{CRUTCH_LOAD_CELL, DRIVE_CURRENT_MONITOR, FOOT_LOAD_CELL, JOINT_DRIVE};
use crate::sensors::{CurrentMonitorSpec, LoadCellSpec};

/// Control-loop rate, Hz.
pub const TICK_HZ: u32 = 1_000;
/// Control-loop period, s.
pub const DT_S: f32 = 1.0 / TICK_HZ as f32;

/// Every number the device is built with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeviceConfig {
    /// Control-loop period, s.
    pub dt_s: f32,
    /// Pilot plus exoskeleton with the device's joint limits: Table III
    /// for the device as built; a patient's model once fitted
    /// ([`DeviceConfig::fitted`]).
    pub body: BodyModel<f64>,
    /// The exoskeleton's own segments (masses; centres of mass and
    /// inertias where measured), which a patient's model adds to the
    /// pilot's.
    pub exo: ExoSegments<f64>,
    /// The passive spring of each exoskeleton ankle, N·m/rad (relaxed at
    /// 0 rad dorsiflexion).
    pub ankle_spring_nm_per_rad: f64,
    /// The hip and knee drives, joint order.
    pub drives: [DriveSpec; JOINTS],
    /// The motor drivers' configuration (from the drives), joint order.
    pub motors: [MotorConfig; JOINTS],
    /// Loop gains, sequencer, calibrations, feed-forward model.
    pub controller: ControllerConfig,
    /// The supervisor's envelope and detection bounds.
    pub supervisor: SupervisorConfig,
    /// Encoder calibrations (*per device*: from the calibration sheet):
    /// left hip, left knee, right hip, right knee, left ankle, right ankle.
    pub encoders: [Calibration; ENCODERS],
    /// The foot-sole load cells.
    pub foot_sensor: LoadCellSpec,
    /// The crutch-tip load cells.
    pub crutch_sensor: LoadCellSpec,
    /// Which ADC channel each force sensor is on.
    pub force_channels: ForceChannels,
    /// The hip and knee amplifiers' current monitors.
    pub drive_current_monitor: CurrentMonitorSpec,
    /// Which ADC channel each drive's current monitor is on (joint order).
    pub drive_current_channels: [Channel; JOINTS],
    /// MODE and GO.
    pub buttons: ButtonConfig,
    /// `true` when the e-stop input reads high while pressed.
    pub e_stop_active_high: bool,
    /// MODE+GO hold that resets faults, ticks.
    pub reset_hold_ticks: u32,
}

/// Why the device configuration could not be built.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DeviceError {
    /// A force calibration was refused (index: left foot, right foot, left
    /// crutch, right crutch).
    ForceCalibration(usize, CalibrationError),
    /// A drive current monitor's calibration was refused (joint index).
    DriveCurrentCalibration(usize, CalibrationError),
    /// A motor configuration was refused (joint index).
    Motor(usize, motor::ConfigError),
    /// Disabling a motor at boot failed (joint index).
    MotorDisable(usize),
    /// The allowed-gait list was refused.
    Operator(operator::ConfigError),
    /// The supervisor configuration was refused.
    Supervisor(supervisor::ConfigError),
    /// The controller configuration was refused.
    Controller(controller::ConfigError),
    /// A patient's body model was refused.
    Patient(AnthropometryError),
}

/// Hip position loop (joints 0 and 2): Kp 2,000 N·m/rad (5 mrad of error
/// asks 10 N·m: the pilot's plan assumes the joints follow), Kd 80 for a
/// damping ratio near 0.7 on a swinging leg (≈ 0.9 kg·m² about the hip),
/// Ki 1,000 clamped at 25 N·m for model mismatch; the loop's limit is the
/// drive's peak torque (filled in from the drive); slew 12 N·m per tick.
const HIP_GAINS: JointGains = JointGains {
    kp_nm_per_rad: 2_000.0,
    ki_nm_per_rad_s: 1_000.0,
    kd_nm_s_per_rad: 80.0,
    integral_limit_nm: 25.0,
    torque_limit_nm: 0.0, // the drive's peak torque, set in `exogait`
    slew_nm_per_tick: 12.0,
};

/// Knee position loop (joints 1 and 3): the hip's, but the shank and foot
/// are lighter (≈ 0.25 kg·m² about the knee): Kd 60, integral clamp
/// 20 N·m.
const KNEE_GAINS: JointGains = JointGains {
    kd_nm_s_per_rad: 60.0,
    integral_limit_nm: 20.0,
    ..HIP_GAINS
};

/// Gait execution: 30 N on each crutch tip (planted, not only touching),
/// the default timings and thresholds.
const SEQUENCER: SequencerConfig = SequencerConfig {
    crutch_ready_n: 30.0,
    ..SequencerConfig::DEFAULT
};

/// The drives' slew limit, N·m per tick (above the loops' 12, so the loop
/// shapes the response and the driver only protects), and soft start.
const DRIVE_SLEW_NM_PER_TICK: f32 = 15.0;
const DRIVE_SOFT_START_TICKS: u32 = 40;

impl DeviceConfig {
    /// The exogait device.
    pub fn exogait() -> Result<Self, DeviceError> {
        Self::with_drive(JOINT_DRIVE)
    }

    /// The device with `drive` at every hip and knee (the controller's
    /// torque limits, the motor drivers and the supervisor's current check
    /// follow it): for comparing drives, not a device that is built.
    pub fn with_drive(drive: DriveSpec) -> Result<Self, DeviceError> {
        let limits = JointLimits::<f64>::paper_with_heel_rocker();
        let table_iii = BodyModel::<f64>::paper_table_iii();
        let body = BodyModel::new(*table_iii.links(), limits).unwrap_or(table_iii);
        let drives = [drive; JOINTS];
        let motors =
            drives.map(|d| d.motor_config(DT_S, DRIVE_SLEW_NM_PER_TICK, DRIVE_SOFT_START_TICKS));
        let foot = |i: usize| {
            FOOT_LOAD_CELL
                .calibration()
                .map_err(|e| DeviceError::ForceCalibration(i, e))
        };
        let crutch = |i: usize| {
            CRUTCH_LOAD_CELL
                .calibration()
                .map_err(|e| DeviceError::ForceCalibration(i, e))
        };
        let drive_current = |j: usize| {
            let d: &DriveSpec = drives.get(j).unwrap_or(&drive);
            DRIVE_CURRENT_MONITOR
                .calibration(d.joint_torque_per_amp())
                .map_err(|e| DeviceError::DriveCurrentCalibration(j, e))
        };
        let model32: BodyModel<f32> = body.cast();
        let controller = ControllerConfig {
            dt_s: DT_S,
            gains: [HIP_GAINS, KNEE_GAINS, HIP_GAINS, KNEE_GAINS].map(|g| JointGains {
                torque_limit_nm: drive.peak_torque_nm(),
                ..g
            }),
            sequencer: SEQUENCER,
            force_calibration: [foot(0)?, foot(1)?, crutch(2)?, crutch(3)?],
            drive_current_calibration: [
                drive_current(0)?,
                drive_current(1)?,
                drive_current(2)?,
                drive_current(3)?,
            ],
            e_stop_active_high: true,
            rate_filter_hz: 40.0,
            still_rate_rad_s: 0.2,
            model: model32,
        };
        let mut supervisor = SupervisorConfig::default_for(model32.limits());
        supervisor.dt_s = DT_S;
        supervisor.max_jump_counts_per_tick = supervisor.physical_jump_counts();
        supervisor.force_min_n = FOOT_LOAD_CELL.rated_min_n;
        supervisor.force_max_n = FOOT_LOAD_CELL.rated_max_n;
        supervisor.drive_current.full_torque_speed_rad_s = drive.full_torque_speed_rad_s();
        Ok(Self {
            dt_s: DT_S,
            body,
            exo: ExoSegments::paper_default(),
            ankle_spring_nm_per_rad: 30.0,
            drives,
            motors,
            controller,
            supervisor,
            encoders: ENCODER_CALIBRATION,
            foot_sensor: FOOT_LOAD_CELL,
            crutch_sensor: CRUTCH_LOAD_CELL,
            force_channels: FORCE_CHANNELS,
            drive_current_monitor: DRIVE_CURRENT_MONITOR,
            drive_current_channels: DRIVE_CURRENT_CHANNELS,
            buttons: ButtonConfig::DEFAULT_1KHZ,
            e_stop_active_high: true,
            reset_hold_ticks: 3_000,
        })
    }

    /// CRC-32 (ISO-HDLC) of the configuration's contents, every field in
    /// declaration order with floats by their bits
    /// (`gait_core::fingerprint`): the same values give the same number on
    /// the host and on the target, and any changed value changes it. No
    /// `core::fmt`: the QEMU image prints it, and float formatting would
    /// put panic paths into that image.
    pub fn fingerprint(&self) -> u32 {
        let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);
        let mut digest = crc.digest();
        self.feed(&mut |bytes: &[u8]| digest.update(bytes));
        digest.finalize()
    }

    /// The device fitted to a patient: the same drives, sensors, gains,
    /// thresholds and joint limits, with the patient's body model in the
    /// controller's feed-forward (and in the simulator's plant), and the
    /// torque residual's inertias carried over to that body
    /// ([`fitting::response_for`]). The model's joint limits are replaced
    /// by the device's.
    pub fn fitted(&self, body: &BodyModel<f64>) -> Result<Self, AnthropometryError> {
        let body = BodyModel::new(*body.links(), *self.body.limits())?;
        let mut cfg = *self;
        cfg.body = body;
        cfg.controller.model = body.cast();
        cfg.supervisor.response =
            fitting::response_for(&self.supervisor.response, &self.body, &body);
        Ok(cfg)
    }

    /// The combined pilot-plus-exoskeleton model of a pilot of `pilot`'s
    /// height and mass, with the leg `lengths` given (Winter's proportions
    /// where not measured: [`SegmentLengths::winter`]), this device's
    /// exoskeleton segments and joint limits.
    pub fn patient_model(
        &self,
        pilot: &Pilot<f64>,
        lengths: &SegmentLengths<f64>,
    ) -> Result<BodyModel<f64>, AnthropometryError> {
        let options = anthropometry::Options {
            limits: *self.body.limits(),
            ..anthropometry::Options::default()
        };
        anthropometry::body_model_with_lengths(pilot, lengths, &self.exo, &options)
    }

    /// The supervisor.
    pub fn supervisor(&self) -> Result<Supervisor, DeviceError> {
        Supervisor::new(self.supervisor).map_err(DeviceError::Supervisor)
    }

    /// The clinician's gait list: the gaits that have a verified table, in
    /// the order walk, stair up, stair down, the one asked for first. With
    /// no table at all the list holds walking only (it cannot be empty); GO
    /// is then refused by the sequencer.
    pub fn operator_config(
        &self,
        tables: &GaitTables<'_>,
        first: Gait,
    ) -> Result<OperatorConfig, DeviceError> {
        let mut list = [GaitChoice {
            kind: Gait::Walk,
            slot: 0,
            flashes: 1,
        }; operator::MAX_GAITS];
        let mut n = 0;
        let order = [first, Gait::Walk, Gait::StairUp, Gait::StairDown];
        for (i, g) in order.into_iter().enumerate() {
            let repeated = order.get(..i).is_some_and(|before| before.contains(&g));
            if let (Some(slot), false) = (tables.slot_of(g), repeated) {
                if let Some(entry) = list.get_mut(n) {
                    *entry = GaitChoice {
                        kind: g,
                        slot: u8::try_from(slot).unwrap_or(0),
                        flashes: g.code(),
                    };
                    n += 1;
                }
            }
        }
        let allowed = if n == 0 {
            AllowedGaits::new(&[Gait::Walk])
        } else {
            AllowedGaits::from_choices(list.get(..n).unwrap_or(&[]))
        }
        .map_err(DeviceError::Operator)?;
        Ok(OperatorConfig {
            allowed,
            reset_hold_ticks: self.reset_hold_ticks,
        })
    }
}

gait_core::impl_fingerprint!(DeviceConfig {
    dt_s,
    body,
    exo,
    ankle_spring_nm_per_rad,
    drives,
    motors,
    controller,
    supervisor,
    encoders,
    foot_sensor,
    crutch_sensor,
    force_channels,
    drive_current_monitor,
    drive_current_channels,
    buttons,
    e_stop_active_high,
    reset_hold_ticks,
});
gait_core::impl_fingerprint!(CurrentMonitorSpec {
    name,
    current_full_scale_a,
    output_full_scale_v,
    divider_gain,
    offset_v,
    adc_reference_v,
});
gait_core::impl_fingerprint!(LoadCellSpec {
    name,
    zero_counts,
    counts_per_n,
    rated_min_n,
    rated_max_n,
    calibration_points_n,
});
gait_core::impl_fingerprint!(drive::DriveSpec {
    motor,
    gearbox,
    amplifier,
    current_limit_a,
    i2t_warning_share,
    i2t_fault_share,
    brake,
});
gait_core::impl_fingerprint!(drive::MotorSpec {
    name,
    nominal_voltage_v,
    nominal_torque_mnm,
    nominal_current_a,
    torque_constant_mnm_per_a,
    speed_constant_rpm_per_v,
    terminal_resistance_ohm,
    rotor_inertia_gcm2,
    winding_time_constant_s,
});
gait_core::impl_fingerprint!(drive::GearboxSpec {
    name,
    ratio,
    rated_torque_nm,
    average_torque_nm,
    repeated_peak_torque_nm,
    momentary_torque_nm,
    efficiency,
});
gait_core::impl_fingerprint!(drive::AmplifierSpec {
    name,
    supply_v,
    continuous_current_a,
    peak_current_a,
});
gait_core::impl_fingerprint!(drive::DynamicBrake {
    name,
    resistance_ohm
});

/// Encoder zero offsets (*per device*: raw counts with the joint at its
/// zero pose on the calibration jig) and senses of rotation; the right
/// side's magnets are seen from the other side of the joint, hence
/// `Negative`. Order: left hip, left knee, right hip, right knee, left
/// ankle, right ankle.
pub const ENCODER_CALIBRATION: [Calibration; ENCODERS] = [
    Calibration {
        zero_offset_counts: 1_234,
        direction: Direction::Positive,
    },
    Calibration {
        zero_offset_counts: 15_000,
        direction: Direction::Positive,
    },
    Calibration {
        zero_offset_counts: 8_191,
        direction: Direction::Negative,
    },
    Calibration {
        zero_offset_counts: 40,
        direction: Direction::Negative,
    },
    Calibration {
        zero_offset_counts: 3_000,
        direction: Direction::Positive,
    },
    Calibration {
        zero_offset_counts: 12_000,
        direction: Direction::Negative,
    },
];

/// Force sensors on the MCP3208: feet on CH0/CH1, crutch tips on CH2/CH3.
pub const FORCE_CHANNELS: ForceChannels = ForceChannels {
    left_foot: Channel::Ch0,
    right_foot: Channel::Ch1,
    left_crutch: Channel::Ch2,
    right_crutch: Channel::Ch3,
};

/// The drives' current monitors on the MCP3208's other four channels:
/// left hip CH4, left knee CH5, right hip CH6, right knee CH7.
pub const DRIVE_CURRENT_CHANNELS: [Channel; JOINTS] =
    [Channel::Ch4, Channel::Ch5, Channel::Ch6, Channel::Ch7];

/// The controller the device runs over `tables` (each already verified),
/// the clinician's list starting with `first`.
pub fn build_controller<'t>(
    cfg: &DeviceConfig,
    tables: GaitTables<'t>,
    first: Gait,
) -> Result<Controller<'t>, DeviceError> {
    Controller::new(
        cfg.controller,
        tables,
        cfg.operator_config(&tables, first)?,
        cfg.supervisor()?,
    )
    .map_err(DeviceError::Controller)
}

/// A board's peripherals, already typed for the drivers (one SPI device
/// per chip select, pins erased to one type per role).
pub struct BoardIo<ENC, ADC, PWM, DIR, EN, IN, OUT> {
    /// Encoder SPI devices: left hip, left knee, right hip, right knee,
    /// left ankle, right ankle.
    pub encoders: [ENC; ENCODERS],
    /// The force ADC's SPI device.
    pub adc: ADC,
    /// PWM channels, joint order.
    pub pwm: [PWM; JOINTS],
    /// Direction pins, joint order (high = positive torque).
    pub dir: [DIR; JOINTS],
    /// Bridge-enable pins, joint order (high = enabled).
    pub enable: [EN; JOINTS],
    /// MODE button.
    pub mode: IN,
    /// GO button.
    pub go: IN,
    /// E-stop input.
    pub e_stop: IN,
    /// Gait LED.
    pub gait_led: OUT,
    /// Fault LED.
    pub fault_led: OUT,
    /// Buzzer.
    pub buzzer: OUT,
}

/// What [`hardware`] returns.
pub type HardwareResult<ENC, ADC, PWM, DIR, EN, IN, OUT> =
    Result<Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>, DeviceError>;

/// Hands a board's peripherals to gait-control's drivers with the device's
/// calibrations and limits, and disables every motor output (enable low,
/// duty zero) before returning.
pub fn hardware<ENC, ADC, PWM, DIR, EN, IN, OUT, PwmE, PinE>(
    cfg: &DeviceConfig,
    io: BoardIo<ENC, ADC, PWM, DIR, EN, IN, OUT>,
) -> HardwareResult<ENC, ADC, PWM, DIR, EN, IN, OUT>
where
    ENC: SpiDevice<u8>,
    ADC: SpiDevice<u8>,
    PWM: SetDutyCycle<Error = PwmE>,
    DIR: OutputPin<Error = PinE>,
    EN: OutputPin<Error = PinE>,
    IN: InputPin,
    OUT: OutputPin,
{
    let [e0, e1, e2, e3, e4, e5] = io.encoders;
    let [c0, c1, c2, c3, c4, c5] = cfg.encoders;
    let [p0, p1, p2, p3] = io.pwm;
    let [d0, d1, d2, d3] = io.dir;
    let [n0, n1, n2, n3] = io.enable;
    let [m0, m1, m2, m3] = cfg.motors;
    let motor = |i: usize, p, d, n, m| Motor::new(p, d, n, m).map_err(|e| DeviceError::Motor(i, e));
    let mut motors = [
        motor(0, p0, d0, n0, m0)?,
        motor(1, p1, d1, n1, m1)?,
        motor(2, p2, d2, n2, m2)?,
        motor(3, p3, d3, n3, m3)?,
    ];
    for (i, m) in motors.iter_mut().enumerate() {
        m.disable().map_err(|_| DeviceError::MotorDisable(i))?;
    }
    Ok(Hardware {
        encoders: [
            As5048a::new(e0, c0),
            As5048a::new(e1, c1),
            As5048a::new(e2, c2),
            As5048a::new(e3, c3),
            As5048a::new(e4, c4),
            As5048a::new(e5, c5),
        ],
        adc: Mcp3208::new(io.adc),
        force_channels: cfg.force_channels,
        drive_current_channels: cfg.drive_current_channels,
        motors,
        mode: Button::new(io.mode, cfg.buttons),
        go: Button::new(io.go, cfg.buttons),
        e_stop: io.e_stop,
        gait_led: Indicator::new(io.gait_led),
        fault_led: Indicator::new(io.fault_led),
        buzzer: Indicator::new(io.buzzer),
    })
}
