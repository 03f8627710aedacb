//! A safe hold's torso levelling: the stance shank measured ahead of the
//! hold's plan (a pilot leaning on the crutches; the ankles have no drive)
//! turns the torso back by as much, so that its pitch, and the torque it
//! asks of the hips, stay what they were when the hold began.
//!
//! Why: with hips and knees held, a shank leaning δ further forward pitches
//! the torso by δ too. The torso (57.7 kg, its centre of mass 0.34 m above
//! the hips) asks the hip carrying it for 194 · sin(pitch) N·m against a
//! 150 N·m drive; a walk's torso is planned 21–27° forward, so a lean of
//! 0.2 rad takes it to where a hip that also brakes the swing leg gives way
//! (`docs/safety.md`, "Safe hold").

use super::{JOINTS, Sensed, Sequencer};
use crate::posture::Side;

impl Sequencer<'_> {
    /// Turns the torso of `held` (the hold's joint references) back by the
    /// stance shank's lean past the hold's plan, less
    /// [`SequencerConfig::level_deadband_rad`](super::SequencerConfig), at
    /// most `level_max_rad`, moving at most `level_rate_rad_s`: the stance
    /// hip extends by it, and the other hip too once both feet are down
    /// (the torso turns between thighs that stay where they are). A swing
    /// foot still being set down keeps its hip: it places the foot. An
    /// ankle that cannot tell (NaN) leaves the levelling where it is.
    ///
    /// Once a joint is braked, the torso is never turned back past the
    /// pitch it had then: the braked joint cannot share the
    /// load a torso further back puts on the others (a stair descent's
    /// bent trailing knee, its drive lost on the other leg, sank onto its
    /// stop under a torso levelled behind it).
    pub(super) fn level_torso(&mut self, sensed: &Sensed, dt_s: f32, held: &mut [f32; JOINTS]) {
        let cfg = self.cfg;
        let (stance, setting_down) = self.levelled_legs();
        let ankle = |a: &[f32; 2]| a.get(stance.ankle()).copied().unwrap_or(f32::NAN);
        let joint = |i: usize| sensed.joints_rad.get(i).copied().unwrap_or(f32::NAN);
        // φ3 = φ1 − stance knee + stance hip (`posture::phi_from_joints`).
        let torso = ankle(&sensed.ankles_rad) - joint(stance.hip() + 1) + joint(stance.hip());
        let lean = ankle(&sensed.ankles_rad) - ankle(&self.ankle_plan);
        if lean.is_finite() {
            let mut want = (lean - cfg.level_deadband_rad).clamp(0.0, cfg.level_max_rad.max(0.0));
            if self.any_braked {
                if self.torso_at_brake.is_nan() {
                    self.torso_at_brake = torso;
                }
                let behind = self.torso_at_brake - torso;
                if behind > 0.0 {
                    want = want.min((self.level_rad - behind).max(0.0));
                }
            }
            let step = (cfg.level_rate_rad_s * dt_s).max(0.0);
            self.level_rad += (want - self.level_rad).clamp(-step, step);
        }
        let level = self.level_rad;
        if let Some(h) = held.get_mut(stance.hip()) {
            *h -= level;
        }
        if !setting_down {
            if let Some(h) = held.get_mut(stance.other().hip()) {
                *h -= level;
            }
        }
    }

    /// The stance leg a hold levels, and whether the other foot is still
    /// being set down (its hip then not levelled).
    fn levelled_legs(&self) -> (Side, bool) {
        match self.set_down {
            Some(sd) => (sd.stance, !sd.done),
            None => (self.stance, false),
        }
    }

    /// The hold's reference for `joint` that puts it at `angle_rad` once
    /// levelled: a joint held where it was measured must stay there, not
    /// turn back by the levelling a second time.
    pub(super) fn before_levelling(&self, joint: usize, angle_rad: f32) -> f32 {
        let (stance, setting_down) = self.levelled_legs();
        let levelled = joint == stance.hip() || (!setting_down && joint == stance.other().hip());
        if levelled {
            angle_rad + self.level_rad
        } else {
            angle_rad
        }
    }
}
