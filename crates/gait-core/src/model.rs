//! The body model as data: the five links' geometry and mass properties,
//! the joint limits, and the dynamics coefficients that follow from them.
//!
//! A [`BodyModel`] is validated once when it is built and is immutable after
//! that, so every algorithm can trust it without re-checking.

use crate::scalar::Real;

/// Number of links in the sagittal chain.
pub const LINKS: usize = 5;

/// The chain's layout: for each link, the links on the path from the stance
/// ankle to its proximal joint (the torso and the swing thigh both hang
/// from the hip, the end of link 2; the swing shank from the swing knee).
pub const LINK_PATH: [&[usize]; LINKS] = [&[], &[0], &[0, 1], &[0, 1], &[0, 1, 3]];

/// Standard gravity, m/s².
pub const GRAVITY_M_S2: f64 = 9.81;

/// One rigid link of the chain.
///
/// `com_m` is the distance from the link's proximal joint (joint *i*, the
/// end nearer the stance ankle along the chain) to its centre of mass.
/// `inertia_kgm2` is the moment of inertia about the centre of mass, as the
/// paper's `p_ii = I_i + m_i d_i² + …` implies.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Link<T> {
    /// Joint-to-joint length `l_i`, m.
    pub length_m: T,
    /// Proximal joint to centre of mass `d_i`, m.
    pub com_m: T,
    /// Mass `m_i`, kg.
    pub mass_kg: T,
    /// Moment of inertia about the centre of mass `I_i`, kg·m².
    pub inertia_kgm2: T,
}

/// Range of motion of the actuated and semi-passive joints in anatomical
/// terms (radians, both bounds as positive magnitudes), from Table I.
///
/// The mapping from the model's relative angles Θ to these anatomical angles
/// is in [`crate::kinematics::anatomical_angles`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct JointLimits<T> {
    /// Maximum hip flexion, rad.
    pub hip_flexion_rad: T,
    /// Maximum hip extension, rad.
    pub hip_extension_rad: T,
    /// Maximum knee flexion, rad.
    pub knee_flexion_rad: T,
    /// Maximum knee hyper-extension, rad (0: the knee locks straight).
    pub knee_extension_rad: T,
    /// Maximum ankle dorsiflexion, rad.
    pub ankle_dorsiflexion_rad: T,
    /// Maximum ankle plantarflexion, rad.
    pub ankle_plantarflexion_rad: T,
}

/// How far the stance shank may lean back over the heel (heel rocker), deg.
pub const HEEL_ROCKER_PLANTARFLEXION_DEG: f64 = 12.0;

impl<T: Real> JointLimits<T> {
    /// Table I of the paper: hip 100° flexion / 80° extension, knee 100° / 0°,
    /// ankle 20° dorsiflexion / 0° plantarflexion.
    pub fn paper_table_i() -> Self {
        let deg = |d: f64| T::lit(d.to_radians());
        Self {
            hip_flexion_rad: deg(100.0),
            hip_extension_rad: deg(80.0),
            knee_flexion_rad: deg(100.0),
            knee_extension_rad: deg(0.0),
            ankle_dorsiflexion_rad: deg(20.0),
            ankle_plantarflexion_rad: deg(0.0),
        }
    }

    /// Table I with the stance ankle allowed [`HEEL_ROCKER_PLANTARFLEXION_DEG`]
    /// of "plantarflexion": the shank leaning back over the heel.
    ///
    /// Table I gives the ankle 0° of plantarflexion, yet the paper's own
    /// walking profile starts the stance shank at −0.093 rad (−5.3°): with
    /// the foot flat that is plantarflexion, and a real foot reaches it by
    /// rolling on its heel, which the 5-link model does not describe. The
    /// device's supervisor and the simulator's ankle stop both use these
    /// limits, so that the start posture of the walk table is inside the
    /// envelope on the board as it is in simulation.
    pub fn paper_with_heel_rocker() -> Self {
        Self {
            ankle_plantarflexion_rad: T::lit(HEEL_ROCKER_PLANTARFLEXION_DEG.to_radians()),
            ..Self::paper_table_i()
        }
    }

    fn check(&self) -> Result<(), ModelError> {
        let all = [
            self.hip_flexion_rad,
            self.hip_extension_rad,
            self.knee_flexion_rad,
            self.knee_extension_rad,
            self.ankle_dorsiflexion_rad,
            self.ankle_plantarflexion_rad,
        ];
        for v in all {
            if !v.finite() || v < T::zero() || v > T::lit(core::f64::consts::PI) {
                return Err(ModelError::InvalidJointLimit);
            }
        }
        Ok(())
    }
}

/// Why a set of body parameters was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModelError {
    /// A parameter of the given link (0-based) is NaN or infinite.
    NonFinite {
        /// Link index, 0-based.
        link: usize,
    },
    /// Link length is not positive.
    NonPositiveLength {
        /// Link index, 0-based.
        link: usize,
    },
    /// Link mass is not positive.
    NonPositiveMass {
        /// Link index, 0-based.
        link: usize,
    },
    /// Link inertia is not positive.
    NonPositiveInertia {
        /// Link index, 0-based.
        link: usize,
    },
    /// The centre of mass lies outside the link (needs 0 ≤ d ≤ l).
    ComOutsideLink {
        /// Link index, 0-based.
        link: usize,
    },
    /// The two legs' lengths differ: the paper's IK and the gait cases
    /// assume mirrored legs (l1 = l5, l2 = l4).
    AsymmetricLegs,
    /// A joint limit is negative, above π or not finite.
    InvalidJointLimit,
}

impl core::fmt::Display for ModelError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NonFinite { link } => write!(f, "link {}: a parameter is not finite", link + 1),
            Self::NonPositiveLength { link } => write!(f, "link {}: length must be > 0", link + 1),
            Self::NonPositiveMass { link } => write!(f, "link {}: mass must be > 0", link + 1),
            Self::NonPositiveInertia { link } => {
                write!(f, "link {}: inertia must be > 0", link + 1)
            }
            Self::ComOutsideLink { link } => {
                write!(
                    f,
                    "link {}: centre of mass must satisfy 0 <= d <= l",
                    link + 1
                )
            }
            Self::AsymmetricLegs => write!(f, "legs differ: need l1 = l5 and l2 = l4"),
            Self::InvalidJointLimit => write!(f, "joint limits must be finite and in [0, pi]"),
        }
    }
}

/// Whether link `i` ends at a joint that carries the next links of the chain
/// (`a_i` of eq. (sol2)): 0 for the torso, whose free end carries nothing
/// (links 4 and 5 hang from the hip, the end of link 2).
const CARRIES: [bool; LINKS] = [true, true, false, true, true];

/// For each link, the links further out along the chain that hang from its
/// distal end (the index set of the paper's mass sums).
///
/// Link 1 carries 2..5, link 2 carries 3, 4, 5, the torso carries nothing,
/// link 4 carries 5.
pub(crate) const CARRIED: [[bool; LINKS]; LINKS] = [
    [false, true, true, true, true],
    [false, false, true, true, true],
    [false, false, false, false, false],
    [false, false, false, false, true],
    [false, false, false, false, false],
];

/// The validated five-link body model with its precomputed dynamics
/// coefficients `p_ij` and `g_i`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyModel<T> {
    links: [Link<T>; LINKS],
    limits: JointLimits<T>,
    /// `p_ij` of eq. (sol1), symmetric.
    p: [[T; LINKS]; LINKS],
    /// `g_i` of eq. (sol1).
    g: [T; LINKS],
}

impl<T: Real> BodyModel<T> {
    /// Builds and validates a model.
    ///
    /// Checks finite, positive lengths, masses and inertias, `0 ≤ d ≤ l`,
    /// mirrored legs, and sane joint limits; then precomputes `p_ij`, `g_i`.
    pub fn new(links: [Link<T>; LINKS], limits: JointLimits<T>) -> Result<Self, ModelError> {
        for (i, l) in links.iter().enumerate() {
            let vals = [l.length_m, l.com_m, l.mass_kg, l.inertia_kgm2];
            if vals.iter().any(|v| !v.finite()) {
                return Err(ModelError::NonFinite { link: i });
            }
            if l.length_m <= T::zero() {
                return Err(ModelError::NonPositiveLength { link: i });
            }
            if l.mass_kg <= T::zero() {
                return Err(ModelError::NonPositiveMass { link: i });
            }
            if l.inertia_kgm2 <= T::zero() {
                return Err(ModelError::NonPositiveInertia { link: i });
            }
            if l.com_m < T::zero() || l.com_m > l.length_m {
                return Err(ModelError::ComOutsideLink { link: i });
            }
        }
        let [l1, l2, _, l4, l5] = links;
        let tol = T::lit(1e-6);
        if (l1.length_m - l5.length_m).abs() > tol || (l2.length_m - l4.length_m).abs() > tol {
            return Err(ModelError::AsymmetricLegs);
        }
        limits.check()?;
        let (p, g) = coefficients(&links);
        Ok(Self {
            links,
            limits,
            p,
            g,
        })
    }

    /// Table III of the paper (exoskeleton plus pilot, 93.5 kg) with the
    /// joint limits of Table I.
    pub fn paper_table_iii() -> Self {
        let mk = |l: f64, d: f64, m: f64, i: f64| Link {
            length_m: T::lit(l),
            com_m: T::lit(d),
            mass_kg: T::lit(m),
            inertia_kgm2: T::lit(i),
        };
        let links = [
            mk(0.441, 0.269, 7.05, 0.226),
            mk(0.395, 0.228, 10.5, 0.626),
            mk(0.714, 0.342, 57.7, 9.44),
            mk(0.395, 0.167, 11.5, 0.626),
            mk(0.441, 0.172, 6.05, 0.226),
        ];
        let (p, g) = coefficients(&links);
        // Table III satisfies every check of `new`; building it directly keeps
        // this constructor infallible (a unit test asserts `new` accepts it).
        Self {
            links,
            limits: JointLimits::paper_table_i(),
            p,
            g,
        }
    }

    /// The five links, stance shank first.
    pub fn links(&self) -> &[Link<T>; LINKS] {
        &self.links
    }

    /// Joint limits.
    pub fn limits(&self) -> &JointLimits<T> {
        &self.limits
    }

    /// Link lengths `l_1..l_5`, m.
    pub fn lengths(&self) -> [T; LINKS] {
        self.links.map(|l| l.length_m)
    }

    /// Total mass, kg.
    pub fn total_mass_kg(&self) -> T {
        self.links.iter().fold(T::zero(), |acc, l| acc + l.mass_kg)
    }

    /// `p_ij` of eq. (sol1) (with the mass sum over the links beyond *j*).
    pub fn p(&self) -> &[[T; LINKS]; LINKS] {
        &self.p
    }

    /// `g_i` of eq. (sol1).
    pub fn g(&self) -> &[T; LINKS] {
        &self.g
    }

    /// The same model in another precision.
    pub fn cast<U: Real>(&self) -> BodyModel<U> {
        let c = |x: T| U::lit(x.to_f64());
        let links = self.links.map(|l| Link {
            length_m: c(l.length_m),
            com_m: c(l.com_m),
            mass_kg: c(l.mass_kg),
            inertia_kgm2: c(l.inertia_kgm2),
        });
        let lim = &self.limits;
        let limits = JointLimits {
            hip_flexion_rad: c(lim.hip_flexion_rad),
            hip_extension_rad: c(lim.hip_extension_rad),
            knee_flexion_rad: c(lim.knee_flexion_rad),
            knee_extension_rad: c(lim.knee_extension_rad),
            ankle_dorsiflexion_rad: c(lim.ankle_dorsiflexion_rad),
            ankle_plantarflexion_rad: c(lim.ankle_plantarflexion_rad),
        };
        let (p, g) = coefficients(&links);
        BodyModel {
            links,
            limits,
            p,
            g,
        }
    }
}

/// Eq. (sol1)–(sol2): the coefficients of D, H and G.
///
/// The paper prints the off-diagonal mass sum as running over `k = i+1…5`;
/// that double-counts link *j* itself and the links between *i* and *j*.
/// The correct sum (derived from the kinetic energy, and checked against an
/// independent Jacobian derivation in the tests) runs over the links carried
/// by link *j*'s distal end, which for this chain is `k = j+1…5` masked by
/// [`CARRIED`] (links 4 and 5 hang from the hip, not from the torso's end).
fn coefficients<T: Real>(links: &[Link<T>; LINKS]) -> ([[T; LINKS]; LINKS], [T; LINKS]) {
    let g0 = T::lit(GRAVITY_M_S2);
    let mut p = [[T::zero(); LINKS]; LINKS];
    let mut g = [T::zero(); LINKS];
    // Mass hanging from the distal end of each link.
    let mut beyond = [T::zero(); LINKS];
    for (i, row) in CARRIED.iter().enumerate() {
        let mut s = T::zero();
        for (k, &carried) in row.iter().enumerate() {
            if carried {
                s += links.get(k).map_or(T::zero(), |l| l.mass_kg);
            }
        }
        if let Some(b) = beyond.get_mut(i) {
            *b = s;
        }
    }
    for (i, li) in links.iter().enumerate() {
        let a_i = if CARRIES.get(i).copied().unwrap_or(false) {
            T::one()
        } else {
            T::zero()
        };
        let m_beyond_i = beyond.get(i).copied().unwrap_or(T::zero());
        if let Some(gi) = g.get_mut(i) {
            *gi = (li.mass_kg * li.com_m + a_i * li.length_m * m_beyond_i) * g0;
        }
        for (j, lj) in links.iter().enumerate() {
            let v = if j == i {
                li.inertia_kgm2
                    + li.mass_kg * li.com_m * li.com_m
                    + a_i * li.length_m * li.length_m * m_beyond_i
            } else if j > i {
                // Link j hangs (directly or not) from link i's distal end?
                let hangs = CARRIED
                    .get(i)
                    .and_then(|r| r.get(j))
                    .copied()
                    .unwrap_or(false);
                if hangs {
                    let m_beyond_j = beyond.get(j).copied().unwrap_or(T::zero());
                    let a_j = if CARRIES.get(j).copied().unwrap_or(false) {
                        T::one()
                    } else {
                        T::zero()
                    };
                    li.length_m * (lj.mass_kg * lj.com_m + a_j * lj.length_m * m_beyond_j)
                } else {
                    T::zero()
                }
            } else {
                continue;
            };
            if let Some(x) = p.get_mut(i).and_then(|r| r.get_mut(j)) {
                *x = v;
            }
            if let Some(x) = p.get_mut(j).and_then(|r| r.get_mut(i)) {
                *x = v;
            }
        }
    }
    (p, g)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_iii_passes_validation() {
        let m = BodyModel::<f64>::paper_table_iii();
        assert_eq!(BodyModel::new(*m.links(), *m.limits()), Ok(m));
        assert!((m.total_mass_kg() - 92.8).abs() < 1e-9);
    }

    #[test]
    fn rejects_bad_links() {
        let good = *BodyModel::<f64>::paper_table_iii().links();
        let lim = JointLimits::paper_table_i();
        let mut l = good;
        l[2].mass_kg = 0.0;
        assert_eq!(
            BodyModel::new(l, lim),
            Err(ModelError::NonPositiveMass { link: 2 })
        );
        let mut l = good;
        l[0].com_m = 0.5;
        assert_eq!(
            BodyModel::new(l, lim),
            Err(ModelError::ComOutsideLink { link: 0 })
        );
        let mut l = good;
        l[3].length_m = f64::NAN;
        assert_eq!(
            BodyModel::new(l, lim),
            Err(ModelError::NonFinite { link: 3 })
        );
        let mut l = good;
        l[1].length_m = -0.1;
        assert_eq!(
            BodyModel::new(l, lim),
            Err(ModelError::NonPositiveLength { link: 1 })
        );
        let mut l = good;
        l[4].inertia_kgm2 = 0.0;
        assert_eq!(
            BodyModel::new(l, lim),
            Err(ModelError::NonPositiveInertia { link: 4 })
        );
        let mut l = good;
        l[4].length_m = 0.5;
        assert_eq!(BodyModel::new(l, lim), Err(ModelError::AsymmetricLegs));
        let mut bad = lim;
        bad.knee_flexion_rad = -1.0;
        assert_eq!(
            BodyModel::new(good, bad),
            Err(ModelError::InvalidJointLimit)
        );
    }

    #[test]
    fn corrected_coupling_terms_by_hand() {
        // Worked by hand from the kinetic energy for Table III.
        let m = BodyModel::<f64>::paper_table_iii();
        let p = m.p();
        // p_12 = l1 (m2 d2 + l2 (m3 + m4 + m5))
        let p12 = 0.441 * (10.5 * 0.228 + 0.395 * (57.7 + 11.5 + 6.05));
        assert!((p[0][1] - p12).abs() < 1e-12);
        // p_13 = l1 m3 d3 (torso end carries nothing)
        assert!((p[0][2] - 0.441 * 57.7 * 0.342).abs() < 1e-12);
        // p_24 = l2 (m4 d4 + l4 m5)
        assert!((p[1][3] - 0.395 * (11.5 * 0.167 + 0.395 * 6.05)).abs() < 1e-12);
        // torso is not coupled to the swing leg
        assert_eq!(p[2][3], 0.0);
        assert_eq!(p[2][4], 0.0);
        // symmetric
        for i in 0..5 {
            for j in 0..5 {
                assert_eq!(p[i][j], p[j][i]);
            }
        }
    }
}

crate::impl_fingerprint!([T: crate::fingerprint::Fingerprint] BodyModel<T> { links, limits, p, g });
