//! The paper's contact: the stance ankle pinned to the ground, the foot
//! flat ([`super::Contact::FixedAnkle`]). Lagrangian dynamics of the 5-link
//! chain in absolute angles (paper section III-A, eq. (solution)–(sol2),
//! with the corrected `p_ij`).
//!
//! T_Φ = D(Φ) Φ̈ + H(Φ, Φ̇) Φ̇ + G(Φ), with
//! D_ij = p_ij cos(φ_i − φ_j), H_ij = p_ij sin(φ_i − φ_j) φ̇_j, G_i = −g_i sin φ_i.
//!
//! Only five sine/cosine pairs are evaluated per call; the pairwise
//! differences use cos(a−b) = cos a cos b + sin a sin b and
//! sin(a−b) = sin a cos b − cos a sin b.

use nalgebra::{SMatrix, SVector};

use super::{
    ANKLE_EFFORT_WEIGHT, DoubleSupportStatics, DynamicsError, DynamicsTerms, FOOT_FRICTION, TPhi,
    rk4_with,
};
use crate::kinematics::{Phi, Posture, joint_torques};
use crate::model::{BodyModel, LINKS};
use crate::scalar::Real;

/// Evaluates D(Φ), H(Φ, Φ̇)Φ̇ and G(Φ) (eq. (sol1)).
pub(super) fn terms<T: Real>(
    model: &BodyModel<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
) -> DynamicsTerms<T> {
    let sc = phi.map(|x| x.sin_cos_fast());
    let p = model.p();
    let gc = model.g();
    let mut d = SMatrix::<T, LINKS, LINKS>::zeros();
    let mut h = SVector::<T, LINKS>::zeros();
    let mut g = SVector::<T, LINKS>::zeros();
    // D is symmetric, so filling its column-major storage row by row is the
    // same as filling it column by column.
    let mut d_cells = d.iter_mut();
    for ((((&(si, ci), prow), hi), gi), &g_coef) in
        sc.iter().zip(p).zip(h.iter_mut()).zip(g.iter_mut()).zip(gc)
    {
        let mut acc = T::zero();
        for ((&(sj, cj), &pij), &wj) in sc.iter().zip(prow).zip(dphi) {
            let cos_ij = ci * cj + si * sj;
            let sin_ij = si * cj - ci * sj;
            if let Some(cell) = d_cells.next() {
                *cell = pij * cos_ij;
            }
            acc += pij * sin_ij * wj * wj;
        }
        *hi = acc;
        *gi = -g_coef * si;
    }
    DynamicsTerms { d, h_dphi: h, g }
}

/// Eq. (solution): inverse dynamics T_Φ = D Φ̈ + H Φ̇ + G.
///
/// This is the control loop's feed-forward, so it skips the matrices:
/// T_i = Σ_j p_ij [cos(φ_i − φ_j) φ̈_j + sin(φ_i − φ_j) φ̇_j²] − g_i sin φ_i,
/// from five sine/cosine pairs (fixed-size loops the compiler unrolls).
/// Cross-checked against [`terms`] and against an independent Lagrangian
/// derivation in the tests.
pub(super) fn inverse_dynamics_at<T: Real>(
    model: &BodyModel<T>,
    posture: &Posture<T>,
    dphi: &Phi<T>,
    ddphi: &Phi<T>,
) -> TPhi<T> {
    let sc = &posture.sin_cos;
    let w2 = dphi.map(|w| w * w);
    // cos(φi − φj) and sin(φi − φj) once per pair: the products commute
    // exactly in floating point, so cos_ji = cos_ij and sin_ji = −sin_ij
    // bit for bit, and the sums below are the ones of the full 5 × 5 loop.
    let mut cos = [[T::zero(); LINKS]; LINKS];
    let mut sin = [[T::zero(); LINKS]; LINKS];
    let put = |m: &mut [[T; LINKS]; LINKS], a: usize, b: usize, v: T| {
        if let Some(cell) = m.get_mut(a).and_then(|row| row.get_mut(b)) {
            *cell = v;
        }
    };
    for (i, &(si, ci)) in sc.iter().enumerate() {
        for (j, &(sj, cj)) in sc.iter().enumerate().skip(i) {
            let c = ci * cj + si * sj;
            let s = si * cj - ci * sj;
            put(&mut cos, i, j, c);
            put(&mut cos, j, i, c);
            put(&mut sin, j, i, -s);
            put(&mut sin, i, j, s);
        }
    }
    let mut out = [T::zero(); LINKS];
    let rows = out.iter_mut().zip(sc).zip(model.p()).zip(model.g());
    for ((((o, &(si, _)), prow), &gi), (cos_i, sin_i)) in rows.zip(cos.iter().zip(&sin)) {
        let mut acc = -gi * si;
        for ((((&pij, &aj), &wj2), &cos_ij), &sin_ij) in
            prow.iter().zip(ddphi).zip(&w2).zip(cos_i).zip(sin_i)
        {
            acc += pij * (cos_ij * aj + sin_ij * wj2);
        }
        *o = acc;
    }
    out
}

/// [`inverse_dynamics_at`] at rest (Φ̇ = Φ̈ = 0): the gravity terms
/// alone, T_φi = −g_i sin φi. The same numbers as the full sum with zero
/// rates (its other terms are all zero), a tenth of the work.
pub(super) fn static_torques_at<T: Real>(model: &BodyModel<T>, posture: &Posture<T>) -> TPhi<T> {
    let mut out = [T::zero(); LINKS];
    for ((o, &(si, _)), &gi) in out.iter_mut().zip(&posture.sin_cos).zip(model.g()) {
        *o = -gi * si;
    }
    out
}

/// The joint torques T_Θ that a unit ground force on the second foot takes
/// away, for a force along x and along y: Aᵀ Jᵀ e_x and Aᵀ Jᵀ e_y, with J
/// the Jacobian of the second foot's contact point (its ankle, moved by the
/// stance ankle's `base_d1` = ∂ankle/∂φ1 and by `swing_d5` = ∂contact/∂φ5
/// beyond the ankle; both zero for pinned ankles). A force F there changes
/// the joint torques a motion needs by −(Fx·mx + Fy·my).
pub(super) fn second_foot_torques_at<T: Real>(
    model: &BodyModel<T>,
    posture: &Posture<T>,
    base_d1: [T; 2],
    swing_d5: [T; 2],
) -> ([T; LINKS], [T; LINKS]) {
    let l = model.lengths();
    // Jᵀ e_x and Jᵀ e_y: ∂p5/∂φ_i = l_i (cos φ_i, −sin φ_i) for the links
    // between the stance ankle and the swing ankle (not the torso).
    let mut jx = [T::zero(); LINKS];
    let mut jy = [T::zero(); LINKS];
    for (i, ((x, y), (&li, &(s, c)))) in jx
        .iter_mut()
        .zip(jy.iter_mut())
        .zip(l.iter().zip(&posture.sin_cos))
        .enumerate()
    {
        if i != 2 {
            *x = li * c;
            *y = -li * s;
        }
        if i == 0 {
            *x += base_d1[0];
            *y += base_d1[1];
        }
        if i == LINKS - 1 {
            *x += swing_d5[0];
            *y += swing_d5[1];
        }
    }
    (joint_torques(&jx), joint_torques(&jy))
}

/// The load sharing of [`super::share_load`]: the force F on the second foot
/// that minimises the weighted effort (see there), with the stance ankle
/// moving with φ1 at `base_d1` = ∂(ankle)/∂φ1 and the second foot's contact
/// point moving with φ5 beyond its ankle at `swing_d5` (both zero for
/// pinned ankles; the toe rocker's in [`super::rocker::share_load_at`]).
pub(super) fn share_load_with_base_at<T: Real>(
    model: &BodyModel<T>,
    posture: &Posture<T>,
    single: &[T; LINKS],
    max_load_n: T,
    base_d1: [T; 2],
    swing_d5: [T; 2],
) -> DoubleSupportStatics<T> {
    let (mx, my) = second_foot_torques_at(model, posture, base_d1, swing_d5);
    let w = T::lit(ANKLE_EFFORT_WEIGHT);
    let dot = |a: &[T; LINKS], b: &[T; LINKS]| {
        a.iter()
            .zip(b)
            .enumerate()
            .fold(T::zero(), |s, (i, (&u, &v))| {
                s + if i == 0 { w * u * v } else { u * v }
            })
    };
    // Effort E(F) = |c − Fx mx − Fy my|²_W: a convex quadratic.
    let (a11, a12, a22) = (dot(&mx, &mx), dot(&mx, &my), dot(&my, &my));
    let (b1, b2) = (dot(single, &mx), dot(single, &my));
    let max = if max_load_n.finite() {
        max_load_n.max(T::zero())
    } else {
        T::zero()
    };
    let mu = T::lit(FOOT_FRICTION);
    let effort = |fx: T, fy: T| {
        a11 * fx * fx + T::lit(2.0) * a12 * fx * fy + a22 * fy * fy
            - T::lit(2.0) * (b1 * fx + b2 * fy)
    };
    let feasible = |fx: T, fy: T| {
        fx.finite()
            && fy.finite()
            && fy >= T::zero()
            && fy <= max
            && fx.abs() <= mu * fy + T::lit(1e-9) * (T::one() + fy)
    };
    // Candidates: the interior minimum; the minimum along each edge of the
    // region (fy = max with fx free; the two cone edges fx = ±μ fy), each
    // clamped to its segment; and the corner at the origin.
    let mut best = (T::zero(), T::zero());
    let mut best_e = effort(T::zero(), T::zero());
    let mut consider = |fx: T, fy: T| {
        if feasible(fx, fy) {
            let e = effort(fx, fy);
            if e < best_e {
                best_e = e;
                best = (fx, fy);
            }
        }
    };
    let det = a11 * a22 - a12 * a12;
    if det.abs() > T::lit(1e-12) * (a11 * a22).max(T::lit(1e-12)) {
        consider((b1 * a22 - b2 * a12) / det, (a11 * b2 - a12 * b1) / det);
    }
    if a11 > T::zero() {
        let fx = ((b1 - a12 * max) / a11).max(-mu * max).min(mu * max);
        consider(fx, max);
    }
    for sign in [T::one(), -T::one()] {
        // fx = sign μ fy: E is a parabola in fy.
        let k = sign * mu;
        let curv = a11 * k * k + T::lit(2.0) * a12 * k + a22;
        if curv > T::zero() {
            let fy = ((b1 * k + b2) / curv).max(T::zero()).min(max);
            consider(k * fy, fy);
        }
    }
    let (fx, fy) = best;
    let mut torques = *single;
    for ((t, &x), &y) in torques.iter_mut().zip(&mx).zip(&my) {
        *t = *t - fx * x - fy * y;
    }
    DoubleSupportStatics {
        reaction_n: [fx, fy],
        torques,
        per_newton: (mx, my),
    }
}

/// Forward dynamics Φ̈ = D⁻¹ (T_Φ − H Φ̇ − G), by Cholesky (D is symmetric
/// positive definite for any valid model).
pub(super) fn forward_dynamics<T: Real>(
    model: &BodyModel<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    t_phi: &TPhi<T>,
) -> Result<Phi<T>, DynamicsError> {
    check_finite(phi, dphi, t_phi)?;
    accelerations(&terms(model, phi, dphi), t_phi)
}

/// NaN or infinite inputs are an error, not a NaN result.
pub(super) fn check_finite<T: Real>(
    phi: &Phi<T>,
    dphi: &Phi<T>,
    t_phi: &TPhi<T>,
) -> Result<(), DynamicsError> {
    if phi
        .iter()
        .chain(dphi.iter())
        .chain(t_phi.iter())
        .all(|x| x.finite())
    {
        Ok(())
    } else {
        Err(DynamicsError::NonFinite)
    }
}

/// Φ̈ = D⁻¹ (T_Φ − HΦ̇ − G) from evaluated terms, by Cholesky (shared with
/// the toe rocker's [`super::rocker::forward_dynamics`]).
pub(super) fn accelerations<T: Real>(
    t: &DynamicsTerms<T>,
    t_phi: &TPhi<T>,
) -> Result<Phi<T>, DynamicsError> {
    let rhs = SVector::<T, LINKS>::from(*t_phi) - t.h_dphi - t.g;
    let chol = t.d.cholesky().ok_or(DynamicsError::SingularMassMatrix)?;
    let acc = chol.solve(&rhs);
    if acc.iter().all(|x| x.finite()) {
        Ok(acc.into())
    } else {
        Err(DynamicsError::NonFinite)
    }
}

/// Total mechanical energy K + P (P = Σ g_i cos φ_i, zero at the ankle's
/// height), J. Used to check that the free dynamics conserve it.
pub(super) fn energy<T: Real>(model: &BodyModel<T>, phi: &Phi<T>, dphi: &Phi<T>) -> T {
    let t = terms(model, phi, dphi);
    let w = SVector::<T, LINKS>::from(*dphi);
    let k = w.dot(&(t.d * w)) * T::lit(0.5);
    let p = phi
        .iter()
        .zip(model.g())
        .fold(T::zero(), |acc, (&x, &gi)| acc + gi * x.sin_cos_fast().1);
    k + p
}

/// One classical Runge–Kutta (RK4) step of the chain (flat stance foot)
/// under constant generalised forces `t_phi` over `h` seconds.
pub(super) fn rk4_step<T: Real>(
    model: &BodyModel<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    t_phi: &TPhi<T>,
    h: T,
) -> Result<(Phi<T>, Phi<T>), DynamicsError> {
    rk4_with(phi, dphi, h, |q, w| forward_dynamics(model, q, w, t_phi))
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// The pairs taken once give the plain 5 × 5 sum bit for bit (the
        /// firmware's commands must not move with it).
        #[test]
        fn pairs_taken_once_equal_the_full_sum_bit_for_bit(
            phi in proptest::array::uniform5(-4.0f32..4.0),
            w in proptest::array::uniform5(-12.0f32..12.0),
            a in proptest::array::uniform5(-80.0f32..80.0),
        ) {
            let m = BodyModel::<f64>::paper_table_iii().cast::<f32>();
            let posture = Posture::new(&phi);
            let mut plain = [0.0f32; LINKS];
            for i in 0..LINKS {
                let (si, ci) = posture.sin_cos[i];
                let mut acc = -m.g()[i] * si;
                for j in 0..LINKS {
                    let (sj, cj) = posture.sin_cos[j];
                    let cos_ij = ci * cj + si * sj;
                    let sin_ij = si * cj - ci * sj;
                    acc += m.p()[i][j] * (cos_ij * a[j] + sin_ij * (w[j] * w[j]));
                }
                plain[i] = acc;
            }
            let fast = inverse_dynamics_at(&m, &posture, &w, &a);
            proptest::prop_assert_eq!(plain.map(f32::to_bits), fast.map(f32::to_bits));
        }
    }

    #[test]
    fn fast_path_equals_matrix_form() {
        let m = BodyModel::<f64>::paper_table_iii();
        let phi = [0.21, -0.18, 0.07, 2.71, 3.52];
        let w = [0.4, -0.9, 0.2, -2.1, 3.3];
        let a = [1.5, -2.0, 0.7, 6.0, -9.0];
        let t = terms(&m, &phi, &w);
        let full = t.d * SVector::<f64, LINKS>::from(a) + t.h_dphi + t.g;
        let fast = inverse_dynamics_at(&m, &Posture::new(&phi), &w, &a);
        for i in 0..LINKS {
            assert!(
                (full[i] - fast[i]).abs() < 1e-10,
                "{i}: {} vs {}",
                full[i],
                fast[i]
            );
        }
    }
}
