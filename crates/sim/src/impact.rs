//! The landing impact: post-impact velocities of the mirrored chain.
//!
//! A rigid, plastic foot strike (the classical biped impact map, as in
//! Westervelt, Grizzle et al., *Feedback Control of Dynamic Bipedal Robot
//! Locomotion*, ch. 3, written here in angular-momentum form): the landing
//! ankle stops dead, the old stance foot leaves the ground without an
//! impulse, and the joints transmit no impulsive torque (motor torques are
//! finite). Then five angular momenta are conserved through the impact,
//! because every impulse acting on each subsystem passes through the point
//! they are taken about (new numbering, after the swap):
//!
//! 1. the whole body about the new stance ankle (the ground impulse);
//! 2. links 2–5 about the new stance knee;
//! 3. the torso about the hip;
//! 4. the swing leg (links 4–5) about the hip;
//! 5. the swing shank about the swing knee.
//!
//! Angular momentum is linear in Φ̇, so the post-impact Φ̇ solves a 5×5
//! linear system whose columns are the momenta of unit velocities.
//!
//! The model's mass properties belong to roles, not to physical legs
//! (Table III gives the stance and swing legs different masses), so the
//! pre-impact momenta use the old roles' masses and the post-impact ones the
//! new roles'. Whether the old stance foot really lifts off (moves up) is
//! not checked; [`crate::plant::Landing`] reports its vertical speed.

use gait_core::kinematics::Phi;
use gait_core::model::{BodyModel, LINK_PATH as PATH, LINKS};

/// World position and velocity of one link's centre of mass, its angular
/// velocity (anticlockwise) and its mass properties.
#[derive(Clone, Copy, Debug)]
struct LinkMotion {
    com: [f64; 2],
    vel: [f64; 2],
    omega: f64,
    mass: f64,
    inertia: f64,
}

/// Each link's motion for a posture with the stance ankle at `origin`,
/// moving at `origin_vel` (the toe rocker's rolling ankle; zero when flat).
fn link_motion(
    model: &BodyModel<f64>,
    phi: &Phi<f64>,
    dphi: &Phi<f64>,
    origin: [f64; 2],
    origin_vel: [f64; 2],
) -> [LinkMotion; LINKS] {
    let links = model.links();
    let u = |j: usize| (phi[j].sin(), phi[j].cos());
    // d/dt (sin φ, cos φ) = φ̇ (cos φ, −sin φ).
    let du = |j: usize| (phi[j].cos() * dphi[j], -phi[j].sin() * dphi[j]);
    core::array::from_fn(|i| {
        let mut com = origin;
        let mut vel = origin_vel;
        let segments = PATH[i]
            .iter()
            .map(|&j| (j, links[j].length_m))
            .chain(core::iter::once((i, links[i].com_m)));
        for (j, c) in segments {
            let (s, co) = u(j);
            let (ds, dco) = du(j);
            com[0] += c * s;
            com[1] += c * co;
            vel[0] += c * ds;
            vel[1] += c * dco;
        }
        LinkMotion {
            com,
            vel,
            omega: -dphi[i],
            mass: links[i].mass_kg,
            inertia: links[i].inertia_kgm2,
        }
    })
}

/// Angular momentum (anticlockwise) of the links `subset` about `p`.
fn angular_momentum(links: &[LinkMotion; LINKS], subset: &[usize], p: [f64; 2]) -> f64 {
    subset
        .iter()
        .filter_map(|&i| links.get(i))
        .map(|l| {
            let r = [l.com[0] - p[0], l.com[1] - p[1]];
            l.mass * (r[0] * l.vel[1] - r[1] * l.vel[0]) + l.inertia * l.omega
        })
        .sum()
}

/// Post-impact Φ̇ of the mirrored posture `phi_new` (new stance ankle at
/// `new_origin`) from the pre-impact state (`phi_old`, `dphi_old`, old
/// stance ankle at `old_origin`, moving at `old_origin_vel` when its heel is
/// up). `None` if the system is singular (it is not for any physical
/// posture; the caller falls back).
pub fn post_impact_velocities(
    model: &BodyModel<f64>,
    phi_old: &Phi<f64>,
    dphi_old: &Phi<f64>,
    old_origin: [f64; 2],
    old_origin_vel: [f64; 2],
    phi_new: &Phi<f64>,
    new_origin: [f64; 2],
) -> Option<Phi<f64>> {
    let pts = gait_core::kinematics::forward_kinematics(model, phi_new);
    let at = |p: [f64; 2]| [new_origin[0] + p[0], new_origin[1] + p[1]];
    // (subset in new numbering, point).
    let laws: [(&[usize], [f64; 2]); LINKS] = [
        (&[0, 1, 2, 3, 4], new_origin),
        (&[1, 2, 3, 4], at(pts[0])),
        (&[2], at(pts[1])),
        (&[3, 4], at(pts[1])),
        (&[4], at(pts[3])),
    ];
    // New link k is old link OLD_OF[k].
    const OLD_OF: [usize; LINKS] = [4, 3, 2, 1, 0];
    let before = link_motion(model, phi_old, dphi_old, old_origin, old_origin_vel);
    let before_renumbered: [LinkMotion; LINKS] = core::array::from_fn(|k| before[OLD_OF[k]]);
    let rhs: [f64; LINKS] =
        core::array::from_fn(|r| angular_momentum(&before_renumbered, laws[r].0, laws[r].1));
    let mut m = [[0.0; LINKS]; LINKS];
    for c in 0..LINKS {
        let mut e = [0.0; LINKS];
        e[c] = 1.0;
        let after = link_motion(model, phi_new, &e, new_origin, [0.0; 2]);
        for (r, row) in m.iter_mut().enumerate() {
            row[c] = angular_momentum(&after, laws[r].0, laws[r].1);
        }
    }
    solve(m, rhs)
}

/// Gaussian elimination with partial pivoting; `None` when singular or
/// non-finite.
fn solve(mut a: [[f64; LINKS]; LINKS], mut b: [f64; LINKS]) -> Option<[f64; LINKS]> {
    let scale = a.iter().flatten().fold(0.0f64, |acc, x| acc.max(x.abs()));
    if !(scale.is_finite() && scale > 0.0) {
        return None;
    }
    for col in 0..LINKS {
        let pivot = (col..LINKS).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-12 * scale {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..LINKS {
            let f = a[row][col] / a[col][col];
            let pivot_row = a[col];
            for (x, p) in a[row].iter_mut().zip(pivot_row).skip(col) {
                *x -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; LINKS];
    for row in (0..LINKS).rev() {
        let s: f64 = (row + 1..LINKS).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve_small_system() {
        let mut a = [[0.0; LINKS]; LINKS];
        for (i, row) in a.iter_mut().enumerate() {
            row[i] = 2.0;
            row[(i + 1) % LINKS] = 1.0;
        }
        let x_true = [1.0, -2.0, 3.0, 0.5, -1.5];
        let b: [f64; LINKS] =
            core::array::from_fn(|r| (0..LINKS).map(|c| a[r][c] * x_true[c]).sum());
        let x = solve(a, b).unwrap_or([f64::NAN; LINKS]);
        for i in 0..LINKS {
            assert!((x[i] - x_true[i]).abs() < 1e-12);
        }
        assert!(solve([[0.0; LINKS]; LINKS], b).is_none());
    }

    #[test]
    fn a_body_at_rest_stays_at_rest_and_momentum_is_kept() {
        let m = BodyModel::<f64>::paper_table_iii();
        let pi = core::f64::consts::PI;
        let old = [0.2, 0.15, 0.05, pi - 0.35, pi - 0.2];
        let new = [old[4] - pi, old[3] - pi, old[2], old[1] + pi, old[0] + pi];
        let p5 = gait_core::kinematics::forward_kinematics(&m, &old)[4];
        let x = post_impact_velocities(&m, &old, &[0.0; LINKS], [0.0; 2], [0.0; 2], &new, p5)
            .unwrap_or([f64::NAN; LINKS]);
        assert!(x.iter().all(|v| v.abs() < 1e-12), "{x:?}");
        // Moving: the whole body's momentum about the contact is the same
        // before and after (recomputed here, not taken from the solve).
        let w = [0.6, 0.4, 0.1, -1.5, -2.0];
        let x = post_impact_velocities(&m, &old, &w, [0.0; 2], [0.0; 2], &new, p5)
            .unwrap_or([f64::NAN; LINKS]);
        let before = link_motion(&m, &old, &w, [0.0; 2], [0.0; 2]);
        let after = link_motion(&m, &new, &x, p5, [0.0; 2]);
        let all = [0, 1, 2, 3, 4];
        let h0 = angular_momentum(&before, &all, p5);
        let h1 = angular_momentum(&after, &all, p5);
        // Masses belong to roles, so the two sums differ by the role swap
        // of the legs' masses; with a symmetric model they would agree.
        let mut sym_links = *m.links();
        sym_links[0] = sym_links[4];
        sym_links[0].com_m = sym_links[0].length_m - sym_links[4].com_m;
        sym_links[1] = sym_links[3];
        sym_links[1].com_m = sym_links[1].length_m - sym_links[3].com_m;
        let sym = BodyModel::new(sym_links, *m.limits()).unwrap_or(m);
        let x = post_impact_velocities(&sym, &old, &w, [0.0; 2], [0.0; 2], &new, p5)
            .unwrap_or([f64::NAN; LINKS]);
        let before = link_motion(&sym, &old, &w, [0.0; 2], [0.0; 2]);
        let after = link_motion(&sym, &new, &x, p5, [0.0; 2]);
        let h0s = angular_momentum(&before, &all, p5);
        let h1s = angular_momentum(&after, &all, p5);
        assert!(
            (h0s - h1s).abs() < 1e-9 * h0s.abs().max(1.0),
            "{h0s} vs {h1s}"
        );
        assert!(h0.is_finite() && h1.is_finite());
        // A plastic impact does not create kinetic energy (symmetric model).
        let ke = |l: &[LinkMotion; LINKS]| -> f64 {
            l.iter()
                .map(|k| {
                    0.5 * k.mass * (k.vel[0].powi(2) + k.vel[1].powi(2))
                        + 0.5 * k.inertia * k.omega.powi(2)
                })
                .sum()
        };
        assert!(
            ke(&after) <= ke(&before) + 1e-9,
            "{} > {}",
            ke(&after),
            ke(&before)
        );
    }
}
