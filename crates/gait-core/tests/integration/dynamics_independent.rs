//! The paper's dynamics checked against derivations that share no code with
//! it: the mass matrix from the kinetic energy through centre-of-mass
//! Jacobians (`chain.rs`), the full equation of motion from the Lagrangian by numerical
//! differentiation, energy conservation of the free chain, and Aᵀ by virtual
//! work.

use gait_core::dynamics::Contact::FixedAnkle;
use gait_core::dynamics::{energy, forward_dynamics, inverse_dynamics, rk4_step, terms};
use gait_core::kinematics::{joint_torques, phi_from_theta};
use gait_core::model::GRAVITY_M_S2;
use gait_core::{BodyModel, LINKS};
use proptest::prelude::*;

use crate::chain::{fixed, lagrange_torques, mass_matrix, potential};

fn state() -> impl Strategy<Value = ([f64; LINKS], [f64; LINKS], [f64; LINKS])> {
    let ang = prop::array::uniform5(-3.5f64..3.5);
    let vel = prop::array::uniform5(-4.0f64..4.0);
    let acc = prop::array::uniform5(-20.0f64..20.0);
    (ang, vel, acc)
}

#[test]
fn printed_coupling_index_is_wrong_and_corrected_one_is_right() {
    // The printed p_ij (j > i) sums masses beyond link i; the kinetic energy
    // says beyond link j. For (i, j) = (1, 2) the printed form would add
    // l1 l2 m2 to the true coupling.
    let m = BodyModel::<f64>::paper_table_iii();
    let phi = [0.1, -0.2, 0.05, 2.9, 3.3];
    let d_energy = mass_matrix(&m, &fixed, &phi);
    let c = (phi[0] - phi[1]).cos();
    let printed = 0.441 * 10.5 * 0.228 + 0.441 * 0.395 * (10.5 + 57.7 + 11.5 + 6.05);
    assert!((d_energy[0][1] - printed * c).abs() > 1.0);
    let d_model = terms(&m, &FixedAnkle, &phi, &[0.0; LINKS]).d;
    assert!((d_energy[0][1] - d_model[(0, 1)]).abs() < 1e-12);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn mass_matrix_matches_kinetic_energy((q, _w, _a) in state()) {
        let m = BodyModel::<f64>::paper_table_iii();
        let d_model = terms(&m, &FixedAnkle, &q, &[0.0; LINKS]).d;
        let d_energy = mass_matrix(&m, &fixed, &q);
        for i in 0..LINKS {
            for j in 0..LINKS {
                prop_assert!((d_model[(i, j)] - d_energy[i][j]).abs() < 1e-12,
                    "D[{i}][{j}] model {} energy {}", d_model[(i, j)], d_energy[i][j]);
            }
        }
    }

    #[test]
    fn inverse_dynamics_matches_lagrangian((q, w, a) in state()) {
        let m = BodyModel::<f64>::paper_table_iii();
        let t = inverse_dynamics(&m, &FixedAnkle, &q, &w, &a);
        let r = lagrange_torques(&m, &fixed, &q, &w, &a);
        let scale = r.iter().fold(1.0f64, |s, x| s.max(x.abs()));
        for i in 0..LINKS {
            prop_assert!((t[i] - r[i]).abs() < 1e-6 * scale, "T[{i}] {} vs {}", t[i], r[i]);
        }
    }

    #[test]
    fn forward_dynamics_inverts_inverse_dynamics((q, w, a) in state()) {
        let m = BodyModel::<f64>::paper_table_iii();
        let t = inverse_dynamics(&m, &FixedAnkle, &q, &w, &a);
        let back = forward_dynamics(&m, &FixedAnkle, &q, &w, &t).unwrap();
        for i in 0..LINKS {
            prop_assert!((back[i] - a[i]).abs() < 1e-8 * (1.0 + a[i].abs()));
        }
    }

    #[test]
    fn joint_torques_by_virtual_work((q, w, a) in state(), dtheta in prop::array::uniform5(-1.0f64..1.0)) {
        // δW = T_Θ·δΘ must equal T_Φ·δΦ with δΦ = A δΘ.
        let m = BodyModel::<f64>::paper_table_iii();
        let t_phi = inverse_dynamics(&m, &FixedAnkle, &q, &w, &a);
        let t_theta = joint_torques(&t_phi);
        let zero = phi_from_theta(&[0.0; LINKS]);
        let moved = phi_from_theta(&dtheta);
        let dphi: Vec<f64> = (0..LINKS).map(|i| moved[i] - zero[i]).collect();
        let w_theta: f64 = (0..LINKS).map(|i| t_theta[i] * dtheta[i]).sum();
        let w_phi: f64 = (0..LINKS).map(|i| t_phi[i] * dphi[i]).sum();
        prop_assert!((w_theta - w_phi).abs() < 1e-9 * (1.0 + w_phi.abs()));
    }

    #[test]
    fn f32_inverse_dynamics_agrees_with_f64((q, w, a) in state()) {
        let m64 = BodyModel::<f64>::paper_table_iii();
        let m32: BodyModel<f32> = m64.cast();
        let t64 = inverse_dynamics(&m64, &FixedAnkle, &q, &w, &a);
        let f = |x: [f64; LINKS]| x.map(|v| v as f32);
        let t32 = inverse_dynamics(&m32, &FixedAnkle, &f(q), &f(w), &f(a));
        let scale = t64.iter().fold(1.0f64, |s, x| s.max(x.abs()));
        for i in 0..LINKS {
            // f32 carries ~7 digits; angles up to 3.5 rad lose a little more.
            prop_assert!((f64::from(t32[i]) - t64[i]).abs() < 2e-5 * scale);
        }
    }
}

#[test]
fn free_chain_conserves_energy_under_rk4() {
    let m = BodyModel::<f64>::paper_table_iii();
    let mut q = [0.15, -0.25, 0.1, 2.8, 3.4];
    let mut w = [0.5, -0.8, 0.3, -1.5, 2.0];
    let e0 = energy(&m, &FixedAnkle, &q, &w);
    let zero = [0.0; LINKS];
    let mut max_drift = 0.0f64;
    let mut moved = 0.0f64;
    // RK4's error is O(h⁴): at h = 0.25 ms the integrator, not the model,
    // would have to be wrong for the drift to exceed 1e-6.
    for _ in 0..4000 {
        let (q1, w1) = rk4_step(&m, &FixedAnkle, &q, &w, &zero, 2.5e-4).unwrap();
        moved = moved.max((q1[0] - 0.15).abs());
        q = q1;
        w = w1;
        max_drift = max_drift.max(((energy(&m, &FixedAnkle, &q, &w) - e0) / e0).abs());
    }
    // The chain really moved (a conserved energy of a frozen state is no test).
    assert!(moved > 0.1, "stance shank moved only {moved} rad");
    assert!(
        max_drift < 1e-6,
        "relative energy drift {max_drift:e} over 1 s"
    );
}

#[test]
fn energy_matches_independent_kinetic_and_potential() {
    let m = BodyModel::<f64>::paper_table_iii();
    let q = [0.2, -0.1, 0.05, 2.7, 3.5];
    let w = [0.4, -0.9, 0.2, -2.1, 3.3];
    let d = mass_matrix(&m, &fixed, &q);
    let mut k = 0.0;
    for i in 0..LINKS {
        for j in 0..LINKS {
            k += 0.5 * w[i] * d[i][j] * w[j];
        }
    }
    let e = k + potential(&m, &fixed, &q);
    assert!((energy(&m, &FixedAnkle, &q, &w) - e).abs() < 1e-9 * e.abs());
}

/// Double-support statics by virtual work, independently of the Jacobian
/// the function uses: moving the chain with both feet fixed (the IK keeps
/// the swing ankle where it is while φ1, φ3 and r2 change), the joint
/// torques' work Σ T_θi δθ_i equals the rise in potential energy — the
/// foot's reaction does no work on a fixed foot. Checked along each of the
/// three closed-chain directions, at the start postures of the walk and
/// the stair ascent.
#[test]
fn double_support_statics_satisfy_virtual_work() {
    use gait_core::dynamics::{FOOT_FRICTION, double_support_statics};
    use gait_core::ik::{IkSolver, IkTarget};
    use gait_core::kinematics::theta_from_phi;
    let m = BodyModel::<f64>::paper_table_iii();
    let ik = IkSolver::new(&m);
    let weight = m.total_mass_kg() * GRAVITY_M_S2;
    for (x5, y5, phi1, r2) in [
        (-0.3, 0.0, -0.0932, 1.0 - 1e-3),
        (-0.275, -0.0935, 0.0017, 0.5),
    ] {
        let target = IkTarget {
            x5,
            y5,
            phi1,
            phi3: 0.0,
            r2,
        };
        let phi = ik.solve(&target).unwrap().phi;
        let s = double_support_statics(&m, &FixedAnkle, &phi, weight);
        let [fx, fy] = s.reaction_n;
        assert!(fy > 0.0 && fy <= weight && fx.abs() <= FOOT_FRICTION * fy + 1e-9);
        let h = 1e-6;
        for dir in 0..3 {
            let shifted = |sign: f64| {
                let mut t = target;
                match dir {
                    0 => t.phi1 += sign * h,
                    1 => t.phi3 += sign * h,
                    _ => t.r2 += sign * h,
                }
                ik.solve(&t).unwrap().phi
            };
            let (plus, minus) = (shifted(1.0), shifted(-1.0));
            let (tp, tm) = (theta_from_phi(&plus), theta_from_phi(&minus));
            let work: f64 = (0..LINKS).map(|i| s.torques[i] * (tp[i] - tm[i])).sum();
            let zero = [0.0; LINKS];
            let dv = energy(&m, &FixedAnkle, &plus, &zero) - energy(&m, &FixedAnkle, &minus, &zero);
            assert!(
                (work - dv).abs() < 1e-6 * (1.0 + dv.abs()) + 1e-9,
                "direction {dir}: work {work} vs ΔV {dv}"
            );
        }
        // And the reaction enters through the true Jacobian of the swing
        // ankle (finite differences of the forward kinematics).
        let single_t = joint_torques(&inverse_dynamics(
            &m,
            &FixedAnkle,
            &phi,
            &[0.0; LINKS],
            &[0.0; LINKS],
        ));
        let mut jt_f = [0.0; LINKS];
        for (i, out) in jt_f.iter_mut().enumerate() {
            let mut a = phi;
            let mut b = phi;
            a[i] += 1e-7;
            b[i] -= 1e-7;
            let pa = gait_core::kinematics::forward_kinematics(&m, &a)[4];
            let pb = gait_core::kinematics::forward_kinematics(&m, &b)[4];
            *out = ((pa[0] - pb[0]) * fx + (pa[1] - pb[1]) * fy) / 2e-7;
        }
        let via_fd = joint_torques(&jt_f);
        for i in 0..LINKS {
            let expect = single_t[i] - via_fd[i];
            assert!(
                (s.torques[i] - expect).abs() < 1e-4,
                "joint {i}: {} vs {expect}",
                s.torques[i]
            );
        }
        // Without a load on the second foot: the single-stance statics.
        let single = double_support_statics(&m, &FixedAnkle, &phi, 0.0);
        let expect = joint_torques(&inverse_dynamics(
            &m,
            &FixedAnkle,
            &phi,
            &[0.0; LINKS],
            &[0.0; LINKS],
        ));
        assert_eq!(single.reaction_n, [0.0, 0.0]);
        for (a, b) in single.torques.iter().zip(&expect) {
            assert!((a - b).abs() < 1e-9);
        }
        // Sharing never costs more effort than standing on one leg.
        let effort = |t: &[f64; LINKS]| t.iter().map(|v| v * v).sum::<f64>();
        assert!(effort(&s.torques) <= effort(&single.torques));
    }
}

/// With the load capped below what the posture would like, the reaction is
/// still the least-effort one inside the region (push only, friction cone,
/// cap): no point of a fine grid over the region does better.
#[test]
fn shared_load_is_the_constrained_optimum() {
    use gait_core::dynamics::{ANKLE_EFFORT_WEIGHT, FOOT_FRICTION, share_load};
    use gait_core::ik::{IkSolver, IkTarget};
    let m = BodyModel::<f64>::paper_table_iii();
    let ik = IkSolver::new(&m);
    let phi = ik
        .solve(&IkTarget {
            x5: -0.275,
            y5: -0.0935,
            phi1: 0.0017,
            phi3: 0.0,
            r2: 0.5,
        })
        .unwrap()
        .phi;
    // A motion, not only statics: some accelerations.
    let ddphi = [0.5, -2.0, 3.0, 4.0, -5.0];
    let single = joint_torques(&inverse_dynamics(
        &m,
        &FixedAnkle,
        &phi,
        &[0.0; LINKS],
        &ddphi,
    ));
    // The pilot's ankle counts ANKLE_EFFORT_WEIGHT times a motor.
    let effort = |t: &[f64; LINKS]| {
        ANKLE_EFFORT_WEIGHT * t[0] * t[0] + t[1..].iter().map(|v| v * v).sum::<f64>()
    };
    let (ex, ey) = (
        share_probe(&m, &phi, 1.0, 0.0),
        share_probe(&m, &phi, 0.0, 1.0),
    );
    for cap in [0.0, 50.0, 300.0, 2000.0] {
        let s = share_load(&m, &FixedAnkle, &phi, &single, cap);
        let [fx, fy] = s.reaction_n;
        assert!(fy >= 0.0 && fy <= cap + 1e-9 && fx.abs() <= FOOT_FRICTION * fy + 1e-6);
        let best = effort(&s.torques);
        for i in 0..=40 {
            for j in 0..=40 {
                let gy = cap * f64::from(i) / 40.0;
                let gx = FOOT_FRICTION * gy * (2.0 * f64::from(j) / 40.0 - 1.0);
                let moved: [f64; LINKS] =
                    std::array::from_fn(|k| single[k] - gx * ex[k] - gy * ey[k]);
                assert!(
                    effort(&moved) >= best - 1e-6 * (1.0 + best),
                    "cap {cap}: ({gx}, {gy}) beats {:?}",
                    s.reaction_n
                );
            }
        }
    }
}

/// The joint torques a unit ground force (ux, uy) on the swing ankle takes
/// away, by finite differences of the forward kinematics (Aᵀ Jᵀ u).
fn share_probe(m: &BodyModel<f64>, phi: &[f64; LINKS], ux: f64, uy: f64) -> [f64; LINKS] {
    let mut jt = [0.0; LINKS];
    for (i, out) in jt.iter_mut().enumerate() {
        let mut a = *phi;
        let mut b = *phi;
        a[i] += 1e-7;
        b[i] -= 1e-7;
        let pa = gait_core::kinematics::forward_kinematics(m, &a)[4];
        let pb = gait_core::kinematics::forward_kinematics(m, &b)[4];
        *out = ((pa[0] - pb[0]) * ux + (pa[1] - pb[1]) * uy) / 2e-7;
    }
    joint_torques(&jt)
}
