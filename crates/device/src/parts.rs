//! The parts the device is built from, with the figures of their
//! datasheets (sources and caveats in `docs/device.md`).

use crate::drive::{AmplifierSpec, DriveSpec, DynamicBrake, GearboxSpec, MotorSpec};
use crate::sensors::{CurrentMonitorSpec, LoadCellSpec};

/// TQ RoboDrive ILM 85x26, 48 V winding (frameless, 10 pole pairs): the
/// figures of TQ's product page as carried in IHMC's motor parameter file
/// (`docs/device.md` has the sources and what could not be checked). The
/// speed constant is 1/k_t; the winding's thermal time constant comes from
/// IHMC's fitted thermal model (0.265 K/W × 121.6 J/K).
pub const ILM85X26: MotorSpec = MotorSpec {
    name: "TQ RoboDrive ILM 85x26, 48 V",
    nominal_voltage_v: 48.0,
    nominal_torque_mnm: 2_900.0,
    nominal_current_a: 11.5,
    torque_constant_mnm_per_a: 253.0,
    speed_constant_rpm_per_v: 37.74,
    terminal_resistance_ohm: 0.32,
    rotor_inertia_gcm2: 1_150.0,
    winding_time_constant_s: 32.0,
};

/// Harmonic Drive CSG-25-80-2A component set (catalogue ratings at ratio
/// 80; efficiency at 500–1,000 rpm input, as the CSD-25 tables give for
/// these ratios).
pub const CSG_25_80: GearboxSpec = GearboxSpec {
    name: "Harmonic Drive CSG-25-80-2A",
    ratio: 80.0,
    rated_torque_nm: 82.0,
    average_torque_nm: 113.0,
    repeated_peak_torque_nm: 178.0,
    momentary_torque_nm: 332.0,
    efficiency: 0.75,
};

/// maxon ESCON 70/10 servo controller (current mode) on the device's 48 V
/// battery bus.
pub const ESCON_70_10_AT_48V: AmplifierSpec = AmplifierSpec {
    name: "maxon ESCON 70/10 at 48 V",
    supply_v: 48.0,
    continuous_current_a: 10.0,
    peak_current_a: 30.0,
};

/// The hips' and knees' dynamic brake: a normally-closed three-pole
/// contactor on the motor phases, opened by the bridge-enable line, with
/// 0.5 Ω in series (`docs/device.md`): the joint is damped by 375 N·m·s/rad
/// (a 75 N·m load sinks at 0.2 rad/s, 4.9 A in the winding; 1 rad/s, an
/// abrupt fall, draws 25 A for a moment).
pub const JOINT_BRAKE: DynamicBrake = DynamicBrake {
    name: "normally-closed contactor on the phases, 0.5 Ω in series",
    resistance_ohm: 0.5,
};

/// The most a joint may be driven with, N·m (the product's ceiling; the
/// drive below stays under it).
pub const JOINT_PEAK_TORQUE_NM: f32 = 150.0;

/// The hip and knee drive: ILM 85x26 + CSG-25-80 + ESCON 70/10 at 48 V.
/// Derived at the joint: 150 N·m peak (the amplifier's current limit is
/// set to it, 9.9 A; the gear would take 178 N·m), 113 N·m continuous (the
/// gear's average-torque rating, below the motor's 175 N·m), 2.37 rad/s
/// no-load, full torque to 2.2 rad/s. I²t: derating from 30 % of the
/// winding's budget (τ_w · I_cont²), fault at 60 %.
pub const JOINT_DRIVE: DriveSpec = DriveSpec {
    motor: ILM85X26,
    gearbox: CSG_25_80,
    amplifier: ESCON_70_10_AT_48V,
    current_limit_a: JOINT_PEAK_TORQUE_NM / (0.253 * 80.0 * 0.75),
    i2t_warning_share: 0.3,
    i2t_fault_share: 0.6,
    brake: Some(JOINT_BRAKE),
};

/// Foot-sole load cell with its amplifier into the 12-bit ADC: 200 counts
/// unloaded (so an open cable, 0 counts, is told apart), 1.4 counts/N,
/// rated −50 … 2,500 N (a one-foot landing of the 93 kg system peaks near
/// 2,200 N in stair descent).
pub const FOOT_LOAD_CELL: LoadCellSpec = LoadCellSpec {
    name: "foot sole load cell, 2.5 kN",
    zero_counts: 200.0,
    counts_per_n: 1.4,
    rated_min_n: -50.0,
    rated_max_n: 2_500.0,
    calibration_points_n: [0.0, 800.0, 1_600.0, 2_400.0],
};

/// Crutch-tip load cell: 200 counts unloaded, 7 counts/N, rated
/// −20 … 500 N.
pub const CRUTCH_LOAD_CELL: LoadCellSpec = LoadCellSpec {
    name: "crutch tip load cell, 500 N",
    zero_counts: 200.0,
    counts_per_n: 7.0,
    rated_min_n: -20.0,
    rated_max_n: 500.0,
    calibration_points_n: [0.0, 150.0, 300.0, 450.0],
};

/// Each hip and knee amplifier's analog output 1, set (ESCON Studio) to
/// "actual current averaged", ±4 V for ±12 A (the 9.9 A limit stays
/// inside), onto the MCP3208 through a 0.4 divider around 1.65 V: 2,048
/// counts at 0 A, 165.5 counts/A, the 9.9 A limit 410 … 3,686 counts
/// (inside the 100 / 4,000 count open and short thresholds).
pub const DRIVE_CURRENT_MONITOR: CurrentMonitorSpec = CurrentMonitorSpec {
    name: "ESCON 70/10 analog output 1, actual current averaged, ±4 V = ±12 A",
    current_full_scale_a: 12.0,
    output_full_scale_v: 4.0,
    divider_gain: 0.4,
    offset_v: 1.65,
    adc_reference_v: 3.3,
};
