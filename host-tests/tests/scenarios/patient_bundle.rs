//! A patient's bundle in the closed loop: the controller the board builds
//! for it (`exogait_device::boot::patient_gaits`) offers its gaits in the
//! bundle's order; MODE picks the next, GO plays the one picked, and GO on
//! a gait whose start posture the pilot is not in starts nothing; each
//! gait plays with the stance-hip residual limit its entry carries.

use exogait_device::DeviceConfig;
use exogait_device::boot::{self, TableSlots};
use gait_control::operator::Gait;
use gait_control::sequencer::Phase;
use gait_core::anthropometry::SegmentLengths;
use gait_core::bundle::{Bundle, MAX_GAITS, Patient};
use sim::closed_loop::Rig;
use sim::scenario::{GO_TICKS, descent_then_walk_bundle, patient_rig, run_steps, strong_pilot};

/// A bundle for the device's own body: stair descent first, then walking.
fn bundle(device: &DeviceConfig) -> Vec<u8> {
    let l = SegmentLengths::winter(1.75);
    let patient = Patient {
        height_m: 1.75,
        mass_kg: 76.5,
        segments_m: [l.thigh_m, l.shank_m, l.foot_m],
        model: device.body,
    };
    descent_then_walk_bundle(device, &patient).unwrap()
}

/// Runs `f` on a rig of the device's body standing for the walk, over the
/// controller's list of the bundle (descent, then walk).
fn with_rig(f: impl FnOnce(&mut Rig<'_>)) {
    let device = DeviceConfig::exogait().unwrap();
    let image = bundle(&device);
    let b = Bundle::parse(&image, device.fingerprint()).unwrap();
    let mut slots: TableSlots<'_> = [None; MAX_GAITS];
    let (tables, operator) = boot::patient_gaits(&b, &mut slots, device.reset_hold_ticks).unwrap();
    let mut rig = patient_rig(&device, Gait::Walk, strong_pilot(), tables, operator).unwrap();
    f(&mut rig);
}

#[test]
fn mode_picks_the_bundles_second_gait_and_go_plays_it() {
    with_rig(|rig| {
        // The first gait of the list is the descent.
        assert_eq!(rig.controller.planned_gait(), Gait::StairDown);
        // One short press of MODE, then GO held.
        Rig::press(&rig.mode, 200, 100);
        Rig::press(&rig.go, 600, GO_TICKS);
        run_steps(rig, 2, 16.0).unwrap();
        assert_eq!(rig.controller.sequencer().gait(), Gait::Walk);
        // The walk's stance-hip residual limit, from the bundle's
        // directory (the built-in walk's), is the one its swings are
        // checked with (0x0404): below the device's 100 N·m.
        let walk = gait_core::flash_tables::walk().unwrap();
        let limit = rig.controller.sequencer().stance_hip_residual_nm();
        assert_eq!(limit, walk.stance_hip_residual_nm());
        assert!((70.0..100.0).contains(&limit), "{limit}");
        assert!(rig.faults().is_empty(), "{:?}", rig.faults());
        let landings = rig.plant.landings();
        assert!(landings.len() >= 2);
        // Walking steps of 0.3 m on level ground.
        assert!(
            (landings[0].position_m[0] - 0.3).abs() < 0.05,
            "{landings:?}"
        );
        assert!(landings[1].position_m[1].abs() < 0.01);
    });
}

#[test]
fn go_on_a_gait_the_pilot_does_not_stand_for_starts_nothing() {
    // Standing for the walk, the descent (the list's first) picked.
    with_rig(|rig| {
        Rig::press(&rig.go, 600, GO_TICKS);
        for _ in 0..6_000 {
            let s = rig.tick().unwrap();
            assert!(
                !matches!(
                    s.report.phase,
                    Phase::Swing { .. } | Phase::WaitingReady { .. }
                ),
                "a step started at {} s",
                s.state.time_s
            );
        }
        assert!(rig.plant.landings().is_empty());
        assert!(rig.faults().is_empty(), "{:?}", rig.faults());
    });
}
