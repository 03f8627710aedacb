//! The re-planner's test set-up, shared by its tests and its benchmark
//! (`benches/replan.rs` includes this file): the device's body, the
//! gaits' geometry, its drive and envelope, a pilot off the plan.

use gait_core::BodyModel;
use gait_core::foot::StanceFoot;
use gait_core::model::JointLimits;
use gait_core::replan::{DriveLimit, Measured, ReplanLimits, ReplanSetup};
use gait_core::tables::{GaitKind, GaitTable};

pub const KINDS: [GaitKind; 3] = [GaitKind::Walk, GaitKind::StairUp, GaitKind::StairDown];

/// The device's body: Table III with the heel-rocker joint limits
/// (exogait-device's `DeviceConfig::exogait`).
pub fn model() -> BodyModel<f32> {
    let t3 = BodyModel::<f64>::paper_table_iii();
    BodyModel::new(*t3.links(), JointLimits::paper_with_heel_rocker())
        .unwrap()
        .cast()
}

/// The gaits' geometry (gait-opt's `ClinicalCase::for_gait`).
pub fn spacing(kind: GaitKind) -> [f32; 2] {
    match kind {
        GaitKind::Walk => [0.3, 0.0],
        GaitKind::StairUp => [0.275, 0.0935],
        GaitKind::StairDown => [0.275, -0.0935],
    }
}

pub fn setup(m: &BodyModel<f32>, kind: GaitKind) -> ReplanSetup<'_, f32> {
    ReplanSetup {
        model: m,
        foot: StanceFoot::for_model(m),
        spring_nm_per_rad: 30.0,
        spacing_m: spacing(kind),
        crutch_lever_m: 0.45,
        aim_m: [0.0, 0.0],
    }
}

/// The hip and knee drive (ILM 85x26, CSG-25-80, ESCON 70/10 at 48 V):
/// 150 N·m peak, full torque to 2.215 rad/s, none at the 2.371 rad/s
/// no-load speed. Envelope: the supervisor's default on the heel-rocker
/// limits (hip −75° … 95°, knee −3° … 95°, ankle ≥ −10°).
pub fn limits() -> ReplanLimits<f32> {
    let d = |x: f32| x.to_radians();
    ReplanLimits::clinical(
        DriveLimit {
            peak_nm: 150.0,
            full_torque_speed_rad_s: 2.215,
            no_load_speed_rad_s: 2.371,
        },
        [d(-75.0), d(95.0)],
        [d(-3.0), d(95.0)],
        d(-10.0),
    )
}

/// The table's φ1 rate at its start, rad/s.
pub fn table_rate(t: &GaitTable<'_>) -> f32 {
    (t.sample(1).unwrap()[0] - t.first()[0]) / t.period_s()
}

/// A pilot `deg` off the table's start, moving with it.
pub fn measured(t: &GaitTable<'_>, deg: f32) -> Measured<f32> {
    Measured {
        phi1_rad: t.first()[0] + deg.to_radians(),
        rate_rad_s: table_rate(t),
        persist: 0.0,
        posture: None,
    }
}
