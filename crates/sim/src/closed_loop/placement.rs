//! Where the pilot has put the stance foot before the first step: further
//! forward (or back) under the body than the gait's start posture puts it,
//! as a pilot who stood up or stopped with the foot a little off does. The
//! stance ankle then stands off its planned angle, which is what the
//! board's re-planner reads.

use gait_core::kinematics::forward_kinematics;

use super::{Rig, RigError};
use crate::plant::Plant;

/// How near the placed posture's hip and other ankle must come to their
/// aims, m (the two-link solutions are exact up to rounding).
const PLACEMENT_TOLERANCE_M: f64 = 1e-9;

/// The straightest a stance leg is stretched, as a share of its two
/// links' length: past it the hip sinks.
const MAX_STRETCH: f64 = 0.998;

/// The shank and thigh angles (Φ convention: clockwise from vertical-up)
/// that put the hip at `hip` from the ankle, the knee bent to the side
/// whose thigh-less-shank angle is nearest `bend` (the present one). `None`
/// when the leg cannot reach.
fn two_link(l1: f64, l2: f64, hip: [f64; 2], bend: f64) -> Option<(f64, f64)> {
    let r = hip[0].hypot(hip[1]);
    let cos_gamma = (r * r + l1 * l1 - l2 * l2) / (2.0 * r * l1);
    if !(r > 0.0 && cos_gamma.abs() <= 1.0) {
        return None;
    }
    let (beta, gamma) = (hip[0].atan2(hip[1]), cos_gamma.acos());
    [beta + gamma, beta - gamma]
        .map(|a1| {
            let w = [hip[0] - l1 * a1.sin(), hip[1] - l1 * a1.cos()];
            (a1, w[0].atan2(w[1]))
        })
        .into_iter()
        .min_by(|a, b| {
            let off = |(a1, a2): &(f64, f64)| (a2 - a1 - bend).abs();
            off(a).total_cmp(&off(b))
        })
}

fn unreachable() -> RigError {
    RigError::Config("a leg cannot reach a stance foot placed so far off")
}

impl Rig<'_> {
    /// Stands the body with the stance foot `offset_m` further forward
    /// under it than now (negative: back), before the first tick: the hip,
    /// the torso and the other foot where they were (the hip lower only
    /// where the stance leg would have to stretch straight), each leg
    /// reaching its foot with its knee bent to the same side. The stance
    /// shank then leans back from its planned angle by about `offset_m`
    /// over the leg's length (forward for a foot placed back).
    ///
    /// # Errors
    ///
    /// [`RigError::Config`] once the controller has ticked, or when the
    /// stance leg cannot reach the new place; [`RigError::Sim`] when the
    /// plant refuses the posture.
    pub fn place_stance_foot(&mut self, offset_m: f64) -> Result<(), RigError> {
        if !self.trace.is_empty() {
            return Err(RigError::Config("the foot is placed before the first tick"));
        }
        let now = self.plant.state();
        let mut phi = now.phi;
        let model = self.plant.config().model;
        let [l1, l2, ..] = model.lengths();
        let [_, hip, _, _, other] = forward_kinematics(&model, &phi);
        // The stance ankle is the origin of the stance frame: a foot moved
        // forward under the body puts the hip and the other foot that much
        // behind it. A leg that would have to stretch straighter than
        // `MAX_STRETCH` lowers the hip instead (a straight stance leg: the
        // pilot sinks onto the foot).
        let x = hip[0] - offset_m;
        let reach = MAX_STRETCH * (l1 + l2);
        let y = hip[1].min((reach * reach - x * x).max(0.0).sqrt());
        let aim = [x, y];
        let (phi1, phi2) = two_link(l1, l2, aim, phi[1] - phi[0]).ok_or_else(unreachable)?;
        phi[0] = phi1;
        phi[1] = phi2;
        // The other leg reaches its foot from the new hip, its knee on its
        // branch (the swing leg's reach of the sequencer's set-down).
        let other_aim = [other[0] - offset_m, other[1]];
        phi = gait_core::reach::place_swing_ankle_from(&model, &phi, aim, other_aim, 0.0);
        let [_, placed, _, _, placed_other] = forward_kinematics(&model, &phi);
        let missed = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
        if missed(placed, aim) > PLACEMENT_TOLERANCE_M
            || missed(placed_other, other_aim) > PLACEMENT_TOLERANCE_M
        {
            return Err(unreachable());
        }
        let stance_foot = [now.points_m[0][0] + offset_m, now.points_m[0][1]];
        let mut plant = Plant::with_posture(
            *self.plant.config(),
            phi,
            [0.0; 5],
            self.plant.stance(),
            stance_foot,
        )
        .map_err(RigError::Sim)?;
        plant.set_pilot(self.plant.pilot());
        self.plant = plant;
        // The sensors read the placed body from the first tick on, as they
        // read the start posture (`Rig::new`).
        let s = self.plant.state();
        for (cell, a) in self.ankle_cells.iter().zip(s.ankle_dorsiflexion_rad) {
            cell.set(a.unwrap_or(0.0));
        }
        self.publish();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::two_link;
    use crate::scenario::{flash_tables, gait_rig, strong_pilot};
    use gait_control::operator::Gait;

    #[test]
    fn dbg_compare_branches() {
        let mut rig = gait_rig(Gait::StairDown, strong_pilot(), flash_tables()).unwrap();
        let before = rig.plant.state();
        rig.place_stance_foot(0.02).unwrap();
        let after = rig.plant.state();
        eprintln!(
            "before {:?}\nafter {:?}\npts b {:?}\npts a {:?}",
            before.phi, after.phi, before.points_m, after.points_m
        );
    }

    #[test]
    fn a_placed_stance_foot_moves_alone_and_its_shank_leans_the_other_way() {
        for (gait, offset) in [
            (Gait::Walk, 0.02),
            (Gait::Walk, -0.02),
            (Gait::StairDown, 0.02),
        ] {
            let mut rig = gait_rig(gait, strong_pilot(), flash_tables()).unwrap();
            let before = rig.plant.state();
            rig.place_stance_foot(offset).unwrap();
            let after = rig.plant.state();
            let [p0, p5] = [0, 5].map(|i| (before.points_m[i], after.points_m[i]));
            // The stance foot moved by the offset, the other stayed.
            assert!((p0.1[0] - p0.0[0] - offset).abs() < 1e-9 && (p0.1[1] - p0.0[1]).abs() < 1e-9);
            assert!((p5.1[0] - p5.0[0]).abs() < 1e-9 && (p5.1[1] - p5.0[1]).abs() < 1e-9);
            // The hip kept its place, or sank where the leg was straight.
            let (h0, h1) = (before.points_m[2], after.points_m[2]);
            assert!(
                (h1[0] - h0[0]).abs() < 1e-9 && h1[1] <= h0[1] + 1e-9,
                "{gait:?} {offset}"
            );
            // A foot placed forward leans the shank back, and the reverse.
            let turned = after.phi[0] - before.phi[0];
            assert!(turned * offset < 0.0, "{gait:?} {offset}: {turned}");
            // The torso is as it was.
            assert_eq!(after.phi[2], before.phi[2]);
        }
        // Only before the first tick.
        let mut rig = gait_rig(Gait::Walk, strong_pilot(), flash_tables()).unwrap();
        rig.tick().unwrap();
        assert!(rig.place_stance_foot(0.01).is_err());
    }

    #[test]
    fn the_two_link_leg_reaches_its_hip_with_the_knee_on_its_side() {
        let (l1, l2) = (0.45, 0.42);
        for (hip, bend) in [
            ([0.05, 0.8], 0.3),
            ([-0.1, 0.75], 0.5),
            ([0.02, 0.86], -0.1),
        ] {
            let (a1, a2) = two_link(l1, l2, hip, bend).unwrap();
            let reached = [l1 * a1.sin() + l2 * a2.sin(), l1 * a1.cos() + l2 * a2.cos()];
            assert!((reached[0] - hip[0]).abs() < 1e-12 && (reached[1] - hip[1]).abs() < 1e-12);
            // The bend keeps the sign it was asked to stay near.
            assert_eq!((a2 - a1).signum(), bend.signum(), "{hip:?}");
        }
        // Out of reach.
        assert!(two_link(l1, l2, [0.0, 0.9], 0.1).is_none());
    }
}
