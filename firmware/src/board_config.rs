//! The numbers both boards run with: loop gains, motor and drive limits,
//! encoder and force-sensor calibrations, which ADC channel is which, and
//! the gait tables in flash. Both images build their controller and their
//! [`Hardware`] through [`build_controller`] and [`hardware`], so the QEMU
//! benchmark runs exactly the configuration the motor board runs.
//!
//! The device: a 93 kg system (pilot plus exoskeleton, the paper's
//! Table III), hips and knees driven by brushless motors through 100:1
//! harmonic drives, sign-magnitude H-bridges at 20 kHz. Values marked
//! *per device* are measured at assembly and must be replaced by the
//! numbers on the device's calibration sheet before it carries a pilot.
//!
//! No control logic here: this module only fills in gait-control's
//! configuration types and hands the board's peripherals to its drivers.

use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::pwm::SetDutyCycle;
use embedded_hal::spi::SpiDevice;
use gait_control::controller::{
    self, Controller, ControllerConfig, ENCODERS, FORCE_CAL_POINTS, FORCES, Hardware,
};
use gait_control::drivers::as5048a::{As5048a, Calibration, Direction};
use gait_control::drivers::buttons::{Button, ButtonConfig};
use gait_control::drivers::mcp3208::{
    CalibrationError, Channel, ForceCalibration, ForceChannels, Mcp3208,
};
use gait_control::drivers::motor::{self, Motor, MotorConfig};
use gait_control::drivers::status::Indicator;
use gait_control::operator::{self, AllowedGaits, Gait, OperatorConfig};
use gait_control::position_loop::JointGains;
use gait_control::posture::JOINTS;
use gait_control::sequencer::{GaitTables, SequencerConfig};
use gait_control::supervisor::{self, Supervisor, SupervisorConfig};
use gait_core::BodyModel;

/// Control-loop rate, Hz.
pub const TICK_HZ: u32 = 1_000;
/// Control-loop period, s.
pub const DT_S: f32 = 1.0 / TICK_HZ as f32;

/// The gait tables this image carries (`gait_core::flash_tables`, made by
/// `cargo xtask tables`), each verified (magic, version, kind, length,
/// CRC-32, finite samples) before it can be selected: a table that fails is
/// left out, so its gait cannot start.
#[must_use]
pub fn flash_tables() -> GaitTables<'static> {
    GaitTables {
        walk: gait_core::flash_tables::walk().ok(),
        stair_up: gait_core::flash_tables::stair_up().ok(),
        stair_down: gait_core::flash_tables::stair_down().ok(),
    }
}

/// Hip position loop (joints 0 and 2). Kp 500 N·m/rad: 0.1 rad of error
/// asks for 50 N·m, the order of the stance hip's gravity torque; Kd 30
/// N·m·s/rad gives a damping ratio of ≈ 0.7 on a swinging thigh + shank +
/// foot (≈ 0.9 kg·m² about the hip: ω ≈ 24 rad/s); Ki small, only to remove the
/// steady error left by model mismatch, clamped at 10 N·m; 70 N·m is the
/// loop's own limit (below the drive's 75 N·m); slew 2 N·m per tick
/// (2 kN·m/s) keeps the output free of steps at 1 kHz.
pub const HIP_GAINS: JointGains = JointGains {
    kp_nm_per_rad: 500.0,
    ki_nm_per_rad_s: 200.0,
    kd_nm_s_per_rad: 30.0,
    integral_limit_nm: 10.0,
    torque_limit_nm: 70.0,
    slew_nm_per_tick: 2.0,
};

/// Knee position loop (joints 1 and 3): the shank and foot (≈ 0.25 kg·m²
/// about the knee) are lighter than the whole leg about the hip, so lower
/// gains: Kp 400, Kd 14 for a damping ratio of ≈ 0.7; the same 70 N·m
/// limit (the stance knee in stair ascent is the largest knee demand).
pub const KNEE_GAINS: JointGains = JointGains {
    kp_nm_per_rad: 400.0,
    ki_nm_per_rad_s: 150.0,
    kd_nm_s_per_rad: 14.0,
    integral_limit_nm: 10.0,
    torque_limit_nm: 70.0,
    slew_nm_per_tick: 2.0,
};

/// Loop gains in joint order: left hip, left knee, right hip, right knee.
pub const JOINT_GAINS: [JointGains; JOINTS] = [HIP_GAINS, KNEE_GAINS, HIP_GAINS, KNEE_GAINS];

/// One joint drive: motor k_t 0.07 N·m/A through a 100:1 harmonic drive,
/// 90 N·m at the joint at 100 % duty (drive calibration), 4 A continuous
/// (28 N·m at the joint). The drive's limit, 75 N·m, sits above the loop's
/// 70 N·m so the loop shapes the response and the drive only protects.
/// I²t: derating from 50 A²·s above continuous (≈ 0.6 s at 10 A, the
/// 70 N·m current), fault at 100 A²·s; derated to 40 N·m, above the
/// continuous torque so sustained overload still reaches the fault. Slew
/// 2.5 N·m per tick (above the loop's 2.0) and a 200 ms soft start.
pub const JOINT_MOTOR: MotorConfig = MotorConfig {
    torque_limit_nm: 75.0,
    full_scale_torque_nm: 90.0,
    torque_constant_nm_per_a: 0.07,
    gear_ratio: 100.0,
    continuous_current_a: 4.0,
    i2t_warning_a2s: 50.0,
    i2t_fault_a2s: 100.0,
    derated_limit_nm: 40.0,
    slew_nm_per_tick: 2.5,
    soft_start_ticks: 200,
    dt_s: DT_S,
};

/// Drives in joint order (all four joints use the same drive).
pub const MOTORS: [MotorConfig; JOINTS] = [JOINT_MOTOR; JOINTS];

/// Encoder zero offsets (*per device*: raw counts read with the joint at
/// its zero pose, the calibration jig) and sense of rotation. The right
/// side's magnets are seen from the other side of the joint, hence
/// `Negative`. Order: left hip, left knee, right hip, right knee, left
/// ankle, right ankle.
pub const ENCODER_CALIBRATION: [Calibration; ENCODERS] = [
    Calibration {
        zero_offset_counts: 8_192,
        direction: Direction::Positive,
    },
    Calibration {
        zero_offset_counts: 8_192,
        direction: Direction::Positive,
    },
    Calibration {
        zero_offset_counts: 8_192,
        direction: Direction::Negative,
    },
    Calibration {
        zero_offset_counts: 8_192,
        direction: Direction::Negative,
    },
    Calibration {
        zero_offset_counts: 8_192,
        direction: Direction::Positive,
    },
    Calibration {
        zero_offset_counts: 8_192,
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

/// Foot-sole sensor (*per device*): counts at 0, 200, 700 and 1,400 N
/// (load-cell bridge and amplifier; standing on both feet puts ≈ 370 N on
/// each with the crutches loaded). Below 100 counts is an open circuit,
/// above 4,000 a short; rated −50 … 1,500 N.
pub const FOOT_COUNTS: [u16; FORCE_CAL_POINTS] = [200, 1_000, 2_500, 3_800];
/// Forces at [`FOOT_COUNTS`], N.
pub const FOOT_NEWTONS: [f32; FORCE_CAL_POINTS] = [0.0, 200.0, 700.0, 1_400.0];
/// Crutch-tip sensor (*per device*): counts at 0, 50, 200 and 400 N; open
/// below 100 counts, short above 4,000; rated −20 … 500 N.
pub const CRUTCH_COUNTS: [u16; FORCE_CAL_POINTS] = [200, 1_200, 2_600, 3_800];
/// Forces at [`CRUTCH_COUNTS`], N.
pub const CRUTCH_NEWTONS: [f32; FORCE_CAL_POINTS] = [0.0, 50.0, 200.0, 400.0];
/// Readings below this are an open sensor or cable.
pub const OPEN_BELOW_COUNTS: u16 = 100;
/// Readings above this are a shorted sensor or cable.
pub const SHORT_ABOVE_COUNTS: u16 = 4_000;

/// MODE and GO: 20 ms debounce, 1 s long press, pressed pulls low.
pub const BUTTONS: ButtonConfig = ButtonConfig::DEFAULT_1KHZ;

/// The e-stop is a normally-closed contact to ground with a pull-up: it
/// reads high when pressed *or* when its cable is cut, so a broken wire
/// stops the device instead of hiding the button.
pub const E_STOP_ACTIVE_HIGH: bool = true;

/// Cut-off of the controller's joint-rate filter, Hz (well above gait
/// content, ~1–3 Hz; well below the 500 Hz Nyquist of the tick).
pub const RATE_FILTER_HZ: f32 = 30.0;
/// Joint rate that still counts as standing still, rad/s.
pub const STILL_RATE_RAD_S: f32 = 0.05;
/// MODE+GO hold that resets faults: 3 s at 1 kHz.
pub const RESET_HOLD_TICKS: u32 = 3_000;

/// Why the board could not be configured (the image then halts with the
/// motors disabled).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "board-stm32f405", derive(defmt::Format))]
pub enum BoardError {
    /// A force calibration table was refused (index: left foot, right foot,
    /// left crutch, right crutch).
    ForceCalibration(usize, CalibrationError),
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
}

/// The four force calibrations: left foot, right foot, left crutch, right
/// crutch.
pub fn force_calibration() -> Result<[ForceCalibration<FORCE_CAL_POINTS>; FORCES], BoardError> {
    let foot = |i| {
        ForceCalibration::new(
            FOOT_COUNTS,
            FOOT_NEWTONS,
            OPEN_BELOW_COUNTS,
            SHORT_ABOVE_COUNTS,
            -50.0,
            1_500.0,
        )
        .map_err(|e| BoardError::ForceCalibration(i, e))
    };
    let crutch = |i| {
        ForceCalibration::new(
            CRUTCH_COUNTS,
            CRUTCH_NEWTONS,
            OPEN_BELOW_COUNTS,
            SHORT_ABOVE_COUNTS,
            -20.0,
            500.0,
        )
        .map_err(|e| BoardError::ForceCalibration(i, e))
    };
    Ok([foot(0)?, foot(1)?, crutch(2)?, crutch(3)?])
}

/// The controller configuration (gains, sequencer, calibrations, model).
pub fn controller_config() -> Result<ControllerConfig, BoardError> {
    Ok(ControllerConfig {
        dt_s: DT_S,
        gains: JOINT_GAINS,
        sequencer: SequencerConfig::DEFAULT,
        force_calibration: force_calibration()?,
        e_stop_active_high: E_STOP_ACTIVE_HIGH,
        rate_filter_hz: RATE_FILTER_HZ,
        still_rate_rad_s: STILL_RATE_RAD_S,
        model: BodyModel::<f64>::paper_table_iii().cast::<f32>(),
    })
}

/// The clinician's gait list: the gaits that have a verified table, in the
/// order walk, stair up, stair down. With no table at all the list holds
/// walking only (it cannot be empty); GO is then refused by the sequencer.
pub fn operator_config(tables: &GaitTables<'_>) -> Result<OperatorConfig, BoardError> {
    let mut list = [Gait::Walk; operator::MAX_GAITS];
    let mut n = 0;
    for g in [Gait::Walk, Gait::StairUp, Gait::StairDown] {
        if tables.get(g).is_some() {
            if let Some(slot) = list.get_mut(n) {
                *slot = g;
                n += 1;
            }
        }
    }
    let allowed = AllowedGaits::new(list.get(..n.max(1)).unwrap_or(&[Gait::Walk]))
        .map_err(BoardError::Operator)?;
    Ok(OperatorConfig {
        allowed,
        reset_hold_ticks: RESET_HOLD_TICKS,
    })
}

/// The supervisor: Table I with the heel rocker (12° of ankle
/// plantarflexion) as the envelope, with the default margins
/// and detection bounds.
pub fn supervisor() -> Result<Supervisor, BoardError> {
    // The device's ankles roll on the heel: the walk starts with the stance
    // shank 5.3° behind vertical, outside Table I's 0° plantarflexion.
    let mut cfg = SupervisorConfig::default_for(&gait_core::JointLimits::paper_with_heel_rocker());
    cfg.dt_s = DT_S;
    Supervisor::new(cfg).map_err(BoardError::Supervisor)
}

/// The controller both boards run, over the tables in flash.
pub fn build_controller() -> Result<Controller<'static>, BoardError> {
    let tables = flash_tables();
    Controller::new(
        controller_config()?,
        tables,
        operator_config(&tables)?,
        supervisor()?,
    )
    .map_err(BoardError::Controller)
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
    Result<Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>, BoardError>;

/// Hands the board's peripherals to gait-control's drivers with this
/// module's calibrations and limits, and disables every motor output
/// (enable low, duty zero) before returning.
pub fn hardware<ENC, ADC, PWM, DIR, EN, IN, OUT, PwmE, PinE>(
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
    let [c0, c1, c2, c3, c4, c5] = ENCODER_CALIBRATION;
    let [p0, p1, p2, p3] = io.pwm;
    let [d0, d1, d2, d3] = io.dir;
    let [n0, n1, n2, n3] = io.enable;
    let [m0, m1, m2, m3] = MOTORS;
    let motor = |i: usize, p, d, n, m| Motor::new(p, d, n, m).map_err(|e| BoardError::Motor(i, e));
    let mut motors = [
        motor(0, p0, d0, n0, m0)?,
        motor(1, p1, d1, n1, m1)?,
        motor(2, p2, d2, n2, m2)?,
        motor(3, p3, d3, n3, m3)?,
    ];
    for (i, m) in motors.iter_mut().enumerate() {
        m.disable().map_err(|_| BoardError::MotorDisable(i))?;
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
        force_channels: FORCE_CHANNELS,
        motors,
        mode: Button::new(io.mode, BUTTONS),
        go: Button::new(io.go, BUTTONS),
        e_stop: io.e_stop,
        gait_led: Indicator::new(io.gait_led),
        fault_led: Indicator::new(io.fault_led),
        buzzer: Indicator::new(io.buzzer),
    })
}
