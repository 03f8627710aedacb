//! The simulated device is the device we ship: the configuration the
//! simulator's live controller, supervisor, drivers and parts run with is
//! the firmware's (`exogait_device::DeviceConfig::exogait`); `cargo xtask
//! qemu` checks the firmware's side (its image prints the same CRC).

use exogait_device::DeviceConfig;
use host_tests::{standing_rig, strong_pilot};

#[test]
fn the_simulator_runs_the_device_configuration() {
    let device = DeviceConfig::exogait().unwrap();
    let rig = standing_rig(strong_pilot()).unwrap();
    let running = rig.running_config();
    assert_eq!(running, device);
    assert_eq!(running.fingerprint(), device.fingerprint());
    // And the check can fail: a simulator with other gains is caught.
    let mut other = running;
    other.controller.gains[0].kp_nm_per_rad *= 2.0;
    assert_ne!(other.fingerprint(), device.fingerprint());
}

#[test]
fn the_simulated_drives_enforce_the_device_limits() {
    let rig = standing_rig(strong_pilot()).unwrap();
    let d = rig.device().drives[0];
    let m = &rig.wiring.motors[0];
    // Ask for far more than the drive has: the bridge gives its peak.
    let mut pwm = m.pwm();
    let mut dir = m.direction_pin();
    let mut en = m.enable_pin();
    use embedded_hal::digital::OutputPin;
    use embedded_hal::pwm::SetDutyCycle;
    en.set_high().unwrap();
    dir.set_high().unwrap();
    pwm.set_duty_cycle(pwm.max_duty_cycle()).unwrap();
    let full = m.torque_nm();
    assert!(
        (full - f64::from(d.peak_torque_nm())).abs() < 1e-3,
        "{full}"
    );
    // Turning at the no-load speed while driving: nothing left.
    m.set_joint_speed(f64::from(d.no_load_speed_rad_s()));
    assert!(m.torque_nm() < 1.0, "{}", m.torque_nm());
    // Braking at that speed: the peak again.
    m.set_joint_speed(-f64::from(d.no_load_speed_rad_s()));
    assert!((m.torque_nm() - full).abs() < 1e-3);
    // Held at the peak, the winding model derates to the device's level
    // (the derated limit is above the continuous torque, so the
    // accumulator keeps rising to the fault level).
    m.set_joint_speed(0.0);
    let limits = rig.device().motors[0];
    for _ in 0..600_000 {
        m.integrate_thermal(0.001);
        if m.i2t_a2s() >= f64::from(limits.i2t_fault_a2s) {
            break;
        }
    }
    assert!(
        m.i2t_a2s() >= f64::from(limits.i2t_fault_a2s),
        "{}",
        m.i2t_a2s()
    );
    assert!((m.torque_nm() - f64::from(limits.derated_limit_nm)).abs() < 1e-3);
}
