//! The joint-level figures derived from the parts' datasheets.

use exogait_device::DeviceConfig;
use exogait_device::parts::{JOINT_DRIVE, JOINT_PEAK_TORQUE_NM};

#[test]
fn the_joint_drive_peak_continuous_and_torque_speed_line() {
    let d = JOINT_DRIVE;
    // The current limit gives the product's 150 N·m ceiling, below the
    // gear's repeated-peak rating.
    assert!(
        (d.peak_torque_nm() - JOINT_PEAK_TORQUE_NM).abs() < 1e-3,
        "{}",
        d.peak_torque_nm()
    );
    assert!(d.peak_torque_nm() <= d.gearbox.repeated_peak_torque_nm);
    assert!(d.current_limit_a <= d.amplifier.peak_current_a);
    // The gear's average-torque rating (the motor alone: 11.5 A × 0.253 ×
    // 80 × 0.75 = 175 N·m).
    assert!((d.continuous_torque_nm() - 113.0).abs() < 1e-3);
    assert!(d.continuous_current_a() <= d.amplifier.continuous_current_a);
    // 48 V / 0.253 V·s/rad / 80 = 2.37 rad/s.
    assert!(
        (d.no_load_speed_rad_s() - 2.371).abs() < 0.01,
        "{}",
        d.no_load_speed_rad_s()
    );
    let corner = d.full_torque_speed_rad_s();
    assert!(corner > 2.0 && corner < d.no_load_speed_rad_s(), "{corner}");
    assert!((d.available_torque_nm(0.0, 1.0) - 150.0).abs() < 1e-3);
    assert!((d.available_torque_nm(0.99 * corner, 1.0) - 150.0).abs() < 1e-3);
    assert!(d.available_torque_nm(d.no_load_speed_rad_s(), 1.0) < 1.0);
    assert!((d.available_torque_nm(2.3, -1.0) - 150.0).abs() < 1e-3);
    // The line between, from V = R I + k_e ω: at 2.3 rad/s driving,
    // I = (48 − 0.253 · 184) / 0.32.
    let ke = 60.0 / (2.0 * std::f32::consts::PI * 37.74);
    let i = (48.0 - ke * 184.0) / 0.32;
    assert!((d.available_torque_nm(2.3, 1.0) - i * 0.253 * 80.0 * 0.75).abs() < 0.1);
}

#[test]
fn the_motor_driver_uses_the_drive_figures() {
    let cfg = DeviceConfig::exogait().unwrap();
    for m in cfg.motors {
        m.validate().unwrap();
        assert!((m.torque_limit_nm - JOINT_DRIVE.peak_torque_nm()).abs() < 1e-3);
        assert!(m.derated_limit_nm > JOINT_DRIVE.continuous_torque_nm());
        // The driver's current estimate at the peak is the current limit.
        let current = m.torque_limit_nm / (m.gear_ratio * m.torque_constant_nm_per_a);
        assert!((current - JOINT_DRIVE.current_limit_a).abs() < 1e-3);
        assert!(m.i2t_warning_a2s < m.i2t_fault_a2s);
    }
    for g in cfg.controller.gains {
        assert!(g.torque_limit_nm <= JOINT_DRIVE.peak_torque_nm() + 1e-3);
    }
}

#[test]
fn the_fingerprint_changes_with_any_value() {
    let a = DeviceConfig::exogait().unwrap();
    let b = DeviceConfig::exogait().unwrap();
    assert_eq!(a.fingerprint(), b.fingerprint());
    let mut c = a;
    c.controller.gains[1].kd_nm_s_per_rad += 1e-3;
    assert_ne!(a.fingerprint(), c.fingerprint());
    let mut d = a;
    d.supervisor.tracking_error_ticks += 1;
    assert_ne!(a.fingerprint(), d.fingerprint());
}

#[test]
fn the_dynamic_brake_damps_the_joint_as_its_winding_and_resistor_allow() {
    let d = JOINT_DRIVE;
    // η N² k_t k_e / (R + R_brake) = 0.75 · 80² · 0.253 · 0.2530 / 0.82.
    let kt = 0.253_f32;
    let ke = 1.0 / (37.74 * core::f32::consts::PI / 30.0);
    let expected = 0.75 * 80.0 * 80.0 * kt * ke / (0.32 + 0.5);
    let b = d.brake_damping_nm_s_per_rad();
    assert!((b - expected).abs() < 1e-3 * expected, "{b} vs {expected}");
    assert!((370.0..380.0).contains(&b), "{b}");
    // A 75 N·m load sinks at 0.2 rad/s; the braking current is then
    // under the motor's nominal 11.5 A.
    let speed = 75.0 / b;
    let current = ke * 80.0 * speed / (0.32 + 0.5);
    assert!(
        speed < 0.21 && current < d.motor.nominal_current_a,
        "{speed} rad/s, {current} A"
    );
    let limp = exogait_device::drive::DriveSpec { brake: None, ..d };
    assert_eq!(limp.brake_damping_nm_s_per_rad(), 0.0);
}
