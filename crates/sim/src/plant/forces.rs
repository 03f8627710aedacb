//! The generalised forces on the chain at a state: motors, joint stops,
//! the passive ankle spring, the pilot on the crutches and the ground under
//! the swing foot (the stance foot's toe rocker included).

use super::*;

/// The swing foot's ground contact point ([`Plant::swing_sole`]).
pub(super) struct SwingSole {
    /// The contact point, world x, and the sole's height in the terrain's
    /// ankle-level convention, m.
    pub(super) point_m: [f64; 2],
    /// Its velocity, m/s.
    pub(super) velocity_m_s: [f64; 2],
    /// ∂(contact point)/∂φ5 beyond the ankle's own (the toe turning with
    /// the shank), m/rad; zero while flat.
    pub(super) d5: [f64; 2],
    /// Whether the foot stands on its toe.
    pub(super) on_toe: bool,
    /// The ground the sole meets, in the same convention, m: below the
    /// contact point, or for a foot on its toe [`toe_ground`].
    pub(super) ground_m: f64,
}

/// How far the shoe's sole reaches past the toe pivot (the metatarsal
/// heads), m.
pub(super) const SHOE_PAST_TOE_M: f64 = 0.02;

/// The ground under a foot standing on its toe (ankle at `ankle_x`, toe
/// at `toe_x`), m. A toe a few millimetres past a stair's nosing still
/// rests on it: the shoe's sole reaches [`SHOE_PAST_TOE_M`] further (the
/// lower tread under the toe had a trailing foot hang in the air, and the
/// plant declare it lifted). A toe under the next riser up is blocked by
/// the riser, which this vertical contact does not model: the foot stays
/// on its own tread (the upper tread's height there pushed the foot up
/// through the step).
fn toe_ground(terrain: &crate::terrain::Terrain, ankle_x: f64, toe_x: f64) -> f64 {
    let own = terrain.height_m(ankle_x);
    let under_toe = terrain.height_m(toe_x);
    if under_toe > own {
        own
    } else {
        under_toe.max(terrain.height_m(toe_x - SHOE_PAST_TOE_M))
    }
}

/// The generalised forces at one state.
pub(super) struct Forces {
    pub(super) t_phi: [f64; LINKS],
    pub(super) contact_n: [f64; 2],
    pub(super) pilot_nm: f64,
    /// Ankle spring plus the ankle's stop.
    pub(super) spring_nm: f64,
    pub(super) stops_nm: [f64; 4],
    /// The brakes' torques by joint (order of [`joint`]), N·m.
    pub(super) brake_nm: [f64; 4],
}

/// Anatomical angles and rates by role: ankle dorsiflexion, stance knee
/// flexion, stance hip flexion, swing hip flexion, swing knee flexion.
pub(super) fn role_angles(phi: &Phi<f64>, dphi: &Phi<f64>) -> ([f64; LINKS], [f64; LINKS]) {
    let q = anatomical_angles(&theta_from_phi(phi));
    // Θ̇ = A⁻¹Φ̇ = theta_from_phi(Φ̇) − theta_from_phi(0) (b drops out).
    let t = theta_from_phi(dphi);
    let t0 = theta_from_phi(&[0.0; LINKS]);
    let dt: [f64; LINKS] = core::array::from_fn(|i| t[i] - t0[i]);
    (q, [dphi[0], dt[1], -dt[2], dt[3], -dt[4]])
}

impl Plant {
    /// The stance ankle's offset from the flat foot's ankle, its
    /// φ1-derivatives (zero while flat).
    pub(super) fn ankle_at(&self, phi1: f64) -> foot::AnklePlacement<f64> {
        match &self.cfg.foot {
            Some(f) => f.ankle(phi1),
            None => foot::AnklePlacement {
                position_m: [0.0; 2],
                d1: [0.0; 2],
                d2: [0.0; 2],
            },
        }
    }

    /// Whether the stance heel is up at φ1.
    pub(super) fn on_toe(&self, phi1: f64) -> bool {
        self.cfg.foot.is_some_and(|f| f.on_toe(phi1))
    }

    /// Where the swing foot meets the ground: under the ankle while flat;
    /// at the toe while it still stands on it, before lift-off (a
    /// descent's trailing foot, its shank leaning past the stop: the foot
    /// turns with the shank, held on its stop, so a ground force there also
    /// turns the swing shank, [`SwingSole::d5`]). Once lifted the foot hangs
    /// free, its angle not modelled, and is a point at the ankle again, as in
    /// the paper (a toe held at the stop in the air caught the stair nosing
    /// in stair ascent).
    pub(super) fn swing_sole(&self, phi: &Phi<f64>, dphi: &Phi<f64>) -> SwingSole {
        let (ankle, v) = self.swing_foot_at(phi, dphi);
        let lean = gait_core::kinematics::wrap_pi(phi[4] - PI);
        let terrain = &self.cfg.terrain;
        match self.cfg.foot.filter(|f| !self.lifted && f.on_toe(lean)) {
            Some(f) => {
                let a = f.ankle(lean);
                let toe = f.toe();
                // Toe − ankle in the world, and its φ5-derivative.
                let r = [toe[0] - a.position_m[0], toe[1] - a.position_m[1]];
                let d5 = [-a.d1[0], -a.d1[1]];
                let x = ankle[0] + r[0];
                SwingSole {
                    // Heights in the ankle-level convention of the terrain:
                    // the sole is `rise` below the raised ankle.
                    point_m: [x, ankle[1] - a.position_m[1]],
                    velocity_m_s: [v[0] + d5[0] * dphi[4], v[1] + d5[1] * dphi[4]],
                    d5,
                    on_toe: true,
                    ground_m: toe_ground(terrain, ankle[0], x),
                }
            }
            None => SwingSole {
                point_m: ankle,
                velocity_m_s: v,
                d5: [0.0; 2],
                on_toe: false,
                ground_m: terrain.height_m(ankle[0]),
            },
        }
    }

    /// Every generalised force at a state: motors (held), ankle spring,
    /// pilot, joint stops; mapped to T_Φ.
    pub(super) fn forces(&self, phi: &Phi<f64>, dphi: &Phi<f64>, t_s: f64) -> Forces {
        let (q, dq) = role_angles(phi, dphi);
        let contact_n = self.contact_force(phi, dphi);
        let (pilot, spring) = self.ankle_torques_at(t_s, phi, dphi[0], contact_n);
        // On the toe the ankle rests on its stop: spring and stop torques
        // act between the (massless) foot and the shank, and the toe, not
        // the ankle, meets the ground: nothing of them reaches the chain.
        let toe = self.on_toe(phi[0]);
        let spring = if toe { 0.0 } else { spring };
        let lim = self.cfg.model.limits();
        let bounds = [
            (lim.ankle_plantarflexion_rad, lim.ankle_dorsiflexion_rad),
            (lim.knee_extension_rad, lim.knee_flexion_rad),
            (lim.hip_extension_rad, lim.hip_flexion_rad),
            (lim.hip_extension_rad, lim.hip_flexion_rad),
            (lim.knee_extension_rad, lim.knee_flexion_rad),
        ];
        let mut stops: [f64; LINKS] = match &self.cfg.stops {
            Some(st) => {
                core::array::from_fn(|i| st.torque_nm(q[i], dq[i], bounds[i].0, bounds[i].1))
            }
            None => [0.0; LINKS],
        };
        if self.cfg.foot.is_some() && q[0] > 0.0 {
            // The dorsiflexion stop is the toe rocker's heel-off.
            stops[0] = stops[0].max(0.0);
        }
        let (hip_s, knee_s, hip_w, knee_w) = match self.stance {
            Side::Left => (0, 1, 2, 3),
            Side::Right => (2, 3, 0, 1),
        };
        // The brakes oppose each joint's anatomical rate.
        let mut brake_nm = [0.0; 4];
        for (j, role) in [(knee_s, 1), (hip_s, 2), (hip_w, 3), (knee_w, 4)] {
            brake_nm[j] = -self.brakes[j] * dq[role];
        }
        let m: [f64; 4] = core::array::from_fn(|j| self.motor_nm[j] + brake_nm[j]);
        let (st_hip, st_knee, sw_hip, sw_knee) = (m[hip_s], m[knee_s], m[hip_w], m[knee_w]);
        // Torques on the role coordinates [ankle dorsiflexion, stance knee
        // flexion, stance hip flexion, swing hip flexion, swing knee flexion]
        // = s·θ with s = (−1, +1, −1, +1, −1), so T_θ = s·τ.
        let role = [
            pilot + spring + stops[0],
            st_knee + stops[1],
            st_hip + stops[2],
            sw_hip + stops[3],
            sw_knee + stops[4],
        ];
        let t_theta = [-role[0], role[1], -role[2], role[3], -role[4]];
        let mut stops_nm = [0.0; 4];
        stops_nm[hip_s] = stops[2];
        stops_nm[knee_s] = stops[1];
        stops_nm[hip_w] = stops[3];
        stops_nm[knee_w] = stops[4];
        let mut t_phi = t_phi_from_t_theta(&t_theta);
        // Generalised forces of a force F at the swing ankle: Jᵀ F with
        // ∂p5/∂φ_i = l_i (cos φ_i, −sin φ_i) for links 1, 2, 4, 5.
        let l = self.cfg.model.lengths();
        for i in [0, 1, 3, 4] {
            t_phi[i] += l[i] * (phi[i].cos() * contact_n[0] - phi[i].sin() * contact_n[1]);
        }
        // The moving stance ankle carries the swing foot with it; a force
        // on the swing foot's toe also turns its shank.
        let d1 = self.ankle_at(phi[0]).d1;
        t_phi[0] += d1[0] * contact_n[0] + d1[1] * contact_n[1];
        let d5 = self.swing_sole(phi, dphi).d5;
        t_phi[4] += d5[0] * contact_n[0] + d5[1] * contact_n[1];
        Forces {
            t_phi,
            contact_n,
            pilot_nm: pilot,
            spring_nm: spring + stops[0],
            stops_nm,
            brake_nm,
        }
    }

    /// (pilot, spring) torques on the ankle-dorsiflexion coordinate at `t_s`.
    pub(super) fn ankle_torques_at(
        &self,
        t_s: f64,
        phi: &Phi<f64>,
        dphi1: f64,
        contact_n: [f64; 2],
    ) -> (f64, f64) {
        let phi1 = phi[0];
        let desired = self.pilot_target.desired(t_s, t_s - self.last_swap_s);
        let spring = -self.cfg.ankle_stiffness_nm_per_rad * (phi1 - self.cfg.ankle_rest_rad);
        // What would hold this posture still on the dorsiflexion coordinate
        // (T_θ1 = −that), less what the spring already gives and what the
        // ground under the other foot takes (its generalised forces Jᵀ F).
        let static_nm = if self.cfg.pilot.gravity_compensation != 0.0 {
            let zero = [0.0; LINKS];
            let mut required =
                dynamics::inverse_dynamics(&self.cfg.model, &self.contact(), phi, &zero, &zero);
            let l = self.cfg.model.lengths();
            for i in [0, 1, 3, 4] {
                required[i] -= l[i] * (phi[i].cos() * contact_n[0] - phi[i].sin() * contact_n[1]);
            }
            let d1 = self.ankle_at(phi1).d1;
            required[0] -= d1[0] * contact_n[0] + d1[1] * contact_n[1];
            let d5 = self.swing_sole(phi, &[0.0; LINKS]).d5;
            required[4] -= d5[0] * contact_n[0] + d5[1] * contact_n[1];
            let spring_now = if self.on_toe(phi1) { 0.0 } else { spring };
            -joint_torques(&required)[0] - spring_now
        } else {
            0.0
        };
        let pilot = self.cfg.pilot.torque_nm(desired, phi1, dphi1, static_nm);
        (pilot, spring)
    }

    /// Swing-ankle world position and velocity at a state.
    pub(super) fn swing_foot_at(&self, phi: &Phi<f64>, dphi: &Phi<f64>) -> ([f64; 2], [f64; 2]) {
        let p5 = forward_kinematics(&self.cfg.model, phi)[4];
        let a = self.ankle_at(phi[0]);
        let l = self.cfg.model.lengths();
        let mut v = [a.d1[0] * dphi[0], a.d1[1] * dphi[0]];
        for i in [0, 1, 3, 4] {
            v[0] += l[i] * dphi[i] * phi[i].cos();
            v[1] -= l[i] * dphi[i] * phi[i].sin();
        }
        let o = self.stance_foot_m;
        (
            [
                o[0] + a.position_m[0] + p5[0],
                o[1] + a.position_m[1] + p5[1],
            ],
            v,
        )
    }

    /// The ground's force on the swing ankle at a state (world x, y), N.
    pub(super) fn contact_force(&self, phi: &Phi<f64>, dphi: &Phi<f64>) -> [f64; 2] {
        let Some(c) = &self.cfg.contact else {
            return [0.0; 2];
        };
        let sole = self.swing_sole(phi, dphi);
        let (p, v) = (sole.point_m, sole.velocity_m_s);
        let depth = sole.ground_m - p[1];
        if depth <= 0.0 {
            return [0.0; 2];
        }
        let fy = (c.stiffness_n_per_m * depth - c.damping_n_s_per_m * v[1]).max(0.0);
        let stick = self
            .contact_anchor_x
            .filter(|&(_, toe)| toe == sole.on_toe)
            .map_or(0.0, |(ax, _)| -c.tangential_stiffness_n_per_m * (p[0] - ax));
        let limit = c.friction * fy;
        let fx = (stick - c.tangential_damping_n_s_per_m * v[0]).clamp(-limit, limit);
        [fx, fy]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terrain::Terrain;

    #[test]
    fn a_toe_just_past_a_nosing_rests_on_it_and_a_toe_under_a_riser_stays_on_its_tread() {
        // Descending: treads at 0 up to x = 0.3, then 0.1 lower.
        let down = Terrain::Stairs {
            start_x_m: 0.3,
            rise_m: -0.1,
            tread_m: 0.3,
            steps: 4,
        };
        assert_eq!(toe_ground(&down, 0.15, 0.28), 0.0);
        assert_eq!(toe_ground(&down, 0.15, 0.3 + 0.5 * SHOE_PAST_TOE_M), 0.0);
        assert_eq!(toe_ground(&down, 0.15, 0.3 + 1.5 * SHOE_PAST_TOE_M), -0.1);
        // Ascending: the next tread 0.1 higher from x = 0.3.
        let up = Terrain::Stairs {
            start_x_m: 0.3,
            rise_m: 0.1,
            tread_m: 0.3,
            steps: 4,
        };
        assert_eq!(toe_ground(&up, 0.15, 0.31), 0.0);
        assert_eq!(toe_ground(&up, 0.35, 0.45), 0.1);
        assert_eq!(toe_ground(&Terrain::Level, 0.0, 0.5), 0.0);
    }
}
