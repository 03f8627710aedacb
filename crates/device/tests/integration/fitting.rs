//! The device fitted to a patient: the torque residual's inertias follow
//! the patient's body (`fitting::response_for`), checked against the
//! Lagrangian's own coefficients.

use exogait_device::DeviceConfig;
use exogait_device::fitting::{Measures, fit, response_for};
use gait_core::model::BodyModel;

fn patient(height_m: f64, mass_kg: f64) -> BodyModel<f64> {
    let device = DeviceConfig::exogait().unwrap();
    fit(&device, &Measures::height_and_mass(height_m, mass_kg))
        .unwrap()
        .model
}

/// What the swing inertias stand for, from the model's p_ij (D_ij = p_ij
/// cos(φi − φj)): the shank about the knee is D₅₅, the straight leg about
/// the hip D₄₄ + 2 D₄₅ + D₅₅.
fn swing_from_lagrangian(body: &BodyModel<f64>) -> (f64, f64) {
    let p = body.p();
    (p[3][3] + 2.0 * p[3][4] + p[4][4], p[4][4])
}

#[test]
fn the_residual_s_inertias_follow_the_patient_s_body() {
    let device = DeviceConfig::exogait().unwrap();
    let own = device.supervisor.response;
    // The device's own body: unchanged.
    assert_eq!(response_for(&own, &device.body, &device.body), own);
    for (height, mass) in [(1.60, 55.0), (1.90, 95.0)] {
        let body = patient(height, mass);
        let fitted = device.fitted(&body).unwrap();
        let r = fitted.supervisor.response;
        let (hip, knee) = swing_from_lagrangian(&body);
        let (hip0, knee0) = swing_from_lagrangian(&device.body);
        let close = |a: f32, b: f64| ((f64::from(a) - b) / b).abs() < 1e-5;
        assert!(close(
            r.swing_inertia_kgm2[0],
            f64::from(own.swing_inertia_kgm2[0]) * hip / hip0
        ));
        assert!(close(
            r.swing_inertia_kgm2[1],
            f64::from(own.swing_inertia_kgm2[1]) * knee / knee0
        ));
        let leg = |b: &BodyModel<f64>| b.links()[0].length_m + b.links()[1].length_m;
        let stance = body.total_mass_kg() * leg(&body).powi(2)
            / (device.body.total_mass_kg() * leg(&device.body).powi(2));
        assert!(close(
            r.stance_inertia_kgm2[0],
            f64::from(own.stance_inertia_kgm2[0]) * stance
        ));
        assert!(close(
            r.stance_inertia_kgm2[1],
            f64::from(own.stance_inertia_kgm2[1]) * stance
        ));
        // The bound and the filter are the device's.
        assert_eq!(r.limit_nm, own.limit_nm);
        assert_eq!(r.ticks, own.ticks);
        assert_eq!(r.bandwidth_hz, own.bandwidth_hz);
        // Heavier and taller, heavier limbs: larger inertias, and smaller
        // for the lighter patient.
        let heavier = mass > 80.0;
        assert_eq!(
            r.stance_inertia_kgm2[0] > own.stance_inertia_kgm2[0],
            heavier
        );
        assert_eq!(r.swing_inertia_kgm2[0] > own.swing_inertia_kgm2[0], heavier);
    }
}
