//! The reference: everything the controller follows in one tick, handed
//! over by the sequencer ([`crate::sequencer::Sequencer::update`]) so that
//! the controller never reads a table or asks which phase the gait is in.
//!
//! A table sample travels once: flash → Φ (one interpolation, plus the two
//! lookups of its central differences) → joint angles and the model's
//! motion → torques in the controller.

use gait_core::LINKS;
use gait_core::kinematics::Phi;
use gait_core::tables::GaitTable;

use crate::posture::{JOINTS, Side};
use crate::sequencer::{SeqEvents, SeqStatus, StepTable};

/// What the joints, the feed-forward and the supervisor follow this tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reference {
    /// Reference angles, joint order, rad.
    pub angle_rad: [f32; JOINTS],
    /// Reference rates, rad/s.
    pub rate_rad_s: [f32; JOINTS],
    /// The stance leg now.
    pub stance: Side,
    /// While a table is being played (up to its end): Φ, Φ̇ and Φ̈ in the
    /// stance leg's frame, for the feed-forward of the motion. `None`: the
    /// reference is a held or blended posture, and the feed-forward is its
    /// statics.
    pub motion: Option<TableMotion>,
    /// What the gait plans for each ankle (left, right) as a stance shank's
    /// lean φ1, rad (past the stop the heel is planned up); NaN where
    /// nothing is planned: the table's stance φ1 in a swing, the start
    /// posture's ankles while both feet are down ([`ankles_in_swing`],
    /// [`ankles_in_start_posture`]; standing, of the clinician's
    /// selection), what it was when a safe hold began.
    pub ankle_plan_rad: [f32; 2],
    /// Share (0 … 1) of the body's weight the other foot may carry: all of
    /// it between steps (both feet planned down), during a swing what the
    /// table plans for its swing foot
    /// ([`gait_core::playback::other_foot_share`]); `None` in a safe hold,
    /// where only the foot's sensor can tell.
    pub other_foot_share: Option<f32>,
    /// Where gait execution is after this tick.
    pub status: SeqStatus,
    /// What happened this tick.
    pub events: SeqEvents,
}

/// The table's motion at one time, stance frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableMotion {
    /// Φ, rad.
    pub phi: Phi<f32>,
    /// Φ̇, rad/s.
    pub dphi: Phi<f32>,
    /// Φ̈, rad/s².
    pub ddphi: Phi<f32>,
}

/// The motion of `table` at `t_s`, given its Φ there (`phi`, the one
/// interpolation of the tick): rates by central differences over one table
/// period, taken from samples inside the table. Past either end, at_time
/// clamps, and a central difference across the clamp would read the last
/// rate as a stop within one period (φ1 still moving at 0.14 rad/s at the
/// landing became a 1,200 N·m ankle and 600 N·m knee demand). `None` once
/// the table has ended: the reference then holds its last posture.
pub fn table_motion(table: &StepTable<'_>, t_s: f32, phi: Phi<f32>) -> Option<TableMotion> {
    if t_s > table.duration_s() {
        return None;
    }
    let h = table.period_s();
    let tc = t_s.max(h).min(table.duration_s() - h);
    let (a, c) = (table.at_time(tc - h), table.at_time(tc + h));
    let mid = if tc == t_s { phi } else { table.at_time(tc) };
    let mut dphi = [0.0f32; LINKS];
    let mut ddphi = [0.0f32; LINKS];
    for (((o1, o2), (&x0, &x1)), &x2) in dphi
        .iter_mut()
        .zip(ddphi.iter_mut())
        .zip(a.iter().zip(&mid))
        .zip(&c)
    {
        *o1 = (x2 - x0) / (2.0 * h);
        *o2 = (x2 - 2.0 * x1 + x0) / (h * h);
    }
    Some(TableMotion { phi, dphi, ddphi })
}

/// Where the ankles are planned while both feet are down in a table's
/// start posture (standing, waiting, transferring): the stance ankle at the
/// table's first φ1, the other at its last (the trailing leg's lean;
/// periodic tables). Left, right; NaN without a table.
pub fn ankles_in_start_posture(table: Option<&GaitTable<'_>>, stance: Side) -> [f32; 2] {
    let mut out = [f32::NAN; 2];
    if let Some(tb) = table {
        let [first, ..] = tb.first();
        let [last, ..] = tb.last();
        set_ankle(&mut out, stance, first);
        set_ankle(&mut out, stance.other(), last);
    }
    out
}

/// The ankle plan in a swing: the stance ankle at `phi1`, the swing foot
/// in the air (NaN).
pub fn ankles_in_swing(stance: Side, phi1: f32) -> [f32; 2] {
    let mut out = [f32::NAN; 2];
    set_ankle(&mut out, stance, phi1);
    out
}

fn set_ankle(out: &mut [f32; 2], side: Side, v: f32) {
    if let Some(p) = out.get_mut(side.ankle()) {
        *p = v;
    }
}
