//! The plant against physics and its own bookkeeping.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::needless_range_loop)]

use std::f64::consts::PI;

use gait_core::kinematics::{anatomical_angles, forward_kinematics, theta_from_phi};
use sim::pilot::{PilotConfig, PilotTarget};
use sim::plant::{Landing, STANDING};
use sim::{Plant, PlantConfig, Side, SimError, Terrain};

const G: f64 = 9.81;

/// A joint-space PD "position servo" (test harness, not a controller):
/// anatomical targets per joint, gains per joint.
fn servo(plant: &Plant, target: [f64; 4], kp: f64, kd: f64) -> [f64; 4] {
    let s = plant.state();
    std::array::from_fn(|j| kp * (target[j] - s.joint_angles_rad[j]) - kd * s.joint_rates_rad_s[j])
}

fn free_config() -> PlantConfig {
    PlantConfig {
        ankle_stiffness_nm_per_rad: 0.0,
        stops: None,
        contact: None,
        max_speed_rad_s: 1e3,
        min_hip_height_m: -10.0,
        foot: None,
        ..PlantConfig::default()
    }
}

/// Leaning past the ankle's 20° stop, the stance heel lifts: the ankle then
/// reads the stop, rises on its circle about the toe, the switch loses a
/// little energy (plastic) and the motion on the toe conserves it.
#[test]
fn falling_past_the_stop_rolls_onto_the_toe() {
    let cfg = PlantConfig {
        foot: Some(gait_core::foot::StanceFoot::table_i()),
        ..free_config()
    };
    let stop = cfg.model.limits().ankle_dorsiflexion_rad;
    let phi = [stop - 0.02, 0.0, 0.0, PI, PI];
    let mut p =
        Plant::with_posture(cfg, phi, [1.0, 1.0, 1.0, 1.0, 1.0], Side::Left, [0.0, 0.0]).unwrap();
    p.set_pilot(PilotTarget::Off);
    let mut e = p.state().energy_j;
    let mut switched = false;
    for _ in 0..150 {
        p.step([0.0; 4]).unwrap();
        let s = p.state();
        if s.phi[0] > stop && !switched {
            switched = true;
            assert!(
                s.energy_j <= e + 1e-9,
                "heel-off gained energy: {e} -> {}",
                s.energy_j
            );
        } else if switched {
            assert!(((s.energy_j - e) / e).abs() < 1e-7, "{e} -> {}", s.energy_j);
        }
        e = s.energy_j;
    }
    assert!(switched);
    let s = p.state();
    assert!(s.phi[0] > stop + 0.1, "leaning on: {}", s.phi[0]);
    // The encoder reads the stop; the ankle has risen off the ground.
    assert_eq!(s.ankle_dorsiflexion_rad[0], Some(stop));
    assert!(s.points_m[0][1] > 0.01, "ankle at {:?}", s.points_m[0]);
}

#[test]
fn unforced_chain_conserves_energy_to_rk4_accuracy() {
    for stiffness in [0.0, 400.0] {
        let cfg = PlantConfig {
            ankle_stiffness_nm_per_rad: stiffness,
            ..free_config()
        };
        let phi = [0.05, -0.03, 0.04, PI - 0.2, PI + 0.1];
        let mut p = Plant::with_posture(cfg, phi, [0.0; 5], Side::Left, [0.0, 0.0]).unwrap();
        p.set_pilot(PilotTarget::Off);
        let e0 = p.state().energy_j;
        let mut moved = 0.0f64;
        for _ in 0..500 {
            p.step([0.0; 4]).unwrap();
            moved = moved.max((p.state().phi[0] - phi[0]).abs());
        }
        assert!(p.landings().is_empty());
        let e1 = p.state().energy_j;
        assert!(moved > 0.05, "the chain should fall: moved {moved}");
        assert!(
            ((e1 - e0) / e0).abs() < 1e-7,
            "k = {stiffness}: energy {e0} -> {e1}"
        );
    }
}

/// A drive's dynamic brake (375 N·m·s/rad on a shank of some 0.3 kg·m²,
/// a time constant under 1 ms) applied at every stage of the plant's
/// integration: stable at the full damping on either stance leg, each
/// braked joint's torque is −b ω at its own rate (a brake on the wrong
/// joint or role, or of the wrong sign, fails), and the energy lost is
/// what the brakes take (∫ Σ b ω² dt).
#[test]
fn braked_joints_dissipate_what_their_brakes_take_and_stay_stable() {
    let b = 375.0;
    let phi = [0.05, -0.03, 0.04, PI - 0.2, PI + 0.1];
    let patterns = [
        [b; 4],
        [0.0, b, 0.0, b],
        [b, 0.0, b, 0.0],
        [b, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, b],
    ];
    for stance in [Side::Left, Side::Right] {
        for brakes in patterns {
            let mut p =
                Plant::with_posture(free_config(), phi, [0.0; 5], stance, [0.0, 0.0]).unwrap();
            p.set_pilot(PilotTarget::Off);
            p.set_brakes(brakes);
            let e0 = p.state().energy_j;
            let power = |s: &sim::TrueState| -> f64 {
                (0..4)
                    .map(|j| brakes[j] * s.joint_rates_rad_s[j].powi(2))
                    .sum()
            };
            let (mut taken, mut last_power) = (0.0, power(&p.state()));
            let mut fastest = 0.0f64;
            for _ in 0..400 {
                let e_before = p.state().energy_j;
                p.step([0.0; 4]).unwrap();
                let s = p.state();
                let now = power(&s);
                taken += 0.5 * (last_power + now) * p.config().dt_s;
                last_power = now;
                let case = format!("{stance:?} {brakes:?}");
                assert!(s.energy_j <= e_before + 1e-9, "{case}: energy rose");
                for j in 0..4 {
                    // The brake opposes the motion, and is the only joint
                    // torque.
                    let (t, w) = (s.motor_torques_nm[j], s.joint_rates_rad_s[j]);
                    assert!((t + brakes[j] * w).abs() < 1e-9, "{case}: joint {j}");
                    if brakes[j] > 0.0 {
                        fastest = fastest.max(w.abs());
                    }
                }
            }
            let lost = e0 - p.state().energy_j;
            let case = format!("{stance:?} {brakes:?}");
            assert!(
                lost > 1e-4,
                "{case}: the brakes should take energy, lost {lost} J"
            );
            assert!(
                (lost - taken).abs() < 0.02 * taken,
                "{case}: lost {lost} J, brakes took {taken} J"
            );
            assert!(
                fastest < 5.0,
                "{case}: a braked joint ran at {fastest} rad/s"
            );
        }
    }
}

#[test]
fn ankle_spring_torque_pushes_back_and_pilot_off_gives_baseline_only() {
    let cfg = PlantConfig {
        ankle_stiffness_nm_per_rad: 100.0,
        ..free_config()
    };
    let phi = [0.1, 0.1, 0.0, PI, PI];
    let mut p = Plant::with_posture(cfg, phi, [0.0; 5], Side::Left, [0.0, 0.0]).unwrap();
    p.set_pilot(PilotTarget::Off);
    let s = p.state();
    assert!((s.spring_torque_nm + 10.0).abs() < 1e-12);
    assert_eq!(s.pilot_torque_nm, 0.0);
    let baseline = PilotConfig::default().baseline_crutch_load_n;
    assert!((s.crutch_forces_n[0] + s.crutch_forces_n[1] - baseline).abs() < 1e-12);
}

#[test]
fn limp_knees_buckle_and_the_fall_is_a_typed_error() {
    let cfg = PlantConfig {
        stops: None,
        ..PlantConfig::default()
    };
    // Stance knee flexed 0.1 rad, no motor torque: the knee folds.
    let phi = [0.05, -0.05, 0.0, PI, PI];
    let mut p = Plant::with_posture(cfg, phi, [0.0; 5], Side::Left, [0.0, 0.0]).unwrap();
    let mut last_knee = p.state().joint_angles_rad[1];
    assert!((last_knee - 0.1).abs() < 1e-12);
    let mut fell = None;
    for _ in 0..3000 {
        let before = p.state();
        match p.step([0.0; 4]) {
            Ok(_) => {
                let knee = p.state().joint_angles_rad[1];
                assert!(
                    knee >= last_knee - 1e-9,
                    "knee unfolds: {last_knee} -> {knee}"
                );
                last_knee = knee;
            }
            Err(e) => {
                // The state is left as it was before the failed step.
                assert_eq!(p.state(), before);
                fell = Some(e);
                break;
            }
        }
    }
    assert!(
        matches!(fell, Some(SimError::Fell { .. })),
        "expected a fall, got {fell:?}"
    );
    // With the device's stops, the knee stop at 100° flexion catches the
    // collapse (the hip and torso keep folding: that is not this test's
    // business, so the fall guard is lowered).
    let cfg = PlantConfig {
        min_hip_height_m: 0.1,
        ..PlantConfig::default()
    };
    let mut p = Plant::with_posture(cfg, phi, [0.0; 5], Side::Left, [0.0, 0.0]).unwrap();
    let mut deepest = 0.0f64;
    for _ in 0..1500 {
        if p.step([0.0; 4]).is_err() {
            break;
        }
        deepest = deepest.max(p.state().joint_angles_rad[1]);
    }
    let limit = 100f64.to_radians();
    assert!(deepest > limit && deepest < limit + 0.15, "knee {deepest}");
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let mut p = Plant::new(PlantConfig::default()).unwrap();
    assert_eq!(p.step([f64::NAN, 0.0, 0.0, 0.0]), Err(SimError::NonFinite));
    assert_eq!(p.time_s(), 0.0);
    let mut blew_up = false;
    for _ in 0..200 {
        match p.step([1e6, -1e6, 1e6, -1e6]) {
            Ok(_) => {}
            Err(SimError::Runaway { .. } | SimError::Fell { .. } | SimError::NonFinite) => {
                blew_up = true;
                break;
            }
            Err(e) => panic!("unexpected {e:?}"),
        }
    }
    assert!(blew_up);
    let bad = PlantConfig {
        dt_s: 0.0,
        ..PlantConfig::default()
    };
    assert_eq!(Plant::new(bad).err(), Some(SimError::Config("dt_s")));
}

#[test]
fn a_flexion_torque_flexes_each_joint_of_either_leg() {
    // Each motor alone, from standing, with the others held by the servo:
    // a positive (flexion) torque must increase that joint's flexion.
    for stance in [Side::Left, Side::Right] {
        for j in 0..4 {
            let mut p =
                Plant::with_posture(PlantConfig::default(), STANDING, [0.0; 5], stance, [0.0; 2])
                    .unwrap();
            for _ in 0..50 {
                let mut t = servo(&p, [0.0; 4], 2000.0, 100.0);
                t[j] = 20.0;
                p.step(t).unwrap();
            }
            let q = p.state().joint_angles_rad[j];
            assert!(q > 1e-3, "stance {stance:?}, joint {j}: flexion {q}");
        }
    }
}

#[test]
fn servo_holds_standing_and_crutches_carry_the_baseline() {
    // The bare chain (no swing-foot contact): everything through the stance
    // ankle, so the statics are exact.
    let cfg = PlantConfig {
        contact: None,
        ..PlantConfig::default()
    };
    let phi = [0.03, -0.02, 0.01, PI - 0.05, PI];
    let mut p = Plant::with_posture(cfg, phi, [0.0; 5], Side::Right, [0.0, 0.0]).unwrap();
    p.set_pilot(PilotTarget::Hold { phi1_rad: 0.0 });
    // The servo leaves the chain compliant, and the pilot damps a slow
    // (≈ 2 s) sway: give it 6 s.
    for _ in 0..6000 {
        let t = servo(&p, [0.0; 4], 1500.0, 80.0);
        p.step(t).unwrap();
    }
    let s = p.state();
    let m = cfg.model.total_mass_kg();
    assert!(s.phi[0].abs() < 2e-3, "phi1 {}", s.phi[0]);
    for q in s.joint_angles_rad {
        assert!(q.abs() < 2e-3, "{:?}", s.joint_angles_rad);
    }
    let hip = s.points_m[2][1];
    assert!((hip - 0.836).abs() < 1e-3, "hip {hip}");
    let crutch = s.crutch_forces_n[0] + s.crutch_forces_n[1];
    let baseline = cfg.pilot.baseline_crutch_load_n;
    assert!((crutch - baseline).abs() < 2.0, "crutch {crutch}");
    assert!((s.crutch_forces_n[0] - s.crutch_forces_n[1]).abs() < 1e-12);
    let feet = s.foot_forces_n[0] + s.foot_forces_n[1];
    assert!(
        (feet + crutch - m * G).abs() < 0.01 * m * G,
        "feet {feet} + crutch {crutch} vs weight {}",
        m * G
    );
    // Without ground contact the swing (left) foot carries nothing.
    assert!(s.foot_forces_n[0] == 0.0 && s.foot_forces_n[1] > 100.0);
    assert!(p.landings().is_empty());
}

/// A step: stance leaning forward, swing leg flexed in the air; the servo
/// straightens the swing knee so the foot comes down ahead.
fn stepping_plant(terrain: Terrain) -> (Plant, [f64; 4]) {
    let cfg = PlantConfig {
        terrain,
        ..PlantConfig::default()
    };
    let phi1 = 0.15;
    let phi = [phi1, phi1, 0.0, PI - 0.55, PI + 0.3];
    let pts = forward_kinematics(&cfg.model, &phi);
    assert!(
        pts[4][1] > 0.05,
        "swing foot starts in the air: {:?}",
        pts[4]
    );
    let mut p = Plant::with_posture(cfg, phi, [0.0; 5], Side::Left, [0.0, 0.0]).unwrap();
    p.set_pilot(PilotTarget::Hold { phi1_rad: phi1 });
    let anat = anatomical_angles(&theta_from_phi(&phi));
    // Left stance: left hip, left knee, right hip, right knee.
    let target = [anat[2], anat[1], 0.45, 0.0];
    (p, target)
}

fn run_until_landing(p: &mut Plant, target: [f64; 4]) -> (sim::TrueState, Landing) {
    for _ in 0..2000 {
        let before = p.state();
        let t = servo(p, target, 1500.0, 80.0);
        if let Some(l) = p.step(t).unwrap() {
            return (before, l);
        }
    }
    panic!("no landing; swing foot at {:?}", p.state().points_m[5]);
}

#[test]
fn landing_swaps_legs_and_keeps_the_world_consistent() {
    let (mut p, target) = stepping_plant(Terrain::Level);
    assert!(p.state().swing_lifted);
    let (before, landing) = run_until_landing(&mut p, target);
    let after = p.state();
    assert_eq!(landing.side, Side::Right);
    assert_eq!(after.stance, Side::Right);
    assert_eq!(p.landings(), &[landing]);
    assert!(landing.descent_speed_m_s > 0.0);
    assert!(landing.position_m[1].abs() < 0.01, "{landing:?}");
    assert!(landing.step_length_m > 0.1, "{landing:?}");
    // The new stance foot is where the swing foot touched down; the old
    // stance foot has not moved.
    assert_eq!(after.feet_m[1], landing.position_m);
    for k in 0..2 {
        assert!((after.feet_m[0][k] - before.feet_m[0][k]).abs() < 1e-9);
    }
    // Every joint angle of each physical leg is continuous through the
    // swap (the posture is mirrored, not changed), and so is the hip.
    for j in 0..4 {
        assert!(
            (after.joint_angles_rad[j] - before.joint_angles_rad[j]).abs() < 0.02,
            "joint {j}: {:?} -> {:?}",
            before.joint_angles_rad,
            after.joint_angles_rad
        );
    }
    assert!(!after.swing_lifted);
    // The trailing foot is still planted: its encoder reads its shank's
    // lean as the stance one does (it read "in the air" at the swap, and
    // the controller's heel-up estimate flipped in a noisy stair descent).
    let planted = after.ankle_dorsiflexion_rad[0].expect("the trailing ankle reads");
    let stop = p.config().model.limits().ankle_dorsiflexion_rad;
    let lean = gait_core::kinematics::wrap_pi(after.phi[4] - std::f64::consts::PI);
    assert!((planted - lean.min(stop)).abs() < 1e-12, "{planted} {lean}");
    assert!(after.ankle_dorsiflexion_rad[1].is_some());
    // The new swing foot (left) is on the ground and loaded.
    assert!(after.foot_forces_n[0] >= 0.0 && after.foot_forces_n[1] > 0.0);
}

#[test]
fn landing_on_a_stair_tread_raises_the_stance_frame() {
    let terrain = Terrain::Stairs {
        start_x_m: 0.15,
        rise_m: 0.04,
        tread_m: 0.3,
        steps: 3,
    };
    let (mut p, target) = stepping_plant(terrain);
    let (_, landing) = run_until_landing(&mut p, target);
    assert!((landing.ground_m - 0.04).abs() < 1e-12, "{landing:?}");
    assert!((landing.position_m[1] - 0.04).abs() < 0.01, "{landing:?}");
    let s = p.state();
    assert_eq!(s.points_m[0], landing.position_m);
    // Hip height in the world is the new stance foot's height plus the
    // frame's hip height.
    let hip_frame = forward_kinematics(&p.config().model, &s.phi)[1][1];
    assert!((s.points_m[2][1] - (landing.position_m[1] + hip_frame)).abs() < 1e-12);
}

#[test]
fn knee_stop_holds_full_extension() {
    let mut p = Plant::new(PlantConfig::default()).unwrap();
    let mut worst = 0.0f64;
    for _ in 0..500 {
        let mut t = servo(&p, [0.0; 4], 1500.0, 80.0);
        // Both knees pushed into extension with 30 N·m.
        t[1] = -30.0;
        t[3] = -30.0;
        p.step(t).unwrap();
        let s = p.state();
        worst = worst.min(s.joint_angles_rad[1]).min(s.joint_angles_rad[3]);
    }
    let s = p.state();
    assert!(worst > -0.012, "knee hyperextends to {worst}");
    // At rest against the stop, the swing knee's stop carries the push
    // (+30 N·m); the stance knee's also carries part of the body's weight.
    assert!(s.stop_torques_nm[1] > 25.0, "{:?}", s.stop_torques_nm);
    assert!(
        (s.stop_torques_nm[3] - 30.0).abs() < 3.0,
        "{:?}",
        s.stop_torques_nm
    );
    // Without stops the same push folds the knee backwards.
    let cfg = PlantConfig {
        stops: None,
        ..PlantConfig::default()
    };
    let mut p = Plant::new(cfg).unwrap();
    for _ in 0..200 {
        let mut t = servo(&p, [0.0; 4], 1500.0, 80.0);
        t[3] = -30.0;
        p.step(t).unwrap();
    }
    assert!(p.state().joint_angles_rad[3] < -0.05);
}

#[test]
fn leaning_pilot_carries_the_gravity_moment_on_the_crutches() {
    // Held still leaning forward, the ankle must supply −M·g·x_com (statics);
    // the spring takes its share, the pilot the rest, and the crutches carry
    // the pilot's part over the lever, plus the baseline. Bare chain: no
    // swing-foot contact sharing the moment.
    let cfg = PlantConfig {
        contact: None,
        ..PlantConfig::default()
    };
    let lean = 0.08;
    let phi = [lean, lean, 0.0, PI, PI];
    let mut p = Plant::with_posture(cfg, phi, [0.0; 5], Side::Left, [0.0, 0.0]).unwrap();
    p.set_pilot(PilotTarget::Hold { phi1_rad: lean });
    let anat = anatomical_angles(&theta_from_phi(&phi));
    let target = [anat[2], anat[1], anat[3], anat[4]];
    for _ in 0..6000 {
        let t = servo(&p, target, 3000.0, 150.0);
        p.step(t).unwrap();
    }
    let s = p.state();
    let m = cfg.model.total_mass_kg();
    let gravity_moment = m * G * s.com_m[0];
    assert!(s.com_m[0] > 0.05, "leaning forward: {:?}", s.com_m);
    let ankle = s.pilot_torque_nm + s.spring_torque_nm;
    assert!(
        (ankle + gravity_moment).abs() < 0.01 * gravity_moment,
        "ankle {ankle} vs −M g x = {}",
        -gravity_moment
    );
    assert!((s.spring_torque_nm + cfg.ankle_stiffness_nm_per_rad * s.phi[0]).abs() < 1e-9);
    let crutch = s.crutch_forces_n[0] + s.crutch_forces_n[1];
    let expected =
        s.pilot_torque_nm.abs() / cfg.pilot.crutch_lever_m + cfg.pilot.baseline_crutch_load_n;
    assert!((crutch - expected).abs() < 1e-9);
    assert!(
        crutch > cfg.pilot.baseline_crutch_load_n + 100.0,
        "{crutch}"
    );
    // The feet carry the rest of the weight.
    let feet = s.foot_forces_n[0] + s.foot_forces_n[1];
    assert!((feet + crutch - m * G).abs() < 0.01 * m * G);
}
