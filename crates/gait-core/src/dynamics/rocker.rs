//! The device's contact: the stance foot's toe rocker
//! ([`super::Contact::ToeRocker`], geometry in [`crate::foot`]). Equal to
//! the pinned ankle ([`super::pinned`]) while the foot is flat.
//!
//! The torque the pilot must supply (through the crutches) is the
//! generalised force of the whole chain about the current pivot,
//! T_θ1 = −Σ T_φi: the ankle torque while flat, the toe torque on the toe.
//!
//! With the base moving as a(φ1), the centre of mass of every link gains
//! a(φ1), so (virtual work; M total mass, c the fixed-base centre of mass,
//! c = Σ_k w_k u(φ_k), u = (sin, cos)):
//! T'_j = T_j + M w_j u'(φ_j)·ä + [j = 1] M a'(φ1)·(ä + c̈ + g ŷ),
//! ä = a' φ̈1 + a'' φ̇1². Checked in `tests/integration/toe_rocker.rs` against the
//! Lagrangian of an explicitly built kinetic energy, by energy conservation
//! across heel-off, and by the impact maps' conserved momenta.

use nalgebra::{SMatrix, SVector};

use super::{DoubleSupportStatics, DynamicsError, DynamicsTerms, TPhi, pinned, rk4_with};
use crate::foot::StanceFoot;
use crate::kinematics::{Phi, Point, Posture};
use crate::model::{BodyModel, CARRIED, GRAVITY_M_S2, LINKS};
use crate::scalar::Real;

/// The fixed-base centre of mass as c = Σ_k w_k u(φ_k), u = (sin φ, cos φ):
/// w_k = (m_k d_k + l_k · mass carried by link k) / M, m.
fn com_weights<T: Real>(model: &BodyModel<T>) -> [T; LINKS] {
    let links = model.links();
    let total = model.total_mass_kg();
    let mut w = [T::zero(); LINKS];
    for ((wk, link), carried) in w.iter_mut().zip(links).zip(CARRIED.iter()) {
        let beyond = links
            .iter()
            .zip(carried)
            .fold(T::zero(), |s, (l, &c)| if c { s + l.mass_kg } else { s });
        *wk = (link.mass_kg * link.com_m + link.length_m * beyond) / total;
    }
    w
}

/// Per-link (u, u') = ((sin φ, cos φ), (cos φ, −sin φ)).
fn units<T: Real>(phi: &Phi<T>) -> [(Point<T>, Point<T>); LINKS] {
    units_at(&Posture::new(phi))
}

/// [`units`] at a posture whose sines are known.
fn units_at<T: Real>(posture: &Posture<T>) -> [(Point<T>, Point<T>); LINKS] {
    posture.sin_cos.map(|(s, c)| ([s, c], [c, -s]))
}

fn dot<T: Real>(a: Point<T>, b: Point<T>) -> T {
    a[0] * b[0] + a[1] * b[1]
}

/// Inverse dynamics on this foot: T'_Φ (see the module docs). Equal to
/// [`pinned::inverse_dynamics_at`] while the foot is flat.
pub(super) fn inverse_dynamics_at<T: Real>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    posture: &Posture<T>,
    dphi: &Phi<T>,
    ddphi: &Phi<T>,
) -> TPhi<T> {
    let phi = &posture.phi;
    let mut out = pinned::inverse_dynamics_at(model, posture, dphi, ddphi);
    if !foot.on_toe(first(phi)) {
        return out;
    }
    let a = foot.ankle(first(phi));
    let mass = model.total_mass_kg();
    let w = com_weights(model);
    let u = units_at(posture);
    let (w1, a1) = (first(dphi), first(ddphi));
    let base_acc = [
        a.d1[0] * a1 + a.d2[0] * w1 * w1,
        a.d1[1] * a1 + a.d2[1] * w1 * w1,
    ];
    let mut com_acc = [T::zero(); 2];
    for ((&(uk, dk), &wk), (&qd, &qdd)) in u.iter().zip(&w).zip(dphi.iter().zip(ddphi)) {
        com_acc[0] += wk * (dk[0] * qdd - uk[0] * qd * qd);
        com_acc[1] += wk * (dk[1] * qdd - uk[1] * qd * qd);
    }
    for ((o, &(_, dk)), &wk) in out.iter_mut().zip(&u).zip(&w) {
        *o += mass * wk * dot(base_acc, dk);
    }
    let g = T::lit(GRAVITY_M_S2);
    let [o1, ..] = &mut out;
    *o1 += mass
        * dot(
            a.d1,
            [base_acc[0] + com_acc[0], base_acc[1] + com_acc[1] + g],
        );
    out
}

/// [`inverse_dynamics_at`] at rest on this foot: the pinned statics and,
/// with the heel up, the weight acting through the moving base
/// (m g ∂a_y/∂φ1 on φ1). The same numbers as the full sum with zero rates.
pub(super) fn static_torques_at<T: Real>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    posture: &Posture<T>,
) -> TPhi<T> {
    let phi = &posture.phi;
    let mut out = pinned::static_torques_at(model, posture);
    if foot.on_toe(first(phi)) {
        let a = foot.ankle(first(phi));
        let [o1, ..] = &mut out;
        *o1 += model.total_mass_kg() * (a.d1[1] * T::lit(GRAVITY_M_S2));
    }
    out
}

/// D'(Φ), H'Φ̇ and G'(Φ) on this foot (the module docs' equation split by
/// its dependence on Φ̈).
pub(super) fn terms<T: Real>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
) -> DynamicsTerms<T> {
    let mut t = pinned::terms(model, phi, dphi);
    if !foot.on_toe(first(phi)) {
        return t;
    }
    let a = foot.ankle(first(phi));
    let mass = model.total_mass_kg();
    let w = com_weights(model);
    let u = units(phi);
    let w1 = first(dphi);
    // Column k of the coupling M w_k (a'·u'_k), and the base's centripetal
    // push M w_k (a''·u'_k) φ̇1².
    let mut coupling = SVector::<T, LINKS>::zeros();
    let mut base_push = SVector::<T, LINKS>::zeros();
    for (((c, b), &(_, dk)), &wk) in coupling
        .iter_mut()
        .zip(base_push.iter_mut())
        .zip(&u)
        .zip(&w)
    {
        *c = mass * wk * dot(a.d1, dk);
        *b = mass * wk * dot(a.d2, dk) * w1 * w1;
    }
    let mut centripetal = [T::zero(); 2];
    for ((&(uk, _), &wk), &qd) in u.iter().zip(&w).zip(dphi) {
        centripetal[0] -= wk * uk[0] * qd * qd;
        centripetal[1] -= wk * uk[1] * qd * qd;
    }
    let e1 = SVector::<T, LINKS>::from([T::one(), T::zero(), T::zero(), T::zero(), T::zero()]);
    t.d += coupling * e1.transpose()
        + e1 * coupling.transpose()
        + e1 * e1.transpose() * (mass * dot(a.d1, a.d1));
    let row1 = mass
        * dot(
            a.d1,
            [
                a.d2[0] * w1 * w1 + centripetal[0],
                a.d2[1] * w1 * w1 + centripetal[1],
            ],
        );
    t.h_dphi += base_push + e1 * row1;
    t.g += e1 * (mass * T::lit(GRAVITY_M_S2) * a.d1[1]);
    t
}

/// Forward dynamics on this foot: Φ̈ = D'⁻¹ (T_Φ − H'Φ̇ − G').
pub(super) fn forward_dynamics<T: Real>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    t_phi: &TPhi<T>,
) -> Result<Phi<T>, DynamicsError> {
    pinned::check_finite(phi, dphi, t_phi)?;
    pinned::accelerations(&terms(model, foot, phi, dphi), t_phi)
}

/// [`pinned::share_load_with_base_at`] with these feet: the second foot's
/// force also acts through the stance ankle's motion about its toe, and,
/// when the second foot stands on its own toe (its shank, seen as a stance
/// shank, leans past the stop: a descent's trailing foot), at that toe.
pub(super) fn share_load_at<T: Real>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    posture: &Posture<T>,
    single: &[T; LINKS],
    max_load_n: T,
) -> DoubleSupportStatics<T> {
    let phi = &posture.phi;
    let d1 = foot.ankle(first(phi)).d1;
    let [.., phi5] = *phi;
    let lean = crate::kinematics::wrap_pi(phi5 - T::pi());
    // Toe − ankle = toe − a(lean): its φ5-derivative is −a'(lean).
    let a = foot.ankle(lean).d1;
    pinned::share_load_with_base_at(model, posture, single, max_load_n, d1, [-a[0], -a[1]])
}

/// [`pinned::second_foot_torques_at`] with these feet (see
/// [`share_load_at`]).
pub(super) fn second_foot_torques_at<T: Real>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    posture: &Posture<T>,
) -> ([T; LINKS], [T; LINKS]) {
    let phi = &posture.phi;
    let d1 = foot.ankle(first(phi)).d1;
    let [.., phi5] = *phi;
    let lean = crate::kinematics::wrap_pi(phi5 - T::pi());
    let a = foot.ankle(lean).d1;
    pinned::second_foot_torques_at(model, posture, d1, [-a[0], -a[1]])
}

/// Kinetic plus gravitational energy on this foot (heights from the flat
/// foot's ankle), J.
pub(super) fn energy<T: Real>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
) -> T {
    let t = terms(model, foot, phi, dphi);
    let w = SVector::<T, LINKS>::from(*dphi);
    let kinetic = w.dot(&(t.d * w)) * T::lit(0.5);
    let potential = phi
        .iter()
        .zip(model.g())
        .fold(T::zero(), |acc, (&x, &gi)| acc + gi * x.sin_cos_fast().1);
    let lift = model.total_mass_kg() * T::lit(GRAVITY_M_S2) * foot.ankle(first(phi)).position_m[1];
    kinetic + potential + lift
}

/// Linear momentum of the chain, kg·m/s.
fn linear_momentum<T: Real>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
) -> Point<T> {
    let a = foot.ankle(first(phi));
    let w = com_weights(model);
    let mut v = [a.d1[0] * first(dphi), a.d1[1] * first(dphi)];
    for ((&(_, dk), &wk), &qd) in units(phi).iter().zip(&w).zip(dphi) {
        v[0] += wk * dk[0] * qd;
        v[1] += wk * dk[1] * qd;
    }
    let m = model.total_mass_kg();
    [m * v[0], m * v[1]]
}

/// The instant the heel lifts or lands: the velocities after the switch.
///
/// Heel-off (the ankle meets its stop; the ground pushes only at the toe)
/// conserves the angular momentum about the toe; heel strike (the heel
/// lands; the ankle is free again) conserves it about the ankle. Both keep
/// every sub-chain's angular momentum about the knee and hip joints (no
/// impulsive joint torque), i.e. the momenta p_φj for j ≥ 2. With
/// L_toe = L_ankle + (a − toe) × P and −Σ_j p_φj = L about the pivot, the
/// switch changes only p_φ1: p'_φ1 = p_φ1 ∓ (a − toe) × P. The velocities then
/// solve D' Φ̇⁺ = p'. `to_toe` picks the direction; Φ is the switching
/// posture (on either side of heel-off: the masses use the new contact).
pub fn contact_switch_velocities<T: Real>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    to_toe: bool,
) -> Result<Phi<T>, DynamicsError> {
    // The posture just before and just after (the switch is at heel_off;
    // the moving ankle's Jacobian differs on the two sides).
    // Past the stop by a few units of the scalar's precision (1e-9 is lost
    // in f32 rounding at 0.35 rad).
    let nudge = T::default_epsilon() * T::lit(4.0) * (T::one() + foot.heel_off_rad.abs());
    let (before, after) = {
        let [q1, q2, q3, q4, q5] = *phi;
        let on = [q1.max(foot.heel_off_rad + nudge), q2, q3, q4, q5];
        let flat = [q1.min(foot.heel_off_rad), q2, q3, q4, q5];
        if to_toe { (flat, on) } else { (on, flat) }
    };
    let pre = terms(model, foot, &before, dphi);
    let mut p = pre.d * SVector::<T, LINKS>::from(*dphi);
    let momentum = linear_momentum(model, foot, &before, dphi);
    let ankle = foot.ankle(first(phi)).position_m;
    let toe = foot.toe();
    let r = [ankle[0] - toe[0], ankle[1] - toe[1]];
    let cross = r[0] * momentum[1] - r[1] * momentum[0];
    if let Some(p1) = p.get_mut(0) {
        *p1 += if to_toe { -cross } else { cross };
    }
    let post = terms(model, foot, &after, dphi);
    let chol = post.d.cholesky().ok_or(DynamicsError::SingularMassMatrix)?;
    let v: SMatrix<T, LINKS, 1> = chol.solve(&p);
    if v.iter().all(|x| x.finite()) {
        Ok(v.into())
    } else {
        Err(DynamicsError::NonFinite)
    }
}

/// Like [`pinned::rk4_step`] on this foot (constant generalised
/// forces over `h`); a step that crosses heel-off applies
/// [`contact_switch_velocities`] at its end.
pub(super) fn rk4_step<T: Real>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    t_phi: &TPhi<T>,
    h: T,
) -> Result<(Phi<T>, Phi<T>), DynamicsError> {
    let (q, mut w) = rk4_with(phi, dphi, h, |q, w| {
        forward_dynamics(model, foot, q, w, t_phi)
    })?;
    let (was, is) = (foot.on_toe(first(phi)), foot.on_toe(first(&q)));
    if was != is {
        w = contact_switch_velocities(model, foot, &q, &w, is)?;
    }
    Ok((q, w))
}

/// φ1 of an angle array.
fn first<T: Real>(a: &Phi<T>) -> T {
    let [x, ..] = *a;
    x
}
