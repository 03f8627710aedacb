//! The swing foot meeting the ground: its position and height, the
//! landing test, and the leg swap with the impact map.

use super::*;

/// A registered landing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Landing {
    /// Simulation time, s.
    pub time_s: f64,
    /// The leg that landed (the new stance leg).
    pub side: Side,
    /// Where its ankle landed, world frame, m.
    pub position_m: [f64; 2],
    /// Ground height there, m (the ankle may be up to the tolerance above,
    /// or below it by what it travelled in the last step).
    pub ground_m: f64,
    /// Downward ankle speed at touch-down, m/s (positive).
    pub descent_speed_m_s: f64,
    /// Horizontal distance from the previous stance foot, m.
    pub step_length_m: f64,
    /// Vertical speed of the trailing (old stance) foot just after the
    /// impact, m/s, positive up; negative means the impact model's lift-off
    /// assumption did not hold.
    pub trailing_foot_speed_up_m_s: f64,
}

/// A swing foot that has moved this far along the ground from where it was
/// at the last leg swap has been lifted, m.
pub(super) const MIN_STEP_TRAVEL_M: f64 = 0.2;

/// A lifted swing foot lands only this far along the ground from where it
/// was at the last leg swap, m: a trailing foot that hovers above its
/// clearance after an impact and settles back onto its own tread has not
/// taken a step (counted as one, the plant swapped its legs twice within a
/// weight transfer, with an impact's velocity jump at each swap).
pub(super) const MIN_LANDING_TRAVEL_M: f64 = 0.05;

/// A lifted swing foot whose ground contact carries this much has landed,
/// N (well below the controller's 80 N landing threshold, so the plant's
/// leg swap never lags the controller's).
pub(super) const LANDED_LOAD_N: f64 = 30.0;

impl Plant {
    /// Remembers where the swing foot's contact began; forgets it once the
    /// foot is clear of the ground.
    pub(super) fn update_contact_anchor(&mut self) {
        let sole = self.swing_sole(&self.phi, &self.dphi);
        let p = sole.point_m;
        let depth = sole.ground_m - p[1];
        let same = self
            .contact_anchor_x
            .is_some_and(|(_, toe)| toe == sole.on_toe);
        if depth >= 0.0 {
            if !same {
                self.contact_anchor_x = Some((p[0], sole.on_toe));
            }
        } else if depth < -0.001 {
            self.contact_anchor_x = None;
        }
    }

    /// Swing-ankle position in the world, m.
    pub(super) fn swing_foot_world(&self) -> [f64; 2] {
        self.swing_foot_at(&self.phi, &self.dphi).0
    }

    /// The swing foot's sole above the ground (the toe, for a foot whose
    /// heel is up), m.
    pub(super) fn swing_height_above_ground_m(&self) -> f64 {
        let sole = self.swing_sole(&self.phi, &self.dphi);
        sole.point_m[1] - sole.ground_m
    }

    /// Swing-ankle velocity, m/s: Σ l_i φ̇_i (cos φ_i, −sin φ_i) over links
    /// 1, 2, 4, 5.
    pub(super) fn swing_foot_velocity(&self) -> [f64; 2] {
        self.swing_foot_at(&self.phi, &self.dphi).1
    }

    pub(super) fn detect_landing(&mut self) -> Option<Landing> {
        let above = self.swing_height_above_ground_m();
        if !self.lifted {
            // Lifted: clear of the ground by the clearance, or carried
            // forward (or back) a good part of a step — a low swing whose
            // foot, still leaning on its toe's geometry, never shows the
            // clearance; a foot hovering after an impact does neither.
            let travel = (self.swing_foot_world()[0] - self.swing_start_x_m).abs();
            if above > self.cfg.lift_clearance_m || travel >= MIN_STEP_TRAVEL_M {
                self.lifted = true;
            }
            return None;
        }
        let v = self.swing_foot_velocity();
        // Touching down, or already standing on it: a foot set down at rest
        // (a table that lands with zero speed) may settle into the ground
        // without ever moving down through the tolerance band.
        let touching = above <= self.cfg.landing_tolerance_m && v[1] < 0.0;
        let loaded = self.contact_n[1] >= LANDED_LOAD_N;
        let travel = (self.swing_foot_world()[0] - self.swing_start_x_m).abs();
        if !(touching || loaded) || travel < MIN_LANDING_TRAVEL_M {
            return None;
        }
        let foot = self.swing_foot_world();
        let mut landing = Landing {
            time_s: self.time_s,
            side: self.stance.other(),
            position_m: foot,
            ground_m: self.cfg.terrain.height_m(foot[0]),
            descent_speed_m_s: -v[1],
            step_length_m: foot[0] - self.stance_foot_m[0],
            trailing_foot_speed_up_m_s: 0.0,
        };
        self.swap(foot);
        landing.trailing_foot_speed_up_m_s = self.swing_foot_velocity()[1];
        self.landings.push(landing);
        Some(landing)
    }

    /// Mirrors the posture onto the other leg and applies the impact map
    /// ([`crate::impact`]); see the module docs.
    pub(super) fn swap(&mut self, new_stance_foot: [f64; 2]) {
        let a = self.ankle_at(self.phi[0]);
        let old_ankle = [
            self.stance_foot_m[0] + a.position_m[0],
            self.stance_foot_m[1] + a.position_m[1],
        ];
        let old_ankle_vel = [a.d1[0] * self.dphi[0], a.d1[1] * self.dphi[0]];
        let [p1, p2, p3, p4, p5] = self.phi;
        let [_, _, w3, w4, w5] = self.dphi;
        let near_zero = gait_core::kinematics::wrap_pi::<f64>;
        let near_pi = |x: f64| PI + near_zero(x - PI);
        let phi_new = [
            near_zero(p5 - PI),
            near_zero(p4 - PI),
            near_zero(p3),
            near_pi(p2 + PI),
            near_pi(p1 + PI),
        ];
        self.dphi = crate::impact::post_impact_velocities(
            &self.cfg.model,
            &self.phi,
            &self.dphi,
            old_ankle,
            old_ankle_vel,
            &phi_new,
            new_stance_foot,
        )
        // Fallback (never needed for a physical posture): keep the new stance
        // leg's and the torso's angular velocities, stop the new swing leg.
        .unwrap_or([w5, w4, w3, 0.0, 0.0]);
        self.phi = phi_new;
        // The pilot's target was the old stance shank's: until the harness
        // gives one for the new stance shank, the pilot holds it where it is
        // (a target of the other shank would read as a 0.2 rad error).
        self.pilot_target = PilotTarget::Hold {
            phi1_rad: phi_new[0],
        };
        self.stance = self.stance.other();
        self.stance_foot_m = new_stance_foot;
        self.last_swap_s = self.time_s;
        self.lifted = false;
        self.swing_start_x_m = self.swing_foot_world()[0];
        self.contact_anchor_x = None;
        self.update_contact_anchor();
        // A failure here would repeat at the next step's first stage and be
        // reported there; the outputs keep their pre-swap values meanwhile.
        let _ = self.refresh_outputs();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plant standing on its left foot with the right one lifted
    /// (`lifted`) from `start_x` (world, m) and now carrying 100 N.
    fn loaded_swing_foot(start_x: f64) -> Plant {
        let mut plant = Plant::with_posture(
            PlantConfig::default(),
            STANDING,
            [0.0; LINKS],
            Side::Left,
            [0.0; 2],
        )
        .unwrap();
        plant.lifted = true;
        plant.swing_start_x_m = start_x;
        plant.contact_n = [0.0, 100.0];
        plant
    }

    #[test]
    fn a_lifted_foot_lands_only_a_step_from_where_it_lifted() {
        // Standing: the swing foot is beside the stance foot, at x = 0.
        let x = Plant::with_posture(
            PlantConfig::default(),
            STANDING,
            [0.0; LINKS],
            Side::Left,
            [0.0; 2],
        )
        .unwrap()
        .swing_foot_world()[0];
        // Settling back where it lifted (a trailing foot hovering after an
        // impact): no landing, no swap.
        let mut hover = loaded_swing_foot(x - 0.5 * MIN_LANDING_TRAVEL_M);
        assert!(hover.detect_landing().is_none());
        assert_eq!(hover.stance(), Side::Left);
        // A step's travel forward (or back, a descent's foot set down behind):
        // a landing, the legs swapped.
        for from in [x - 0.1, x + 0.1] {
            let mut step = loaded_swing_foot(from);
            let landed = step.detect_landing().expect("a landing");
            assert_eq!(landed.side, Side::Right);
            assert_eq!(step.stance(), Side::Right);
        }
    }
}
