//! The five-link chain derived here, sharing no code with the model's
//! dynamics: the tree, each link's centre of mass and its Jacobian, the
//! mass matrix from the kinetic energy, the potential, and the equation of
//! motion from the Lagrangian by numerical differentiation. The stance
//! ankle is the chain's base: fixed (the paper's flat foot) or rolling with
//! φ1 (the toe rocker), so both models are checked by the same derivation.

use gait_core::model::GRAVITY_M_S2;
use gait_core::{BodyModel, LINKS};

/// The stance ankle for a stance shank at φ1: its position and its
/// derivative by φ1.
pub type Base<'a> = &'a dyn Fn(f64) -> ([f64; 2], [f64; 2]);

/// A stance ankle that stays at the origin (the paper's flat foot).
pub fn fixed(_phi1: f64) -> ([f64; 2], [f64; 2]) {
    ([0.0; 2], [0.0; 2])
}

/// The tree, written independently of the model's tables: the link whose
/// distal end each link hangs from (None: the stance ankle).
const PARENT: [Option<usize>; LINKS] = [None, Some(0), Some(1), Some(1), Some(3)];

/// COM of link k and its Jacobian ∂c_k/∂φ (2×5), built from the tree on
/// `base`.
pub fn com_and_jacobian(
    m: &BodyModel<f64>,
    base: Base<'_>,
    phi: &[f64; LINKS],
    k: usize,
) -> ([f64; 2], [[f64; LINKS]; 2]) {
    let links = m.links();
    let (a, da) = base(phi[0]);
    let mut c = a;
    let mut j = [[0.0; LINKS]; 2];
    j[0][0] += da[0];
    j[1][0] += da[1];
    let mut cur = PARENT[k];
    while let Some(p) = cur {
        let l = links[p].length_m;
        c[0] += l * phi[p].sin();
        c[1] += l * phi[p].cos();
        j[0][p] += l * phi[p].cos();
        j[1][p] -= l * phi[p].sin();
        cur = PARENT[p];
    }
    let d = links[k].com_m;
    c[0] += d * phi[k].sin();
    c[1] += d * phi[k].cos();
    j[0][k] += d * phi[k].cos();
    j[1][k] -= d * phi[k].sin();
    (c, j)
}

/// D from K = ½ Σ m_k |J_k φ̇|² + ½ Σ I_k φ̇_k².
pub fn mass_matrix(
    m: &BodyModel<f64>,
    base: Base<'_>,
    phi: &[f64; LINKS],
) -> [[f64; LINKS]; LINKS] {
    let mut d = [[0.0; LINKS]; LINKS];
    for (k, link) in m.links().iter().enumerate() {
        let (_, jac) = com_and_jacobian(m, base, phi, k);
        for a in 0..LINKS {
            for b in 0..LINKS {
                d[a][b] += link.mass_kg * (jac[0][a] * jac[0][b] + jac[1][a] * jac[1][b]);
            }
        }
        d[k][k] += link.inertia_kgm2;
    }
    d
}

/// P = Σ m_k g y_k.
pub fn potential(m: &BodyModel<f64>, base: Base<'_>, phi: &[f64; LINKS]) -> f64 {
    (0..LINKS)
        .map(|k| m.links()[k].mass_kg * GRAVITY_M_S2 * com_and_jacobian(m, base, phi, k).0[1])
        .sum()
}

/// T = D q̈ + C(q, q̇) + ∂P/∂q, with Christoffel terms and ∂P/∂q by central
/// differences of the energy-derived D and P.
pub fn lagrange_torques(
    m: &BodyModel<f64>,
    base: Base<'_>,
    q: &[f64; LINKS],
    w: &[f64; LINKS],
    a: &[f64; LINKS],
) -> [f64; LINKS] {
    let h = 1e-6;
    let d = mass_matrix(m, base, q);
    let mut dd = [[[0.0; LINKS]; LINKS]; LINKS]; // dd[k][i][j] = ∂D_ij/∂q_k
    let mut dp = [0.0; LINKS];
    for k in 0..LINKS {
        let (mut qp, mut qm) = (*q, *q);
        qp[k] += h;
        qm[k] -= h;
        let (dpk, dmk) = (mass_matrix(m, base, &qp), mass_matrix(m, base, &qm));
        for i in 0..LINKS {
            for j in 0..LINKS {
                dd[k][i][j] = (dpk[i][j] - dmk[i][j]) / (2.0 * h);
            }
        }
        dp[k] = (potential(m, base, &qp) - potential(m, base, &qm)) / (2.0 * h);
    }
    let mut t = [0.0; LINKS];
    for i in 0..LINKS {
        let mut s = dp[i];
        for j in 0..LINKS {
            s += d[i][j] * a[j];
            for k in 0..LINKS {
                s += (dd[k][i][j] - 0.5 * dd[i][j][k]) * w[j] * w[k];
            }
        }
        t[i] = s;
    }
    t
}
