//! What the plant reports after each step: the true state, the sensors'
//! truths and the chain's energy.

use super::*;

/// The true state, for metrics, plots and the peripherals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrueState {
    /// Simulation time, s.
    pub time_s: f64,
    /// The stance leg.
    pub stance: Side,
    /// Absolute link angles Φ in the stance frame, rad.
    pub phi: Phi<f64>,
    /// Φ̇, rad/s.
    pub dphi: Phi<f64>,
    /// Anatomical joint angles, flexion positive, rad: left hip, left knee,
    /// right hip, right knee (the order of [`joint`]).
    pub joint_angles_rad: [f64; 4],
    /// Their rates, rad/s.
    pub joint_rates_rad_s: [f64; 4],
    /// Ankle dorsiflexion per side (left, right), rad: the stance ankle's is
    /// φ1, a swing foot still on the ground reads its shank's lean the same
    /// way; a swing ankle in the air is not modelled (`None`).
    pub ankle_dorsiflexion_rad: [Option<f64>; 2],
    /// Ankle positions per side (left, right), world frame, m.
    pub feet_m: [[f64; 2]; 2],
    /// Stance ankle p0 then p1…p5 (stance knee, hip, torso top, swing knee,
    /// swing ankle), world frame, m.
    pub points_m: [[f64; 2]; 6],
    /// Centre of mass, world frame, m.
    pub com_m: [f64; 2],
    /// Vertical ground force under each foot (left, right), N.
    pub foot_forces_n: [f64; 2],
    /// Vertical force on each crutch (left, right), N.
    pub crutch_forces_n: [f64; 2],
    /// The pilot's balancing torque on the stance ankle (dorsiflexion
    /// positive), N·m.
    pub pilot_torque_nm: f64,
    /// The ankle spring's torque plus the ankle stop's (dorsiflexion
    /// positive), N·m.
    pub spring_torque_nm: f64,
    /// The joint stops' torques (order of [`joint`], flexion positive), N·m.
    pub stop_torques_nm: [f64; 4],
    /// The motor torques at the present state, N·m (order of [`joint`]):
    /// those applied in the last step plus the brakes' at the present rates.
    pub motor_torques_nm: [f64; 4],
    /// Mechanical energy: kinetic + gravity (world heights) + ankle spring, J.
    pub energy_j: f64,
    /// Whether the swing ankle has been lifted since the last swap.
    pub swing_lifted: bool,
}

impl Plant {
    /// The true state now.
    pub fn state(&self) -> TrueState {
        let model = &self.cfg.model;
        let pts = forward_kinematics(model, &self.phi);
        let a = self.ankle_at(self.phi[0]).position_m;
        let o = [self.stance_foot_m[0] + a[0], self.stance_foot_m[1] + a[1]];
        let world = |p: [f64; 2]| [o[0] + p[0], o[1] + p[1]];
        let points_m = [
            o,
            world(pts[0]),
            world(pts[1]),
            world(pts[2]),
            world(pts[3]),
            world(pts[4]),
        ];
        let (anat, rates) = role_angles(&self.phi, &self.dphi);
        let (angles, rates_out) = match self.stance {
            Side::Left => (
                [anat[2], anat[1], anat[3], anat[4]],
                [rates[2], rates[1], rates[3], rates[4]],
            ),
            Side::Right => (
                [anat[3], anat[4], anat[2], anat[1]],
                [rates[3], rates[4], rates[2], rates[1]],
            ),
        };
        let mut ankle = [None; 2];
        // The encoder reads the shank–foot angle: φ1, or the stop once the
        // heel is up.
        let on_ground = |lean: f64| self.cfg.foot.map_or(lean, |f| f.dorsiflexion(lean));
        ankle[self.stance.index()] = Some(on_ground(self.phi[0]));
        // A swing foot not yet lifted (the trailing foot after a landing,
        // until its toe-off clears the ground) is planted like a stance
        // foot: its encoder reads its shank's lean the same way, on the toe
        // the stop. (Its contact force is no test: it is 0 at the swap's
        // tick, and the reading then dipped off the stop — enough to flip
        // the controller's heel-up estimate of φ1 in a noisy stair descent
        // whose foot set down unloaded.) In the air the ankle is not
        // modelled (`None`).
        if !self.lifted {
            let lean = gait_core::kinematics::wrap_pi(self.phi[4] - PI);
            ankle[self.stance.other().index()] = Some(on_ground(lean));
        }
        let mut feet_m = [[0.0; 2]; 2];
        feet_m[self.stance.index()] = o;
        feet_m[self.stance.other().index()] = points_m[5];

        let coms = link_com(model, &self.phi);
        let total_m = model.total_mass_kg();
        let mut com = [0.0; 2];
        for (c, l) in coms.iter().zip(model.links()) {
            com[0] += l.mass_kg * c[0] / total_m;
            com[1] += l.mass_kg * c[1] / total_m;
        }
        let com_m = world(com);

        let crutch_forces_n = self.cfg.pilot.crutch_forces_n(self.pilot_nm);
        let support = total_m * (GRAVITY_M_S2 + self.com_accel_y());
        let feet_total = (support - crutch_forces_n[0] - crutch_forces_n[1]).max(0.0);
        // The swing foot carries what the ground contact pushes; the stance
        // foot the rest of the support the crutches do not take.
        let swing_load = self.contact_n[1].max(0.0);
        let mut foot_forces_n = [0.0; 2];
        foot_forces_n[self.stance.index()] = (feet_total - swing_load).max(0.0);
        foot_forces_n[self.stance.other().index()] = swing_load;

        let spring_angle = self
            .cfg
            .foot
            .map_or(self.phi[0], |f| f.dorsiflexion(self.phi[0]));
        let spring_pe = 0.5
            * self.cfg.ankle_stiffness_nm_per_rad
            * (spring_angle - self.cfg.ankle_rest_rad).powi(2);
        let chain = dynamics::energy(model, &self.contact(), &self.phi, &self.dphi);
        let energy_j = chain + total_m * GRAVITY_M_S2 * self.stance_foot_m[1] + spring_pe;
        TrueState {
            time_s: self.time_s,
            stance: self.stance,
            phi: self.phi,
            dphi: self.dphi,
            joint_angles_rad: angles,
            joint_rates_rad_s: rates_out,
            ankle_dorsiflexion_rad: ankle,
            feet_m,
            points_m,
            com_m,
            foot_forces_n,
            crutch_forces_n,
            pilot_torque_nm: self.pilot_nm,
            spring_torque_nm: self.spring_nm,
            stop_torques_nm: self.stops_nm,
            motor_torques_nm: core::array::from_fn(|j| self.motor_nm[j] + self.brake_nm[j]),
            energy_j,
            swing_lifted: self.lifted,
        }
    }

    /// Vertical acceleration of the centre of mass, m/s²: the stance
    /// ankle's own (on its circle about the toe) plus the links' relative
    /// to it ([`gait_core::kinematics::link_com_accelerations`]).
    pub(super) fn com_accel_y(&self) -> f64 {
        let model = &self.cfg.model;
        let a = self.ankle_at(self.phi[0]);
        let base = a.d1[1] * self.ddphi[0] + a.d2[1] * self.dphi[0].powi(2);
        let relative = link_com_accelerations(model, &self.phi, &self.dphi, &self.ddphi);
        let mut total = model.total_mass_kg() * base;
        for (link, [_, y]) in model.links().iter().zip(relative) {
            total += link.mass_kg * y;
        }
        total / model.total_mass_kg()
    }
}
