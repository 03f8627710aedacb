//! Angle systems and forward kinematics (paper section III-A, eq. (lin_trans)).
//!
//! Frame: stance ankle at the origin, x forward, y up. Absolute angles `φ_i`
//! are measured clockwise from vertical-up; relative angles `θ_i` are between
//! link *i* and link *i−1* (ground for *i* = 1), anticlockwise positive.
//! Links 1–3 form a chain ankle → knee → hip → torso top; links 4 and 5 hang
//! from the hip `p2` (not from the torso's end `p3`).

use crate::model::{BodyModel, LINK_PATH, LINKS};
use crate::scalar::Real;

/// A point in the sagittal plane, m.
pub type Point<T> = [T; 2];

/// Absolute link angles Φ, rad.
pub type Phi<T> = [T; LINKS];

/// Relative joint angles Θ, rad.
pub type Theta<T> = [T; LINKS];

/// The constant part `b` of Φ = AΘ + b.
pub fn b_vector<T: Real>() -> [T; LINKS] {
    let h = T::frac_pi_2();
    let t = T::lit(1.5 * core::f64::consts::PI);
    [h, h, h, t, t]
}

/// Eq. (lin_trans): the matrix A of Φ = AΘ + b (−1 on and below the diagonal).
pub fn a_matrix<T: Real>() -> [[T; LINKS]; LINKS] {
    let mut a = [[T::zero(); LINKS]; LINKS];
    for (i, row) in a.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            if j <= i {
                *x = -T::one();
            }
        }
    }
    a
}

/// Eq. (lin_trans): Φ = AΘ + b (φ_i = b_i − Σ_{j≤i} θ_j).
pub fn phi_from_theta<T: Real>(theta: &Theta<T>) -> Phi<T> {
    let b = b_vector::<T>();
    let mut acc = T::zero();
    let mut phi = [T::zero(); LINKS];
    for ((p, &t), &bi) in phi.iter_mut().zip(theta).zip(&b) {
        acc += t;
        *p = bi - acc;
    }
    phi
}

/// The inverse of eq. (lin_trans): Θ = A⁻¹(Φ − b).
///
/// A⁻¹ is −1 on the diagonal and +1 just below it, so
/// θ_1 = b_1 − φ_1 and θ_i = (b_i − φ_i) − (b_{i−1} − φ_{i−1}).
pub fn theta_from_phi<T: Real>(phi: &Phi<T>) -> Theta<T> {
    let b = b_vector::<T>();
    let mut prev = T::zero();
    let mut theta = [T::zero(); LINKS];
    for ((t, &p), &bi) in theta.iter_mut().zip(phi).zip(&b) {
        let s = bi - p;
        *t = s - prev;
        prev = s;
    }
    theta
}

/// Eq. (hehe): joint torques from the generalised forces of the absolute
/// angles, T_Θ = Aᵀ T_Φ, i.e. T_θj = −Σ_{i≥j} T_φi.
///
/// So the stance-ankle torque T_θ1 is minus the sum of all five.
pub fn joint_torques<T: Real>(t_phi: &[T; LINKS]) -> [T; LINKS] {
    let mut out = [T::zero(); LINKS];
    let mut acc = T::zero();
    for (o, &t) in out.iter_mut().zip(t_phi).rev() {
        acc += t;
        *o = -acc;
    }
    out
}

/// The unit vector of a link at absolute angle φ: (sin φ, cos φ).
#[inline]
fn dir<T: Real>(phi: T) -> Point<T> {
    let (s, c) = phi.sin_cos_fast();
    [s, c]
}

/// Φ with the sine and cosine of each of its angles, worked out once: the
/// control tick's feed-forward dynamics, its load sharing and the swing
/// foot's position all need them, and each pair costs some 46 instructions
/// on the M4 (`*_at` functions take a posture, the others Φ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Posture<T: Real> {
    /// Φ, rad.
    pub phi: Phi<T>,
    /// (sin φ_i, cos φ_i) of each link.
    pub sin_cos: [(T, T); LINKS],
}

impl<T: Real> Posture<T> {
    /// The posture Φ.
    pub fn new(phi: &Phi<T>) -> Self {
        Self {
            phi: *phi,
            sin_cos: phi.map(|x| x.sin_cos_fast()),
        }
    }

    /// Each link's unit vector (sin φ, cos φ).
    pub fn units(&self) -> [Point<T>; LINKS] {
        self.sin_cos.map(|(s, c)| [s, c])
    }
}

/// Forward kinematics: the joint points p1…p5 (stance knee, hip, torso top,
/// swing knee, swing ankle) with the stance ankle p0 at the origin:
/// p_i = p_{i−1} + l_i (sin φ_i, cos φ_i), except that link 4 starts at p2.
pub fn forward_kinematics<T: Real>(model: &BodyModel<T>, phi: &Phi<T>) -> [Point<T>; LINKS] {
    forward_kinematics_units(model, phi.map(dir))
}

/// [`forward_kinematics`] at a posture whose sines are known.
pub fn forward_kinematics_at<T: Real>(model: &BodyModel<T>, p: &Posture<T>) -> [Point<T>; LINKS] {
    forward_kinematics_units(model, p.units())
}

fn forward_kinematics_units<T: Real>(
    model: &BodyModel<T>,
    units: [Point<T>; LINKS],
) -> [Point<T>; LINKS] {
    let [l1, l2, l3, l4, l5] = model.lengths();
    let [u1, u2, u3, u4, u5] = units;
    let p1 = [l1 * u1[0], l1 * u1[1]];
    let p2 = [p1[0] + l2 * u2[0], p1[1] + l2 * u2[1]];
    let p3 = [p2[0] + l3 * u3[0], p2[1] + l3 * u3[1]];
    let p4 = [p2[0] + l4 * u4[0], p2[1] + l4 * u4[1]];
    let p5 = [p4[0] + l5 * u5[0], p4[1] + l5 * u5[1]];
    [p1, p2, p3, p4, p5]
}

/// The centre of mass of each link: its proximal joint plus `d_i` along it.
pub fn link_com<T: Real>(model: &BodyModel<T>, phi: &Phi<T>) -> [Point<T>; LINKS] {
    let [p1, p2, _, p4, _] = forward_kinematics(model, phi);
    let origin = [T::zero(); 2];
    let proximal = [origin, p1, p2, p2, p4];
    let mut out = [origin; LINKS];
    for (((o, base), link), &angle) in out.iter_mut().zip(proximal).zip(model.links()).zip(phi) {
        let u = dir(angle);
        *o = [base[0] + link.com_m * u[0], base[1] + link.com_m * u[1]];
    }
    out
}

/// The acceleration of each link's centre of mass relative to the stance
/// ankle, m/s² (x, y): the link's own term (d_i) plus each link on its path
/// ([`LINK_PATH`], l_j), each c (cos φ φ̈ − sin φ φ̇², −sin φ φ̈ − cos φ φ̇²).
pub fn link_com_accelerations<T: Real>(
    model: &BodyModel<T>,
    phi: &Phi<T>,
    dphi: &Phi<T>,
    ddphi: &Phi<T>,
) -> [Point<T>; LINKS] {
    let links = model.links();
    let acc = |j: usize, c: T| -> Point<T> {
        let (Some(&q), Some(&w), Some(&a)) = (phi.get(j), dphi.get(j), ddphi.get(j)) else {
            return [T::zero(); 2];
        };
        let (s, co) = q.sin_cos_fast();
        let w2 = w * w;
        [c * (co * a - s * w2), c * (-s * a - co * w2)]
    };
    let mut out = [[T::zero(); 2]; LINKS];
    for (i, ((o, link), path)) in out.iter_mut().zip(links.iter()).zip(LINK_PATH).enumerate() {
        *o = acc(i, link.com_m);
        for &j in path {
            let l = links.get(j).map_or(T::zero(), |l| l.length_m);
            let a = acc(j, l);
            o[0] += a[0];
            o[1] += a[1];
        }
    }
    out
}

/// Anatomical joint angles (rad), positive in the direction named:
/// `[stance ankle dorsiflexion, stance knee flexion, stance hip flexion,
///   swing hip flexion, swing knee flexion]`.
///
/// From Θ: ankle dorsiflexion = φ1 = π/2 − θ1 (shank tilted forward, foot flat);
/// stance knee flexion = θ2; stance hip flexion = −θ3 (the stance thigh rises
/// from the knee, so flexion turns it anticlockwise relative to the torso);
/// swing hip flexion = θ4; swing knee flexion = −θ5.
pub fn anatomical_angles<T: Real>(theta: &Theta<T>) -> [T; LINKS] {
    let [t1, t2, t3, t4, t5] = *theta;
    [T::frac_pi_2() - t1, t2, -t3, t4, -t5]
}

/// The same double-support posture described from the other foot: the swing
/// leg becomes the stance leg and vice versa (links 1↔5 and 2↔4 swap roles
/// and directions, the torso keeps its angle). Used to chain steps: a step's
/// landing posture, swapped, is where the next step starts. An involution up
/// to 2π: `swap_legs(swap_legs(Φ)) ≡ Φ`.
///
/// Why: link i of the chain points away from the stance ankle, so the old
/// swing shank (knee → ankle, φ5) seen as the new stance shank (ankle → knee)
/// is φ5 − π, and the old stance thigh (knee → hip, φ2) seen as the new
/// swing thigh (hip → knee) is φ2 + π.
pub fn swap_legs<T: Real>(phi: &Phi<T>) -> Phi<T> {
    let pi = T::pi();
    let [p1, p2, p3, p4, p5] = *phi;
    [
        wrap_pi(p5 - pi),
        wrap_pi(p4 - pi),
        p3,
        pi + wrap_pi(p2),
        pi + wrap_pi(p1),
    ]
}

/// Wraps an angle to (−π, π].
///
/// The remainder by 2π is taken by one subtraction for |x| < 4π (every
/// joint angle): exact there (Sterbenz), so bit for bit what `%` gives,
/// signed zero included; `%` itself only beyond. On `f32`, `%` is libm's
/// `fmodf`, a bit-by-bit loop in software on the M4.
pub fn wrap_pi<T: Real>(x: T) -> T {
    let two_pi = T::two_pi();
    let ax = x.abs();
    let mut y = if ax < two_pi {
        x
    } else if ax < two_pi + two_pi {
        let r = ax - two_pi;
        if x > T::zero() { r } else { -r }
    } else {
        x % two_pi
    };
    if y > T::pi() {
        y -= two_pi;
    } else if y <= -T::pi() {
        y += two_pi;
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The remainder written with `%` throughout.
    fn wrap_pi_by_rem<T: Real>(x: T) -> T {
        let mut y = x % T::two_pi();
        if y > T::pi() {
            y -= T::two_pi();
        } else if y <= -T::pi() {
            y += T::two_pi();
        }
        y
    }

    #[test]
    fn wrap_pi_is_the_remainder_bit_for_bit() {
        let tau32 = core::f32::consts::TAU;
        let special = [
            0.0,
            -0.0,
            tau32,
            -tau32,
            2.0 * tau32,
            -2.0 * tau32,
            1e4,
            -7e3,
        ];
        let odd = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
        let sweep = (-40_000..=40_000).flat_map(|k| {
            let k = k as f32;
            [
                k * 4.5e-4,
                tau32 + k * f32::EPSILON,
                -tau32 - k * f32::EPSILON,
            ]
        });
        for x in special.into_iter().chain(odd).chain(sweep) {
            let (a, b) = (wrap_pi(x), wrap_pi_by_rem(x));
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{x}: {a} {b}"
            );
            let (a, b) = (wrap_pi(f64::from(x)), wrap_pi_by_rem(f64::from(x)));
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{x}: {a} {b}"
            );
        }
    }

    #[test]
    fn com_accelerations_are_the_second_differences_of_the_com_positions() {
        let m = BodyModel::<f64>::paper_table_iii();
        let (q, w, a) = (
            [0.21, -0.18, 0.07, 2.71, 3.52],
            [0.4, -0.9, 0.2, -2.1, 3.3],
            [1.5, -2.0, 0.7, 6.0, -9.0],
        );
        // Φ(t) = q + w t + a t²/2, so the second difference of each link's
        // centre of mass at t = 0 is its acceleration.
        let at =
            |t: f64| -> Phi<f64> { core::array::from_fn(|i| q[i] + w[i] * t + 0.5 * a[i] * t * t) };
        let h = 1e-4;
        let (before, now, after) = (
            link_com(&m, &at(-h)),
            link_com(&m, &at(0.0)),
            link_com(&m, &at(h)),
        );
        let acc = link_com_accelerations(&m, &q, &w, &a);
        for i in 0..LINKS {
            for k in 0..2 {
                let fd = (after[i][k] - 2.0 * now[i][k] + before[i][k]) / (h * h);
                assert!(
                    (fd - acc[i][k]).abs() < 1e-4 * (1.0 + fd.abs()),
                    "link {i}, axis {k}: {fd} vs {}",
                    acc[i][k]
                );
            }
        }
    }

    #[test]
    fn theta_phi_round_trip_and_matrix_form() {
        let theta = [1.2, 0.3, -0.4, 0.5, -0.6];
        let phi = phi_from_theta(&theta);
        let a = a_matrix::<f64>();
        let b = b_vector::<f64>();
        for i in 0..LINKS {
            let mut s = b[i];
            for j in 0..LINKS {
                s += a[i][j] * theta[j];
            }
            assert!((s - phi[i]).abs() < 1e-15);
        }
        let back = theta_from_phi(&phi);
        for i in 0..LINKS {
            assert!((back[i] - theta[i]).abs() < 1e-15);
        }
    }

    #[test]
    fn standing_posture() {
        let m = BodyModel::<f64>::paper_table_iii();
        let pi = core::f64::consts::PI;
        let phi = [0.0, 0.0, 0.0, pi, pi];
        let p = forward_kinematics(&m, &phi);
        assert!((p[1][1] - (0.441 + 0.395)).abs() < 1e-12);
        assert!(p[4][1].abs() < 1e-12 && p[4][0].abs() < 1e-12);
        let theta = theta_from_phi(&phi);
        let anat = anatomical_angles(&theta);
        for a in anat {
            assert!(a.abs() < 1e-12, "{anat:?}");
        }
    }

    #[test]
    fn anatomical_signs() {
        let pi = core::f64::consts::PI;
        // Swing hip flexed 30°: the swing thigh points down and forward.
        let phi = [0.0, 0.0, 0.0, pi - 0.5236, pi - 0.5236];
        let a = anatomical_angles(&theta_from_phi(&phi));
        assert!((a[3] - 0.5236).abs() < 1e-12);
        // Swing knee flexed: the shank points down and back.
        let phi = [0.0, 0.0, 0.0, pi, pi + 0.7];
        let a = anatomical_angles(&theta_from_phi(&phi));
        assert!((a[4] - 0.7).abs() < 1e-12);
        // Stance knee flexed: shank forward, thigh back.
        let phi = [0.2, -0.2, 0.0, pi, pi];
        let a = anatomical_angles(&theta_from_phi(&phi));
        assert!((a[0] - 0.2).abs() < 1e-12);
        assert!((a[1] - 0.4).abs() < 1e-12);
        // Stance hip flexed: torso upright, thigh rising backward from the knee.
        assert!((a[2] - 0.2).abs() < 1e-12);
    }

    proptest::proptest! {
        /// Seen from the other foot, the chain has the same joints: knees,
        /// hip and torso top move with the foot that is now the origin.
        #[test]
        fn swap_legs_describes_the_same_posture(
            p1 in -0.6f64..0.6, p2 in -0.8f64..0.8, p3 in -0.3f64..0.3,
            p4 in 2.3f64..4.0, p5 in 2.5f64..4.2,
        ) {
            let m = BodyModel::<f64>::paper_table_iii();
            let phi = [p1, p2, p3, p4, p5];
            let old = forward_kinematics(&m, &phi);
            let swapped = swap_legs(&phi);
            let new = forward_kinematics(&m, &swapped);
            let foot = old[4];
            let rel = |q: [f64; 2]| [q[0] - foot[0], q[1] - foot[1]];
            let expect = [rel(old[3]), rel(old[1]), rel(old[2]), rel(old[0]), rel([0.0, 0.0])];
            for (a, b) in new.iter().zip(&expect) {
                proptest::prop_assert!((a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12);
            }
            let back = swap_legs(&swapped);
            for (a, b) in back.iter().zip(&phi) {
                proptest::prop_assert!(wrap_pi(a - b).abs() < 1e-12);
            }
        }
    }
}
