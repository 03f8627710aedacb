//! The toe rocker (`Contact::ToeRocker`, `gait_core::foot`) checked against derivations that
//! share no code with it: the ankle's circle written as an angle about the
//! toe, centre-of-mass Jacobians built on that base (`chain.rs`), the
//! Lagrangian of that kinetic energy by numerical differentiation, angular
//! momenta summed link by link, and energy conservation of the free chain
//! on its toe.

use gait_core::dynamics::{self, Contact::FixedAnkle, Contact::ToeRocker};
use gait_core::foot::StanceFoot;
use gait_core::kinematics::forward_kinematics;
use gait_core::model::GRAVITY_M_S2;
use gait_core::{BodyModel, LINKS};
use proptest::prelude::*;

use crate::chain::{com_and_jacobian, lagrange_torques, mass_matrix, potential};

fn model() -> (BodyModel<f64>, StanceFoot<f64>) {
    let m = BodyModel::<f64>::paper_table_iii();
    let f = StanceFoot::for_model(&m);
    (m, f)
}

/// The ankle on its circle about the toe, written as radius and angle
/// (clockwise from vertical): ρ(sin(α0 + ψ), cos(α0 + ψ)) from the toe,
/// and its derivative. `on_toe` forces the branch (ψ may be negative).
fn ankle(f: &StanceFoot<f64>, phi1: f64, on_toe: bool) -> ([f64; 2], [f64; 2]) {
    if !on_toe {
        return ([0.0; 2], [0.0; 2]);
    }
    let rho = f.toe_m.hypot(f.ankle_height_m);
    let alpha0 = (-f.toe_m).atan2(f.ankle_height_m);
    let a = alpha0 + phi1 - f.heel_off_rad;
    (
        [f.toe_m + rho * a.sin(), -f.ankle_height_m + rho * a.cos()],
        [rho * a.cos(), -rho * a.sin()],
    )
}

/// The stance ankle on the toe rocker (`on_toe`) or flat, as the chain's
/// base (see [`ankle`]).
fn rocker(f: &StanceFoot<f64>, on_toe: bool) -> impl Fn(f64) -> ([f64; 2], [f64; 2]) + '_ {
    move |phi1| ankle(f, phi1, on_toe)
}

/// Angular momentum (anticlockwise) of the links in `set` about `point`.
fn angular_momentum(
    m: &BodyModel<f64>,
    f: &StanceFoot<f64>,
    phi: &[f64; LINKS],
    dphi: &[f64; LINKS],
    on_toe: bool,
    set: &[usize],
    point: [f64; 2],
) -> f64 {
    let mut l = 0.0;
    for &k in set {
        let link = m.links()[k];
        let (c, j) = com_and_jacobian(m, &rocker(f, on_toe), phi, k);
        let v = [
            (0..LINKS).map(|i| j[0][i] * dphi[i]).sum::<f64>(),
            (0..LINKS).map(|i| j[1][i] * dphi[i]).sum::<f64>(),
        ];
        let r = [c[0] - point[0], c[1] - point[1]];
        l += link.mass_kg * (r[0] * v[1] - r[1] * v[0]) - link.inertia_kgm2 * dphi[k];
    }
    l
}

/// The joints' sub-chain momenta: links 2–5 about the stance knee, 3–5 and
/// 4–5 about the hip, 5 about the swing knee (the joints' points on this
/// branch).
fn joint_momenta(
    m: &BodyModel<f64>,
    f: &StanceFoot<f64>,
    phi: &[f64; LINKS],
    dphi: &[f64; LINKS],
    on_toe: bool,
) -> [f64; 4] {
    let (a, _) = ankle(f, phi[0], on_toe);
    let p = forward_kinematics(m, phi).map(|p| [p[0] + a[0], p[1] + a[1]]);
    [
        angular_momentum(m, f, phi, dphi, on_toe, &[1, 2, 3, 4], p[0]),
        angular_momentum(m, f, phi, dphi, on_toe, &[2, 3, 4], p[1]),
        angular_momentum(m, f, phi, dphi, on_toe, &[3, 4], p[1]),
        angular_momentum(m, f, phi, dphi, on_toe, &[4], p[3]),
    ]
}

fn kinetic(d: &[[f64; LINKS]; LINKS], w: &[f64; LINKS]) -> f64 {
    let mut k = 0.0;
    for i in 0..LINKS {
        for j in 0..LINKS {
            k += 0.5 * w[i] * d[i][j] * w[j];
        }
    }
    k
}

/// Postures with the stance shank on the toe (φ1 past the 20° stop).
fn toe_state() -> impl Strategy<Value = ([f64; LINKS], [f64; LINKS], [f64; LINKS])> {
    let ang = (
        0.36f64..0.9,
        -1.0f64..1.0,
        -0.6f64..0.6,
        2.0f64..4.2,
        2.0f64..4.2,
    )
        .prop_map(|(a, b, c, d, e)| [a, b, c, d, e]);
    let vel = prop::array::uniform5(-3.0f64..3.0);
    let acc = prop::array::uniform5(-20.0f64..20.0);
    (ang, vel, acc)
}

#[test]
fn ankle_rolls_on_a_circle_about_the_toe_and_starts_where_it_stood() {
    let (_, f) = model();
    let rho = f.toe_m.hypot(f.ankle_height_m);
    for i in 0..=40 {
        let phi1 = f.heel_off_rad - 0.2 + 0.02 * f64::from(i);
        let a = f.ankle(phi1);
        let (expect, dexpect) = ankle(&f, phi1, phi1 > f.heel_off_rad);
        for c in 0..2 {
            assert!((a.position_m[c] - expect[c]).abs() < 1e-12, "{phi1}");
            assert!((a.d1[c] - dexpect[c]).abs() < 1e-12, "{phi1}");
        }
        if f.on_toe(phi1) {
            let toe = f.toe();
            let r = (a.position_m[0] - toe[0]).hypot(a.position_m[1] - toe[1]);
            assert!((r - rho).abs() < 1e-12);
            // The second derivative by differencing the first.
            let h = 1e-6;
            let (p, q) = (f.ankle(phi1 + h), f.ankle(phi1 - h));
            for c in 0..2 {
                assert!(((p.d1[c] - q.d1[c]) / (2.0 * h) - a.d2[c]).abs() < 1e-6);
            }
            // Heel up: the ankle rises as the shank leans on.
            assert!(a.position_m[1] > 0.0);
            assert!(f.dorsiflexion(phi1) == f.heel_off_rad);
        } else {
            assert_eq!(a.position_m, [0.0; 2]);
            assert_eq!(f.dorsiflexion(phi1), phi1);
        }
    }
    // Continuous at heel-off.
    let a = f.ankle(f.heel_off_rad + 1e-9);
    assert!(a.position_m[0].abs() < 1e-9 && a.position_m[1].abs() < 1e-9);
}

#[test]
fn flat_foot_is_the_papers_model_exactly() {
    let (m, f) = model();
    let phi = [0.2, -0.1, 0.05, 2.9, 3.3];
    let w = [0.4, -0.9, 0.2, -2.1, 3.3];
    let a = [1.5, -2.0, 0.7, 6.0, -9.0];
    assert_eq!(
        dynamics::inverse_dynamics(&m, &ToeRocker(f), &phi, &w, &a),
        dynamics::inverse_dynamics(&m, &FixedAnkle, &phi, &w, &a)
    );
    assert_eq!(
        dynamics::energy(&m, &ToeRocker(f), &phi, &w),
        dynamics::energy(&m, &FixedAnkle, &phi, &w)
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn mass_matrix_on_the_toe_matches_kinetic_energy((q, _w, _a) in toe_state()) {
        let (m, f) = model();
        let d = dynamics::terms(&m, &ToeRocker(f), &q, &[0.0; LINKS]).d;
        let e = mass_matrix(&m, &rocker(&f, true), &q);
        for i in 0..LINKS {
            for j in 0..LINKS {
                prop_assert!((d[(i, j)] - e[i][j]).abs() < 1e-10, "D[{i}][{j}] {} vs {}", d[(i, j)], e[i][j]);
            }
        }
    }

    #[test]
    fn inverse_dynamics_on_the_toe_matches_lagrangian((q, w, a) in toe_state()) {
        let (m, f) = model();
        let t = dynamics::inverse_dynamics(&m, &ToeRocker(f), &q, &w, &a);
        let l = lagrange_torques(&m, &rocker(&f, true), &q, &w, &a);
        for i in 0..LINKS {
            prop_assert!((t[i] - l[i]).abs() < 1e-4 * (1.0 + l[i].abs()), "{i}: {} vs {}", t[i], l[i]);
        }
        // The matrix form agrees with the fast form.
        let tm = dynamics::terms(&m, &ToeRocker(f), &q, &w);
        let full = tm.d * nalgebra::SVector::<f64, LINKS>::from(a) + tm.h_dphi + tm.g;
        for i in 0..LINKS {
            prop_assert!((full[i] - t[i]).abs() < 1e-9 * (1.0 + t[i].abs()));
        }
        // And forward dynamics inverts it.
        let back = dynamics::forward_dynamics(&m, &ToeRocker(f), &q, &w, &t).unwrap();
        for i in 0..LINKS {
            prop_assert!((back[i] - a[i]).abs() < 1e-8 * (1.0 + a[i].abs()));
        }
    }

    /// The pivot torque −ΣT_φ is the rate of angular momentum about the toe
    /// plus gravity's moment about it (Newton–Euler, not Lagrange).
    #[test]
    fn pivot_torque_is_momentum_rate_about_the_toe((q, w, a) in toe_state()) {
        let (m, f) = model();
        let t = dynamics::inverse_dynamics(&m, &ToeRocker(f), &q, &w, &a);
        let pivot_torque = -t.iter().sum::<f64>();
        let toe = f.toe();
        let all = [0, 1, 2, 3, 4];
        // dL/dt by a central difference along the motion.
        let h = 1e-6;
        let q_at = |s: f64| -> [f64; LINKS] { core::array::from_fn(|i| q[i] + s * w[i] + 0.5 * s * s * a[i]) };
        let w_at = |s: f64| -> [f64; LINKS] { core::array::from_fn(|i| w[i] + s * a[i]) };
        let dl = (angular_momentum(&m, &f, &q_at(h), &w_at(h), true, &all, toe)
            - angular_momentum(&m, &f, &q_at(-h), &w_at(-h), true, &all, toe)) / (2.0 * h);
        // Gravity's moment about the toe (anticlockwise): Σ (c − toe) × (−m g ŷ).
        let mut gravity = 0.0;
        for k in 0..LINKS {
            let (c, _) = com_and_jacobian(&m, &rocker(&f, true), &q, k);
            gravity += -(c[0] - toe[0]) * m.links()[k].mass_kg * GRAVITY_M_S2;
        }
        // Applied torque + gravity moment = dL/dt.
        prop_assert!((pivot_torque + gravity - dl).abs() < 1e-3 * (1.0 + dl.abs()),
            "{pivot_torque} + {gravity} vs {dl}");
    }

    #[test]
    fn heel_off_and_heel_strike_conserve_the_right_momenta(
        q in (-1.0f64..1.0, -0.6f64..0.6, 2.0f64..4.2, 2.0f64..4.2),
        w in prop::array::uniform5(-3.0f64..3.0),
    ) {
        let (m, f) = model();
        let s = f.heel_off_rad;
        let phi = [s, q.0, q.1, q.2, q.3];
        let toe = f.toe();
        let all = [0, 1, 2, 3, 4];
        // Heel-off: about the toe.
        let up = dynamics::contact_switch_velocities(&m, &f, &phi, &w, true).unwrap();
        let before = angular_momentum(&m, &f, &phi, &w, false, &all, toe);
        let after = angular_momentum(&m, &f, &phi, &up, true, &all, toe);
        prop_assert!((before - after).abs() < 1e-6 * (1.0 + before.abs()), "{before} vs {after}");
        let jb = joint_momenta(&m, &f, &phi, &w, false);
        let ja = joint_momenta(&m, &f, &phi, &up, true);
        for i in 0..4 {
            prop_assert!((jb[i] - ja[i]).abs() < 1e-6 * (1.0 + jb[i].abs()), "joint {i}: {} vs {}", jb[i], ja[i]);
        }
        // A plastic contact switch never adds energy.
        let kb = kinetic(&mass_matrix(&m, &rocker(&f, false), &phi), &w);
        let ka = kinetic(&mass_matrix(&m, &rocker(&f, true), &phi), &up);
        prop_assert!(ka <= kb * (1.0 + 1e-9) + 1e-12, "{kb} -> {ka}");
        // Heel strike: about the ankle.
        let down = dynamics::contact_switch_velocities(&m, &f, &phi, &w, false).unwrap();
        let before = angular_momentum(&m, &f, &phi, &w, true, &all, [0.0; 2]);
        let after = angular_momentum(&m, &f, &phi, &down, false, &all, [0.0; 2]);
        prop_assert!((before - after).abs() < 1e-6 * (1.0 + before.abs()), "{before} vs {after}");
        let jb = joint_momenta(&m, &f, &phi, &w, true);
        let ja = joint_momenta(&m, &f, &phi, &down, false);
        for i in 0..4 {
            prop_assert!((jb[i] - ja[i]).abs() < 1e-6 * (1.0 + jb[i].abs()));
        }
        let kb = kinetic(&mass_matrix(&m, &rocker(&f, true), &phi), &w);
        let ka = kinetic(&mass_matrix(&m, &rocker(&f, false), &phi), &down);
        prop_assert!(ka <= kb * (1.0 + 1e-9) + 1e-12);
    }
}

/// The free chain on its toe conserves energy; across heel-off and heel
/// strike it loses some (the switches are plastic) and never gains.
#[test]
fn free_chain_on_the_toe_conserves_energy() {
    let (m, f) = model();
    // Leaning past the stop, falling forward: stays on the toe.
    let mut q = [0.5, 0.1, -0.1, 3.0, 3.4];
    let mut w = [0.5, -0.3, 0.2, 1.0, -0.5];
    let e0 = dynamics::energy(&m, &ToeRocker(f), &q, &w);
    for _ in 0..2000 {
        assert!(f.on_toe(q[0]));
        (q, w) = dynamics::rk4_step(&m, &ToeRocker(f), &q, &w, &[0.0; LINKS], 1e-4).unwrap();
        if q[0] > 1.2 {
            break;
        }
    }
    let e1 = dynamics::energy(&m, &ToeRocker(f), &q, &w);
    assert!((e1 - e0).abs() < 1e-6 * e0.abs().max(1.0), "{e0} -> {e1}");
    // Energy also matches the explicit kinetic + potential energy.
    let explicit =
        kinetic(&mass_matrix(&m, &rocker(&f, true), &q), &w) + potential(&m, &rocker(&f, true), &q);
    assert!((explicit - e1).abs() < 1e-8 * e1.abs().max(1.0));

    // Falling backwards from the toe onto the heel: energy drops at the
    // strike, never rises.
    let mut q = [0.4, 0.0, 0.1, 3.1, 3.2];
    let mut w = [-1.5, 0.0, 0.0, 0.0, 0.0];
    let mut e = dynamics::energy(&m, &ToeRocker(f), &q, &w);
    let mut struck = false;
    for _ in 0..2000 {
        let was = f.on_toe(q[0]);
        (q, w) = dynamics::rk4_step(&m, &ToeRocker(f), &q, &w, &[0.0; LINKS], 1e-4).unwrap();
        let now = dynamics::energy(&m, &ToeRocker(f), &q, &w);
        if was != f.on_toe(q[0]) {
            struck = true;
            assert!(now < e, "heel strike added energy: {e} -> {now}");
        } else {
            assert!((now - e).abs() < 1e-6 * e.abs().max(1.0), "{e} -> {now}");
        }
        e = now;
        if struck {
            break;
        }
    }
    assert!(struck, "never reached the heel");
}

/// The load sharing with the toe rocker uses the right contact Jacobian:
/// the returned torques are `single − Aᵀ Jᵀ F` with J the derivative of the
/// second foot's toe (stance ankle rolled, swing foot on its toe), here by
/// finite differences of the point built independently.
#[test]
fn load_sharing_acts_at_the_rolled_feet() {
    use gait_core::kinematics::joint_torques;
    let (m, f) = model();
    // Stance on its toe (0.6 rad), trailing/second foot on its toe too
    // (its shank, seen as a stance shank, leans 0.5 rad).
    let phi = [0.6, -0.3, 0.05, 2.6, core::f64::consts::PI + 0.5];
    let toe_of_second = |q: &[f64; LINKS]| -> [f64; 2] {
        let (a, _) = ankle(&f, q[0], true);
        let p5 = forward_kinematics(&m, q)[4];
        let lean = q[4] - core::f64::consts::PI;
        let (b, _) = ankle(&f, lean, true);
        [
            a[0] + p5[0] + f.toe_m - b[0],
            a[1] + p5[1] - f.ankle_height_m - b[1],
        ]
    };
    // What holding the posture on the stance foot alone asks.
    let zero = [0.0; LINKS];
    let single = joint_torques(&dynamics::inverse_dynamics(
        &m,
        &ToeRocker(f),
        &phi,
        &zero,
        &zero,
    ));
    let s = dynamics::share_load(&m, &ToeRocker(f), &phi, &single, 900.0);
    assert!(s.reaction_n[1] > 1.0, "no load shared: {:?}", s.reaction_n);
    let h = 1e-7;
    let mut generalised = [0.0; LINKS];
    for i in 0..LINKS {
        let (mut qp, mut qm) = (phi, phi);
        qp[i] += h;
        qm[i] -= h;
        let (p, q) = (toe_of_second(&qp), toe_of_second(&qm));
        generalised[i] = (p[0] - q[0]) / (2.0 * h) * s.reaction_n[0]
            + (p[1] - q[1]) / (2.0 * h) * s.reaction_n[1];
    }
    let expect = joint_torques(&generalised);
    for i in 0..LINKS {
        let want = single[i] - expect[i];
        assert!(
            (s.torques[i] - want).abs() < 1e-5 * (1.0 + want.abs()),
            "{i}: {} vs {want}",
            s.torques[i]
        );
    }
}

/// The contact switch works in f32 too (the nudge past the stop is not lost
/// in rounding) and agrees with f64.
#[test]
fn contact_switch_in_f32_agrees_with_f64() {
    let (m, f) = model();
    let m32: BodyModel<f32> = m.cast();
    let f32foot = StanceFoot::<f32>::table_i();
    let phi = [f.heel_off_rad, -0.1, 0.05, 3.0, 3.3];
    let w = [0.8, -0.5, 0.2, 1.0, -1.0];
    let v64 = dynamics::contact_switch_velocities(&m, &f, &phi, &w, true).unwrap();
    let v32 = dynamics::contact_switch_velocities(
        &m32,
        &f32foot,
        &phi.map(|x| x as f32),
        &w.map(|x| x as f32),
        true,
    )
    .unwrap();
    // The heel-off map changes the velocities (it is not the identity).
    assert!((0..LINKS).any(|i| (v64[i] - w[i]).abs() > 1e-3));
    for i in 0..LINKS {
        assert!(
            (f64::from(v32[i]) - v64[i]).abs() < 1e-3,
            "{i}: {} vs {}",
            v32[i],
            v64[i]
        );
    }
}
