//! The parts the device is built from, with the figures of their
//! datasheets (sources and caveats in `docs/device.md`).

use crate::drive::{AmplifierSpec, DriveSpec, GearboxSpec, MotorSpec};
use crate::sensors::LoadCellSpec;

/// maxon EC 90 flat ∅90 mm, brushless, 90 W, with Hall sensors, 24 V
/// winding, part 323772 (maxon catalogue, values at nominal voltage).
pub const EC90_FLAT_323772: MotorSpec = MotorSpec {
    name: "maxon EC 90 flat 90 W, 24 V winding (323772)",
    nominal_voltage_v: 24.0,
    nominal_torque_mnm: 387.0,
    nominal_current_a: 5.39,
    torque_constant_mnm_per_a: 70.5,
    speed_constant_rpm_per_v: 135.0,
    terminal_resistance_ohm: 0.363,
    rotor_inertia_gcm2: 3060.0,
    winding_time_constant_s: 52.6,
};

/// Harmonic Drive CSG-25-100-2A component set (efficiency: the CSD-25-100
/// table at 500–1,000 rpm input, 73–78 %; 73 % taken).
pub const CSG_25_100: GearboxSpec = GearboxSpec {
    name: "Harmonic Drive CSG-25-100-2A",
    ratio: 100.0,
    rated_torque_nm: 87.0,
    repeated_peak_torque_nm: 204.0,
    momentary_torque_nm: 369.0,
    efficiency: 0.73,
};

/// maxon ESCON 70/10 servo controller (current mode) on the device's 36 V
/// battery bus.
pub const ESCON_70_10_AT_36V: AmplifierSpec = AmplifierSpec {
    name: "maxon ESCON 70/10 at 36 V",
    supply_v: 36.0,
    continuous_current_a: 10.0,
    peak_current_a: 30.0,
};

/// Peak joint torque the device allows, N·m: the drive's current limit is
/// set for it (the gearbox would take 204 N·m).
pub const JOINT_PEAK_TORQUE_NM: f32 = 150.0;

/// The hip and knee drive: EC 90 flat + CSG-25-100 + ESCON 70/10, current
/// limit 29.1 A (150 N·m at the joint). Derived at the joint: 150 N·m peak,
/// 27.7 N·m continuous, 5.1 rad/s no-load, full torque up to 3.6 rad/s.
/// I²t: derating from 30 % of the winding's budget (τ_w·I_nom² ≈ 1,528
/// A²·s), fault at 60 %.
pub const JOINT_DRIVE: DriveSpec = DriveSpec {
    motor: EC90_FLAT_323772,
    gearbox: CSG_25_100,
    amplifier: ESCON_70_10_AT_36V,
    current_limit_a: JOINT_PEAK_TORQUE_NM / (70.5e-3 * 100.0 * 0.73),
    i2t_warning_share: 0.3,
    i2t_fault_share: 0.6,
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
