//! The flash tables meet the clinical requirements on the table itself (the
//! closed loop is checked in host-tests and by `exogait compare`): within
//! the drives and the supervisor, a person's clearance, no torque spike
//! beyond the human gait's, periodic, accepted by the device.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    missing_docs
)]

use exogait_device::DeviceConfig;
use exogait_device::admission::check_table;
use gait_core::kinematics::swap_legs;
use gait_core::tables::{GaitKind, GaitTable};
use gait_opt::clinical::{ClinicalCase, evaluate_phi};
use gait_opt::human::playable_human_gait;

fn shipped(kind: GaitKind) -> GaitTable<'static> {
    gait_core::flash_tables::of(kind).unwrap()
}

fn phi_of(t: &GaitTable<'_>) -> Vec<[f64; 5]> {
    (0..t.len())
        .map(|k| t.sample(k).unwrap().map(f64::from))
        .collect()
}

#[test]
fn each_flash_table_suits_the_drives_the_supervisor_and_a_person() {
    let device = DeviceConfig::exogait().unwrap();
    for kind in [GaitKind::Walk, GaitKind::StairUp, GaitKind::StairDown] {
        let table = shipped(kind);
        let case = ClinicalCase::for_gait(kind, &device);
        let phi = phi_of(&table);
        let e = evaluate_phi(&case, &phi).unwrap();
        // The device accepts it (envelope, speeds, torques within the
        // drive at every sample).
        let demand = check_table(&device, &table).unwrap();
        // Within the drives with margin for the position loop.
        assert!(
            demand.drive_use <= 0.8,
            "{kind:?}: drive use {}",
            demand.drive_use
        );
        assert!(e.drive_use <= 0.8, "{kind:?}: {}", e.drive_use);
        // Slow, smooth joints: below the design speed, well below the
        // supervisor's 6 / 8 rad/s and the drive's 2.2 rad/s corner.
        for s in e.joint_speed_peak_rad_s {
            assert!(s <= 1.9, "{kind:?}: joint speed {s}");
        }
        assert!(
            e.joint_accel_peak_rad_s2 <= 25.0,
            "{kind:?}: {}",
            e.joint_accel_peak_rad_s2
        );
        // The drives' I²t over steps (each joint a stance joint one step, a
        // swing joint the next) within the continuous rating.
        assert!(
            e.i2t_ratio.iter().all(|&r| r <= 1.0),
            "{kind:?}: {:?}",
            e.i2t_ratio
        );
        // A person's clearance: 3–8 cm over the floor or the nosing, and
        // no part of the sole through anything.
        assert!(
            (0.03..=0.08).contains(&e.clearance_m),
            "{kind:?}: clearance {}",
            e.clearance_m
        );
        assert!(
            e.sole_margin_m >= -0.005,
            "{kind:?}: sole {}",
            e.sole_margin_m
        );
        // No torque spike: the stance ankle's peak no higher than the
        // human gait's at the same geometry and timing.
        let human = playable_human_gait(&case, &gait_opt::default_data_dir()).unwrap();
        let h = evaluate_phi(&case, &human.phi).unwrap();
        assert!(
            e.ankle_peak_nm <= h.ankle_peak_nm,
            "{kind:?}: ankle peak {} vs human {}",
            e.ankle_peak_nm,
            h.ankle_peak_nm
        );
        // The predicted crutch load is well below the human gait's.
        assert!(
            e.balance_ns < 0.5 * h.balance_ns,
            "{kind:?}: {} vs {}",
            e.balance_ns,
            h.balance_ns
        );
        // Periodic: the landing posture, seen from the new stance foot, is
        // the start posture (the transfer between steps moves nothing).
        let first = phi[0];
        let landing = swap_legs(phi.last().unwrap());
        for i in 0..5 {
            assert!(
                (landing[i] - first[i]).abs() < 2e-3,
                "{kind:?}: link {i}: {} vs {}",
                landing[i],
                first[i]
            );
        }
    }
}

#[test]
fn the_admission_check_names_the_sample_the_joint_and_the_limit() {
    let device = DeviceConfig::exogait().unwrap();
    // The walk table played twice as fast: its joints turn too fast for
    // the drive somewhere.
    let t = shipped(GaitKind::Walk);
    let phi = phi_of(&t);
    let fast: Vec<[f64; 5]> = phi.iter().step_by(3).copied().collect();
    let image =
        gait_opt::tables::table_image(GaitKind::Walk, &t.ik_options().cast(), &fast).unwrap();
    let table = GaitTable::parse(&image).unwrap();
    let err = check_table(&device, &table).unwrap_err();
    let text = err.to_string();
    assert!(text.starts_with("sample "), "{text}");
    assert!(
        ["stance", "swing"].iter().any(|w| text.contains(w)),
        "{text}"
    );
    assert!(
        text.contains("rad/s") || text.contains("N·m") || text.contains('°'),
        "{text}"
    );
}
