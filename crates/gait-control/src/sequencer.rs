//! Gait execution: which reference the joints follow, tick by tick.
//!
//! Phases: **Standing** (hold a posture) → **WaitingReady** (at the table's
//! start posture, waiting for the pilot: both crutches loaded and weight on
//! the stance foot) → **Swing** (play the table) → landing detected by the
//! swing foot's sensor → **Transfer** (the legs swap roles; the reference
//! blends to the next step's start posture) → WaitingReady again, or
//! Standing when a stop was requested. **SafeHold** ramps the reference to
//! the posture measured when a fatal fault struck and stays there until a
//! clinician reset.
//!
//! A swing whose table has ended without a landing goes on lowering the
//! foot (the ground search, [`SequencerConfig::ground_search_depth_m`])
//! until the foot's sensor feels the ground or the landing times out.
//!
//! Rules enforced here: a gait starts only from the standing posture it was
//! planned from (within a tolerance), only with a verified table, never while
//! a step is in progress; a stop takes effect at the end of the current step.
//! Work per tick is constant: one table interpolation (and after a table's
//! end one closed-form two-link IK), no iteration, no loop
//! whose length depends on data.

mod config;
mod tables;
mod transfer;

use gait_core::BodyModel;
use gait_core::kinematics::Posture;
use gait_core::tables::GaitTable;

use crate::faults::InSwing;
use crate::operator::{Gait, MAX_GAITS};
use crate::posture::{JOINTS, Side, joints_from_phi};
pub use crate::reference::Reference;
use crate::reference::{ankles_in_start_posture, ankles_in_swing, table_motion};
pub use config::SequencerConfig;
pub use tables::{GaitTables, Selection, gait_of_kind};
use transfer::TransferPlan;

/// The ground search stops where the swing knee would straighten past this
/// flexion, rad (6°): a leg locked straight takes the landing on its stop.
const SEARCH_MIN_KNEE_FLEXION_RAD: f32 = 0.1;

/// Where gait execution is.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    /// Holding a posture.
    Standing,
    /// At a step's start posture, waiting for the pilot to be ready.
    WaitingReady {
        /// The leg that will carry the body.
        stance: Side,
    },
    /// Playing a step.
    Swing {
        /// The leg that carries the body.
        stance: Side,
        /// Time since the swing started, s.
        t_s: f32,
    },
    /// Weight transfer after a landing.
    Transfer {
        /// The new stance leg.
        stance: Side,
        /// Time since the landing, s.
        t_s: f32,
    },
    /// Ramped hold of the posture measured at a fatal fault.
    SafeHold {
        /// Time since the hold began, s.
        t_s: f32,
    },
}

/// Something that happened this tick (for the log and the crutch metric).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SeqEvent {
    /// A start was accepted: now waiting for readiness.
    StartAccepted(Gait, Side),
    /// A start was refused.
    StartRefused(RefuseReason),
    /// The swing of a step began.
    SwingStarted(Gait, Side),
    /// The swing foot landed.
    Landed,
    /// No contact within the timeout after the table ended: holding.
    LandingTimeout,
    /// Now standing (after a stop or a landing timeout).
    Stopped,
}

/// Why a start was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RefuseReason {
    /// No verified table for that gait.
    NoTable,
    /// The joints are not in the table's start posture.
    NotInStartPosture,
    /// A step is in progress, a hold is active, or new steps are blocked.
    Busy,
}

/// What the sequencer measured this tick (calibrated, NaN where unknown).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensed {
    /// Joint angles, joint order, rad.
    pub joints_rad: [f32; JOINTS],
    /// Foot forces (0 left, 1 right), N.
    pub feet_n: [f32; 2],
    /// Crutch forces (0 left, 1 right), N.
    pub crutches_n: [f32; 2],
    /// Ankle dorsiflexion (0 left, 1 right), rad.
    pub ankles_rad: [f32; 2],
}

/// Gait execution state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sequencer<'t> {
    cfg: SequencerConfig,
    phase: Phase,
    gait: Gait,
    /// The slot of the table being played (or last played).
    slot: usize,
    stance: Side,
    stop_requested: bool,
    new_steps_blocked: bool,
    /// Reference at the previous tick (for rates and blends).
    reference: [f32; JOINTS],
    /// Start and end of the current blend (transfer or hold ramp).
    blend_from: [f32; JOINTS],
    blend_to: [f32; JOINTS],
    /// With a model, the weight transfer is planned in double support (see
    /// [`Sequencer::with_model`]); without, it blends joint angles.
    model: Option<BodyModel<f32>>,
    transfer: Option<TransferPlan>,
    /// The swing foot's toe at the start of the table being played (stance
    /// foot's flat frame), m.
    swing_start_m: [f32; 2],
    /// When the table's swing foot was planned fully lifted in the present
    /// swing, s (landing is looked for only after that).
    lifted_at_s: Option<f32>,
    /// How long the swing foot has felt the ground in the landing window
    /// without a break, s (`SequencerConfig::landing_confirm_s`).
    contact_s: f32,
    /// The present swing has reached its landing window (set each swing
    /// tick; a swing starts without it).
    in_landing_window: bool,
    /// The ankle plan of the last reference (kept through a safe hold).
    ankle_plan: [f32; 2],
    /// The table's stance-shank angle φ1 at the last tick of a swing, rad.
    swing_phi1: f32,
    /// A safe hold's set-down of the swing foot, when it struck in a swing.
    set_down: Option<SetDown>,
    /// The table being played (kept at hand: the tick reads it several
    /// times).
    table: Option<GaitTable<'t>>,
    /// The tables, and each slot's transfer end
    /// ([`transfer::transfer_targets`]): last, being large and read at
    /// most once a tick.
    tables: GaitTables<'t>,
    transfer_targets: [Option<[f32; 5]>; MAX_GAITS],
}

/// A swing foot being set down in a safe hold: from where its ankle was
/// when the hold struck, straight down, a point fixed in the world that
/// the swing leg's IK reaches from wherever the measured stance leg and
/// torso are, until the foot's sensor feels the ground.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SetDown {
    /// The leg that carries the body.
    stance: Side,
    /// The posture held (Φ, the stance shank as the table planned it).
    from: [f32; gait_core::LINKS],
    /// The hip and the swing ankle of `from` (stance foot's frame), m:
    /// worked out on the hold's first tick (the tick the fault struck has
    /// played a swing already, and has no room left for it).
    hip_and_ankle_m: Option<([f32; 2], [f32; 2])>,
    /// The swing hip and knee references (joint angles), rad: the IK's
    /// last answer, kept once the foot has found the ground.
    swing_rad: [f32; 2],
    /// The foot has found the ground (or its sensor cannot tell).
    done: bool,
}

impl SetDown {
    /// The set-down of the swing leg from the posture `held` (joint
    /// angles), its stance shank at `phi1`.
    fn from_hold(held: &[f32; JOINTS], phi1: f32, stance: Side) -> Option<Self> {
        let w = stance.other().hip();
        Some(Self {
            stance,
            from: crate::posture::phi_from_joints(held, phi1, stance),
            hip_and_ankle_m: None,
            swing_rad: [held.get(w).copied()?, held.get(w + 1).copied()?],
            done: false,
        })
    }
}

impl<'t> Sequencer<'t> {
    /// Starts standing, holding `posture` (normally the measured joints at
    /// power-up), with the left leg as stance.
    pub fn new(cfg: SequencerConfig, tables: GaitTables<'t>, posture: [f32; JOINTS]) -> Self {
        let mut s = Self {
            cfg,
            tables,
            phase: Phase::Standing,
            gait: Gait::Walk,
            slot: 0,
            table: None,
            stance: Side::Left,
            stop_requested: false,
            new_steps_blocked: false,
            reference: posture,
            blend_from: posture,
            blend_to: posture,
            model: None,
            transfer: None,
            transfer_targets: [None; MAX_GAITS],
            swing_start_m: [0.0; 2],
            lifted_at_s: None,
            in_landing_window: false,
            contact_s: 0.0,
            ankle_plan: [f32::NAN; 2],
            swing_phi1: f32::NAN,
            set_down: None,
        };
        s.restart_at(posture);
        s
    }

    /// Starts afresh at `posture` (as [`Sequencer::new`]), in place,
    /// keeping its tables, model and what was computed from them once (the
    /// controller's first tick holds the measured posture this way, within
    /// the tick's budget: nothing of the tables is copied).
    pub fn restart_at(&mut self, posture: [f32; JOINTS]) {
        let posture = posture.map(|v| if v.is_finite() { v } else { 0.0 });
        self.phase = Phase::Standing;
        self.gait = Gait::Walk;
        self.slot = 0;
        self.table = None;
        self.stance = Side::Left;
        self.stop_requested = false;
        self.new_steps_blocked = false;
        self.reference = posture;
        self.blend_from = posture;
        self.blend_to = posture;
        self.transfer = None;
        self.swing_start_m = [0.0; 2];
        self.lifted_at_s = None;
        self.in_landing_window = false;
        self.contact_s = 0.0;
        self.ankle_plan = [f32::NAN; 2];
        self.swing_phi1 = f32::NAN;
        self.set_down = None;
    }

    /// This sequencer started afresh at `posture` ([`Sequencer::restart_at`]
    /// on a copy).
    #[must_use]
    pub fn restarted_at(&self, posture: [f32; JOINTS]) -> Self {
        let mut s = *self;
        s.restart_at(posture);
        s
    }

    /// Plans each weight transfer in double support with this model's IK
    /// (the trailing foot stays planted while the stance shank, torso and
    /// knee choice move to the next start posture) instead of blending joint
    /// angles, which in double support would make the legs fight each other
    /// through the ground.
    #[must_use]
    pub fn with_model(mut self, model: BodyModel<f32>) -> Self {
        self.transfer_targets = transfer::transfer_targets(&model, &self.tables);
        self.model = Some(model);
        self
    }

    /// The swing foot's toe at the table's posture (stance foot's flat
    /// frame), m; `None` without a model or table.
    fn planned_swing_toe(&self, posture: Option<&Posture<f32>>) -> Option<[f32; 2]> {
        let model = self.model.as_ref()?;
        let posture = posture?;
        let foot = gait_core::foot::StanceFoot::for_model(model);
        Some(gait_core::playback::swing_toe_at(model, &foot, posture))
    }

    /// The ground search: `phi` (the table's last posture) with the swing
    /// ankle lowered by how far the search has gone `since_end_s` after the
    /// table's end (from [`SequencerConfig::ground_search_after_s`] on,
    /// eased in and out over [`SequencerConfig::ground_search_s`] to the
    /// full [`SequencerConfig::ground_search_depth_m`]); `phi` itself before
    /// then or without a model. A tread a few millimetres lower
    /// than planned, or a foot tracking a little high, left the foot
    /// hovering until the landing timed out, and the step stood on one leg
    /// (measured in noisy stair descents, docs/safety.md).
    fn searching_for_ground(
        &self,
        phi: &[f32; gait_core::LINKS],
        since_end_s: f32,
    ) -> [f32; gait_core::LINKS] {
        let Some(model) = self.model.as_ref() else {
            return *phi;
        };
        let c = self.cfg;
        let searching_s = since_end_s - c.ground_search_after_s;
        if !(searching_s.is_finite() && searching_s > 0.0) {
            return *phi;
        }
        let frac = if c.ground_search_s > 0.0 {
            searching_s / c.ground_search_s
        } else {
            1.0
        };
        let depth = c.ground_search_depth_m * smoothstep(frac);
        gait_core::reach::lower_swing_ankle(model, phi, depth, SEARCH_MIN_KNEE_FLEXION_RAD)
    }

    /// The other foot's share at the table's posture in the present swing
    /// (0 without a model: the foot is taken as lifted from the start, and
    /// the landing window counts from the swing's start).
    fn swing_share(&self, posture: Option<&Posture<f32>>) -> f32 {
        self.planned_swing_toe(posture).map_or(0.0, |p| {
            gait_core::playback::other_foot_share(p, self.swing_start_m)
        })
    }

    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The tables this sequencer plays.
    pub fn tables(&self) -> &GaitTables<'t> {
        &self.tables
    }

    /// The gait being played, or last played (walking before the first
    /// start).
    #[must_use]
    pub fn gait(&self) -> Gait {
        self.gait
    }

    /// `true` while a step is in progress (the swing or the weight transfer
    /// after it): no gait change, no new start.
    pub fn step_in_progress(&self) -> bool {
        matches!(self.phase, Phase::Swing { .. } | Phase::Transfer { .. })
    }

    /// The leg whose foot is in the air and moved by the sequencer: the
    /// swing leg in a swing, and in a safe hold that struck in one until
    /// the set-down has found the ground (its joints move a leg, not the
    /// body: the supervisor's response check takes its swing inertias).
    #[must_use]
    pub fn swing_leg(&self) -> Option<Side> {
        match (self.phase, self.set_down) {
            (Phase::Swing { stance, .. }, _) => Some(stance.other()),
            (Phase::SafeHold { .. }, Some(sd)) if !sd.done => Some(sd.stance.other()),
            _ => None,
        }
    }

    /// The swing leg once the table has it well in the air: lifted, and
    /// into the part of its time in the air where a contact would be the
    /// landing. Its foot has left the ground for certain (the trailing toe
    /// may still brush it earlier): the supervisor's stuck-ankle check.
    #[must_use]
    pub fn airborne_leg(&self) -> Option<Side> {
        match self.phase {
            Phase::Swing { stance, .. } if self.in_landing_window => Some(stance.other()),
            _ => None,
        }
    }

    /// `true` while a gait is running (waiting, swinging or transferring).
    pub fn walking(&self) -> bool {
        matches!(
            self.phase,
            Phase::WaitingReady { .. } | Phase::Swing { .. } | Phase::Transfer { .. }
        )
    }

    /// The current reference posture (joint order, rad).
    pub fn reference(&self) -> [f32; JOINTS] {
        self.reference
    }

    /// Asks for a start of `gait`. Accepted only when standing, with a
    /// verified table, from that table's start posture (either leg may be
    /// the stance leg: the one whose mapping matches is chosen).
    pub fn request_start(&mut self, selected: impl Selection, sensed: &Sensed) -> SeqEvent {
        if self.phase != Phase::Standing || self.new_steps_blocked {
            return SeqEvent::StartRefused(RefuseReason::Busy);
        }
        let Some((slot, table)) = selected
            .slot_in(&self.tables)
            .and_then(|i| Some((i, *self.tables.slot(i)?)))
        else {
            return SeqEvent::StartRefused(RefuseReason::NoTable);
        };
        let gait = gait_of_kind(table.kind());
        let first = table.first();
        let tol = self.cfg.start_tolerance_rad;
        for stance in [self.stance, self.stance.other()] {
            let start = joints_from_phi(&first, stance);
            let close = start
                .iter()
                .zip(&sensed.joints_rad)
                .all(|(a, b)| (a - b).abs() <= tol);
            if close {
                self.gait = gait;
                self.slot = slot;
                self.table = Some(table);
                self.stance = stance;
                self.stop_requested = false;
                self.begin_blend(start);
                self.phase = Phase::WaitingReady { stance };
                return SeqEvent::StartAccepted(gait, stance);
            }
        }
        SeqEvent::StartRefused(RefuseReason::NotInStartPosture)
    }

    /// Asks to stop at the end of the current step (or at once when only
    /// waiting for readiness).
    pub fn request_stop(&mut self) {
        self.stop_requested = true;
    }

    /// The supervisor's non-fatal reaction: finish the step, then hold; no
    /// new steps until a reset.
    pub fn block_new_steps(&mut self) {
        self.new_steps_blocked = true;
        self.stop_requested = true;
    }

    /// What a safe hold that strikes now does in a swing: `asked` (the
    /// faults' own [`InSwing`]), except late in a swing whose stance knee
    /// still has its drive and encoder (`braked`: the joints braked), where
    /// the step goes on to its landing. There the body is on its way onto
    /// the landing foot: stopping it asks the stance leg for more than its
    /// drives have until the pilot's arms take the load (0.15 s and more
    /// after the hold), and a foot held short of its tread may not reach
    /// the ground below; the stance knee is what lowers the body onto it
    /// (docs/safety.md, "Swing").
    #[must_use]
    pub fn in_swing_now(&self, asked: InSwing, braked: &[bool; JOINTS]) -> InSwing {
        let Phase::Swing { stance, t_s } = self.phase else {
            return asked;
        };
        let duration = self.table.as_ref().map_or(0.0, |tb| tb.duration_s());
        let slot = transfer::kind_index(self.gait);
        let after = self.cfg.lands_after.get(slot).copied().unwrap_or(1.0);
        let knee_works = !braked.get(stance.hip() + 1).copied().unwrap_or(true);
        if duration > 0.0 && t_s >= after * duration && knee_works {
            InSwing::LandFirst
        } else {
            asked
        }
    }

    /// The supervisor's fatal reaction: ramp to `measured` and hold; in a
    /// swing, first play the step to its landing if `in_swing` says so,
    /// otherwise set the swing foot down where it is while holding the
    /// rest ([`SequencerConfig::set_down_depth_m`]).
    pub fn enter_safe_hold(&mut self, measured: &[f32; JOINTS], in_swing: InSwing) {
        if matches!(self.phase, Phase::SafeHold { .. }) {
            return;
        }
        let swinging = match self.phase {
            Phase::Swing { stance, .. } => Some(stance),
            _ => None,
        };
        if swinging.is_some() && in_swing == InSwing::LandFirst {
            // A foot in the air is not a posture to hold: the step goes on
            // to its landing (sensed, or on the table's own timing when the
            // foot's sensor is lost), the sequencer stands there, and the
            // next call holds what it measures then.
            self.block_new_steps();
            return;
        }
        let target = pick_finite(measured, &self.reference);
        self.blend_from = self.reference;
        self.blend_to = target;
        self.phase = Phase::SafeHold { t_s: 0.0 };
        self.set_down = swinging
            .filter(|_| self.model.is_some() && in_swing == InSwing::HoldNow)
            .and_then(|stance| SetDown::from_hold(&target, self.swing_phi1, stance));
    }

    /// The hold after a restart (0x0603): the step the board was playing is
    /// lost, so which foot is up is read from the feet's sensors. With one
    /// foot carrying a contact and the other not, the loaded one is the
    /// stance leg (the feed-forward's model, too) and the other is set down
    /// as after a fault in a swing, the stance shank from its ankle's
    /// reading; otherwise a hold of `measured` as [`Sequencer::enter_safe_hold`].
    pub fn enter_safe_hold_after_restart(&mut self, measured: &[f32; JOINTS], sensed: &Sensed) {
        if matches!(self.phase, Phase::SafeHold { .. }) {
            return;
        }
        self.enter_safe_hold(measured, InSwing::HoldNow);
        let contact = self.cfg.landing_contact_n;
        let [left, right] = sensed.feet_n;
        let carries = |f: f32| f >= contact;
        let lifted = |f: f32| f.is_finite() && f < contact;
        let stance = if carries(left) && lifted(right) {
            Side::Left
        } else if carries(right) && lifted(left) {
            Side::Right
        } else {
            return;
        };
        let phi1 = sensed
            .ankles_rad
            .get(stance.ankle())
            .copied()
            .unwrap_or(f32::NAN);
        if self.model.is_none() || !phi1.is_finite() {
            return;
        }
        if let Some(sd) = SetDown::from_hold(&self.blend_to, phi1, stance) {
            self.stance = stance;
            self.set_down = Some(sd);
        }
    }

    /// The set-down `t_s` into the hold: `held` (the hold's ramp) with the
    /// swing hip and knee placing the ankle the eased depth below where it
    /// was in the posture held, while the swing foot's sensor reads less
    /// than a contact; from the first contact (or a sensor that cannot
    /// tell) on, where they were then. `held` itself without a set-down.
    fn set_down(&mut self, sensed: &Sensed, t_s: f32, dt_s: f32, held: &mut [f32; JOINTS]) {
        let cfg = self.cfg;
        let (Some(mut sd), Some(model)) = (self.set_down, self.model.as_ref()) else {
            return;
        };
        let foot = sensed
            .feet_n
            .get(sd.stance.other().foot())
            .copied()
            .unwrap_or(f32::NAN);
        if foot >= cfg.landing_contact_n || !foot.is_finite() {
            sd.done = true;
        }
        if !sd.done && sd.hip_and_ankle_m.is_none() {
            let [_, hip, _, _, ankle] = gait_core::kinematics::forward_kinematics(model, &sd.from);
            if hip.iter().chain(&ankle).all(|v| v.is_finite()) {
                sd.hip_and_ankle_m = Some((hip, ankle));
            } else {
                sd.done = true;
            }
        } else if let (false, Some((hip_m, start_m))) = (sd.done, sd.hip_and_ankle_m) {
            let frac = if cfg.set_down_s > 0.0 {
                t_s / cfg.set_down_s
            } else {
                1.0
            };
            let depth = cfg.set_down_depth_m * smoothstep(frac);
            let target = [start_m[0], start_m[1] - depth];
            let placed = gait_core::reach::place_swing_ankle_from(
                model,
                &sd.from,
                hip_m,
                target,
                SEARCH_MIN_KNEE_FLEXION_RAD,
            );
            let joints = joints_from_phi(&placed, sd.stance);
            let w = sd.stance.other().hip();
            if let (Some(&hip), Some(&knee)) = (joints.get(w), joints.get(w + 1)) {
                if hip.is_finite() && knee.is_finite() {
                    // The IK's answer, at most the set-down's joint speed
                    // away: near a straight knee a steady fall of the
                    // ankle asks the knee for any speed.
                    let step = (cfg.set_down_joint_speed_rad_s * dt_s).max(0.0);
                    for (now, to) in sd.swing_rad.iter_mut().zip([hip, knee]) {
                        *now += (to - *now).clamp(-step, step);
                    }
                }
            }
        }
        let w = sd.stance.other().hip();
        if let Some(h) = held.get_mut(w) {
            *h = sd.swing_rad[0];
        }
        if let Some(k) = held.get_mut(w + 1) {
            *k = sd.swing_rad[1];
        }
        self.set_down = Some(sd);
    }

    /// A safe hold's set-down of the swing foot is under way (the foot has
    /// not yet found the ground).
    pub fn set_down_pending(&self) -> bool {
        matches!(self.phase, Phase::SafeHold { .. }) && self.set_down.is_some_and(|sd| !sd.done)
    }

    /// In a safe hold, holds joint `joint` at `angle_rad` from now on
    /// instead of where the hold found it: a joint braked while nothing
    /// told its angle has moved since, and its drive, back on, must hold
    /// it where it is, not pull the body back. Nothing outside a hold.
    pub fn hold_joint_at(&mut self, joint: usize, angle_rad: f32) {
        if !matches!(self.phase, Phase::SafeHold { .. }) || !angle_rad.is_finite() {
            return;
        }
        for posture in [
            &mut self.blend_from,
            &mut self.blend_to,
            &mut self.reference,
        ] {
            if let Some(a) = posture.get_mut(joint) {
                *a = angle_rad;
            }
        }
        if let Some(sd) = self.set_down.as_mut() {
            let w = sd.stance.other().hip();
            if let Some(offset) = joint.checked_sub(w) {
                if let Some(a) = sd.swing_rad.get_mut(offset) {
                    *a = angle_rad;
                }
            }
        }
    }

    /// While the motors are disabled the joints move freely: the reference
    /// follows the measured posture (so no tracking error builds up and
    /// nothing jumps when the motors come back after a reset).
    pub fn follow_measured(&mut self, measured: &[f32; JOINTS]) {
        let target = pick_finite(measured, &self.reference);
        self.reference = target;
        self.blend_from = target;
        self.blend_to = target;
        self.set_down = None;
        self.phase = Phase::SafeHold {
            t_s: self.cfg.hold_ramp_s.max(0.0),
        };
    }

    /// After a clinician reset: stand where the reference is, allow steps.
    pub fn reset_after_faults(&mut self) {
        self.new_steps_blocked = false;
        self.stop_requested = false;
        self.blend_to = self.reference;
        self.blend_from = self.reference;
        self.set_down = None;
        self.phase = Phase::Standing;
    }

    fn begin_blend(&mut self, to: [f32; JOINTS]) {
        self.blend_from = self.reference;
        self.blend_to = to;
    }

    /// Holds joint `i` (joint order) at `measured` from now on, in a hold
    /// (the supervisor's [`Verdict::rehold_joints`](crate::supervisor::Verdict)):
    /// its blend starts and ends there. Nothing outside a hold, or for a
    /// non-finite angle.
    pub fn rehold_joint(&mut self, i: usize, measured: f32) {
        if !matches!(self.phase, Phase::SafeHold { .. }) {
            return;
        }
        if !measured.is_finite() {
            return;
        }
        if let (Some(f), Some(t)) = (self.blend_from.get_mut(i), self.blend_to.get_mut(i)) {
            *f = measured;
            *t = measured;
        }
    }

    fn blended(&self, fraction: f32) -> [f32; JOINTS] {
        let s = smoothstep(fraction);
        let mut out = self.blend_from;
        for (o, &b) in out.iter_mut().zip(&self.blend_to) {
            *o += s * (b - *o);
        }
        out
    }

    /// One tick: advances the phase and returns the whole reference (one
    /// table interpolation). `selected`: the gait the clinician has
    /// selected, whose start posture standing plans the ankles for.
    pub fn update(
        &mut self,
        sensed: &Sensed,
        selected: impl Selection,
        dt_s: f32,
        events: &mut impl FnMut(SeqEvent),
    ) -> Reference {
        let cfg = self.cfg;
        // The table's Φ at the swing's time while it plays (stance, t, Φ).
        let mut swing: Option<(Side, f32, Option<Posture<f32>>)> = None;
        let mut other_share = Some(1.0);
        let next_reference = match self.phase {
            Phase::Standing => self.blend_to,
            Phase::WaitingReady { stance } => {
                if self.stop_requested {
                    self.phase = Phase::Standing;
                    events(SeqEvent::Stopped);
                    self.blend_to
                } else if self.ready(sensed, stance) {
                    self.phase = Phase::Swing { stance, t_s: 0.0 };
                    let start = self.table.as_ref().map(|tb| tb.at_time(0.0));
                    self.swing_start_m = self
                        .planned_swing_toe(start.map(|p| Posture::new(&p)).as_ref())
                        .unwrap_or([0.0; 2]);
                    self.lifted_at_s = None;
                    self.in_landing_window = false;
                    self.contact_s = 0.0;
                    events(SeqEvent::SwingStarted(self.gait, stance));
                    start.map_or(self.reference, |p| joints_from_phi(&p, stance))
                } else {
                    self.blend_to
                }
            }
            Phase::Swing { stance, t_s } => {
                let t = t_s + dt_s;
                let duration = self.table.as_ref().map_or(0.0, |tb| tb.duration_s());
                let swing_foot = sensed
                    .feet_n
                    .get(stance.other().foot())
                    .copied()
                    .unwrap_or(f32::NAN);
                // Past the table's end without a landing, the foot goes on
                // down looking for the ground.
                let phi_t = self
                    .tables
                    .get(self.gait)
                    .map(|tb| self.searching_for_ground(&tb.at_time(t), t - duration));
                let posture_t = phi_t.map(|p| Posture::new(&p));
                self.swing_phi1 = phi_t.map_or(f32::NAN, |p| p[0]);
                let share = self.swing_share(posture_t.as_ref());
                if self.lifted_at_s.is_none() && share <= 0.0 {
                    self.lifted_at_s = Some(t);
                }
                // Contact counts as the landing only once the table has
                // lifted the foot and played the given fraction of its time
                // in the air (earlier contact is a scuff).
                let in_window = self.lifted_at_s.is_some_and(|lift| {
                    t >= lift + cfg.landing_window_fraction * (duration - lift)
                });
                self.in_landing_window = in_window;
                // A foot whose sensor has failed (NaN) cannot report the
                // contact: the step ends on the table's own timing, where
                // the table has put the foot down, once the foot has had
                // the time to follow it there.
                let blind = !swing_foot.is_finite();
                // Never past the landing timeout (a NaN setting is the timeout).
                let settle = cfg.blind_landing_settle_s.min(cfg.landing_timeout_s);
                let blind_landed = blind && t >= duration + settle;
                // Contact counts once it has held `landing_confirm_s`: a
                // spike of a few ticks is not the ground.
                self.contact_s = if in_window && swing_foot >= cfg.landing_contact_n {
                    self.contact_s + dt_s
                } else {
                    0.0
                };
                let touched =
                    self.contact_s > 0.0 && self.contact_s >= cfg.landing_confirm_s - 0.5 * dt_s;
                let landed = in_window && (touched || blind_landed);
                other_share = Some(share);
                let reference = phi_t.map_or(self.reference, |p| joints_from_phi(&p, stance));
                if landed {
                    events(SeqEvent::Landed);
                    if self.stop_requested {
                        self.blend_from = reference;
                        self.blend_to = reference;
                        self.phase = Phase::Standing;
                        self.stance = stance.other();
                        events(SeqEvent::Stopped);
                    } else {
                        let new_stance = stance.other();
                        self.stance = new_stance;
                        self.blend_from = reference;
                        let table = self.table.as_ref().copied();
                        self.blend_to =
                            table.map_or(reference, |tb| joints_from_phi(&tb.first(), new_stance));
                        self.transfer = phi_t.and_then(|p| self.plan_transfer(&p, new_stance));
                        self.phase = Phase::Transfer {
                            stance: new_stance,
                            t_s: 0.0,
                        };
                    }
                } else if t > duration + cfg.landing_timeout_s {
                    events(SeqEvent::LandingTimeout);
                    self.blend_from = reference;
                    self.blend_to = reference;
                    self.phase = Phase::Standing;
                    events(SeqEvent::Stopped);
                } else {
                    self.phase = Phase::Swing { stance, t_s: t };
                    swing = Some((stance, t, posture_t));
                }
                reference
            }
            Phase::Transfer { stance, t_s } => {
                let t = t_s + dt_s;
                let frac = if cfg.transfer_s > 0.0 {
                    t / cfg.transfer_s
                } else {
                    1.0
                };
                if frac >= 1.0 {
                    if self.stop_requested {
                        self.phase = Phase::Standing;
                        events(SeqEvent::Stopped);
                    } else {
                        self.phase = Phase::WaitingReady { stance };
                    }
                    self.blend_from = self.blend_to;
                    self.blend_to
                } else {
                    self.phase = Phase::Transfer { stance, t_s: t };
                    self.transfer_reference(frac, stance)
                }
            }
            Phase::SafeHold { t_s } => {
                other_share = None;
                let t = t_s + dt_s;
                let frac = if cfg.hold_ramp_s > 0.0 {
                    t / cfg.hold_ramp_s
                } else {
                    1.0
                };
                self.phase = Phase::SafeHold {
                    t_s: t.min(cfg.hold_ramp_s.max(cfg.set_down_s).max(0.0) + 1.0),
                };
                let mut held = self.blended(frac.min(1.0));
                self.set_down(sensed, t, dt_s, &mut held);
                held
            }
        };
        let mut rate = [0.0; JOINTS];
        if dt_s > 0.0 {
            for ((r, &n), &o) in rate.iter_mut().zip(&next_reference).zip(&self.reference) {
                *r = (n - o) / dt_s;
            }
        }
        self.reference = next_reference;
        let table = self.table.as_ref();
        let motion = swing.and_then(|(_, t, phi)| table_motion(table?, t, phi?));
        self.ankle_plan = match self.phase {
            Phase::SafeHold { .. } => self.ankle_plan,
            // The first tick of a swing plans nothing yet (as before the
            // table is read).
            Phase::Swing { .. } => swing.map_or([f32::NAN; 2], |(s, t, phi)| {
                let phi1 = match (table, phi) {
                    (Some(tb), Some(p)) if t <= tb.duration_s() => p.phi[0],
                    (Some(tb), _) => tb.at_time(tb.duration_s())[0],
                    (None, _) => f32::NAN,
                };
                ankles_in_swing(s, phi1)
            }),
            Phase::Standing => ankles_in_start_posture(
                selected
                    .slot_in(&self.tables)
                    .and_then(|i| self.tables.slot(i)),
                self.stance,
            ),
            Phase::WaitingReady { .. } | Phase::Transfer { .. } => {
                ankles_in_start_posture(table, self.stance)
            }
        };
        Reference {
            angle_rad: next_reference,
            rate_rad_s: rate,
            stance: self.stance,
            motion,
            ankle_plan_rad: self.ankle_plan,
            other_foot_share: if matches!(self.phase, Phase::SafeHold { .. }) {
                None
            } else {
                other_share
            },
        }
    }

    fn ready(&self, sensed: &Sensed, stance: Side) -> bool {
        let c = self.cfg;
        let crutches = sensed.crutches_n.iter().all(|&f| f >= c.crutch_ready_n);
        // A NaN (faulted sensor) makes the sum NaN: never ready.
        let [left, right] = sensed.feet_n;
        let foot = left + right >= c.feet_ready_n;
        let planned = self.table.as_ref().map(|t| t.first()[0]);
        let ankle = match (planned, sensed.ankles_rad.get(stance.ankle())) {
            (Some(p), Some(&a)) => (a - p).abs() <= c.start_ankle_tolerance_rad,
            _ => false,
        };
        crutches && foot && ankle
    }
}

/// 3s² − 2s³ on [0, 1]: zero velocity at both ends of a blend.
fn smoothstep(x: f32) -> f32 {
    let s = if x.is_finite() {
        x.clamp(0.0, 1.0)
    } else {
        1.0
    };
    s * s * (3.0 - 2.0 * s)
}

fn pick_finite(a: &[f32; JOINTS], fallback: &[f32; JOINTS]) -> [f32; JOINTS] {
    let mut out = *fallback;
    for (o, &v) in out.iter_mut().zip(a) {
        if v.is_finite() {
            *o = v;
        }
    }
    out
}
