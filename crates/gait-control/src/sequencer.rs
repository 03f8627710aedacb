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
mod hold;
mod input;
mod level;
mod start;
mod step;
mod swing;
mod tables;
mod transfer;

use gait_core::BodyModel;

use crate::ahead::AheadSlot;
use crate::operator::{Gait, MAX_GAITS};
use crate::posture::{JOINTS, Side};
pub use crate::reference::Reference;
use crate::reference::{ankles_in_start_posture, ankles_in_swing, table_motion};
use crate::replan::{ReplanConfig, ReplanSlot};
pub use config::SequencerConfig;
use gait_core::tables::GaitTable;
use hold::SetDown;
pub use input::{
    Measured, Order, Orders, RefuseReason, Sensed, SeqEvent, SeqEvents, SeqInput, SeqRequest,
    SeqStatus,
};
pub use step::StepTable;
pub(crate) use swing::SEARCH_MIN_KNEE_FLEXION_RAD;
use swing::SwingState;
pub use tables::{GaitTables, Selection, gait_of_kind};
use transfer::TransferPlan;
pub(crate) use transfer::transfer_params;

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

/// Gait execution state. The phases' own state lives in their modules
/// (`start`, `swing`, `transfer`, `hold`); one call a tick,
/// [`Sequencer::update`], drives them all.
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
    /// The present swing's landing detection.
    swing: SwingState,
    /// The ankle plan of the last reference (kept through a safe hold).
    ankle_plan: [f32; 2],
    /// A safe hold's set-down of the swing foot, when it struck in a swing.
    set_down: Option<SetDown>,
    /// How far a safe hold has turned the torso back, rad
    /// ([`Sequencer::level_torso`]).
    level_rad: f32,
    /// A joint is braked (the last verdict's): the hold's levelling then
    /// never turns the torso back past the pitch it had when one first was.
    any_braked: bool,
    /// The torso's pitch φ3 on the hold's first tick with a joint braked
    /// (that could tell), rad.
    torso_at_brake: f32,
    /// The selected table (kept at hand: the tick reads it several
    /// times).
    table: Option<GaitTable<'t>>,
    /// The stance-hip residual limit of the step played last, N·m: its
    /// table's, NaN for none or a re-planned step (read once a tick by the
    /// supervisor's facts, so worked out when the swing starts).
    stance_hip_residual_nm: f32,
    /// The step a swing plays: that table's, or its re-planned version.
    step: Option<StepTable<'t>>,
    /// The idle-time re-planner's slot and settings, where one runs.
    replanner: Option<(&'t ReplanSlot, ReplanConfig)>,
    /// Ticks since the re-plan of the step about to start was asked for,
    /// and the stance ankle it was asked for, rad.
    replan_wait: Option<u16>,
    replan_from: f32,
    /// The tables, and each slot's transfer end
    /// ([`transfer::transfer_targets`]): last, being large and read at
    /// most once a tick.
    tables: GaitTables<'t>,
    transfer_targets: [Option<[f32; 5]>; MAX_GAITS],
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
            stance_hip_residual_nm: f32::NAN,
            step: None,
            replanner: None,
            replan_wait: None,
            replan_from: f32::NAN,
            stance: Side::Left,
            stop_requested: false,
            new_steps_blocked: false,
            reference: posture,
            blend_from: posture,
            blend_to: posture,
            model: None,
            transfer: None,
            transfer_targets: [None; MAX_GAITS],
            swing: SwingState::START,
            ankle_plan: [f32::NAN; 2],
            set_down: None,
            level_rad: 0.0,
            any_braked: false,
            torso_at_brake: f32::NAN,
        };
        s.restart_at(posture);
        s
    }

    /// Starts afresh at `posture` (as [`Sequencer::new`]), in place,
    /// keeping its tables, model and what was computed from them once (the
    /// controller's first tick holds the measured posture this way, within
    /// the tick's budget: nothing of the tables is copied).
    fn restart_at(&mut self, posture: [f32; JOINTS]) {
        let posture = posture.map(|v| if v.is_finite() { v } else { 0.0 });
        self.phase = Phase::Standing;
        self.gait = Gait::Walk;
        self.slot = 0;
        self.table = None;
        self.stance_hip_residual_nm = f32::NAN;
        self.step = None;
        self.withdraw_replan();
        self.stance = Side::Left;
        self.stop_requested = false;
        self.new_steps_blocked = false;
        self.reference = posture;
        self.blend_from = posture;
        self.blend_to = posture;
        self.transfer = None;
        self.swing = SwingState::START;
        self.ankle_plan = [f32::NAN; 2];
        self.set_down = None;
        self.level_rad = 0.0;
    }

    /// This sequencer started afresh at `posture` (as [`Sequencer::new`]
    /// with its tables and model).
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

    /// Adapts each step to where the pilot's stance ankle is, through the
    /// re-planner that `slot` is shared with ([`crate::replan`]): before a
    /// swing it asks for the step from the measured ankle and plays the
    /// answer, or the table when there is none in time.
    #[must_use]
    pub fn with_replanner(mut self, slot: &'t ReplanSlot, cfg: ReplanConfig) -> Self {
        self.replanner = Some((slot, cfg));
        self
    }

    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The tables this sequencer plays.
    pub fn tables(&self) -> &GaitTables<'t> {
        &self.tables
    }

    /// Where its re-planned steps are, with a re-planner.
    pub fn replan_slot(&self) -> Option<&'t ReplanSlot> {
        self.replanner.map(|(slot, _)| slot)
    }

    /// The gait being played, or last played (walking before the first
    /// start).
    #[must_use]
    pub fn gait(&self) -> Gait {
        self.gait
    }

    /// The torque-residual limit the table of the present (or last) swing
    /// sets for its stance hip, N·m (NaN: none, or a re-planned step; the
    /// supervisor's 0x0404,
    /// [`crate::supervisor::ResponseCheck::stance_hip_limit_nm`]).
    #[must_use]
    pub fn stance_hip_residual_nm(&self) -> f32 {
        self.stance_hip_residual_nm
    }

    /// The current reference posture (joint order, rad).
    pub fn reference(&self) -> [f32; JOINTS] {
        self.reference
    }

    /// Where gait execution is now.
    #[must_use]
    pub fn status(&self) -> SeqStatus {
        SeqStatus {
            phase: self.phase,
            gait: self.gait,
            swing_leg: self.swing_leg(),
            airborne_leg: self.airborne_leg(),
            lands_first_from_s: if matches!(self.phase, Phase::Swing { .. }) {
                self.swing.lands_first_from_s
            } else {
                f32::INFINITY
            },
        }
    }

    fn swing_leg(&self) -> Option<Side> {
        match (self.phase, self.set_down) {
            (Phase::Swing { stance, .. }, _) => Some(stance.other()),
            (Phase::SafeHold { .. }, Some(sd)) if !sd.done => Some(sd.stance.other()),
            _ => None,
        }
    }

    fn airborne_leg(&self) -> Option<Side> {
        match self.phase {
            Phase::Swing { stance, .. } if self.swing.in_landing_window => Some(stance.other()),
            _ => None,
        }
    }

    /// The one call of a tick: obeys the last verdict's orders, then the
    /// closed chain's settled angle, the first tick's restart and the
    /// operator's request, in that order; then advances the phase and
    /// returns the whole reference (one table interpolation) with the
    /// status and the events of the tick.
    pub fn update<S: Selection>(&mut self, input: &SeqInput<'_, S>) -> Reference {
        let mut events = SeqEvents::default();
        self.obey(input.orders, input.braked);
        self.any_braked = input.braked.iter().any(|&b| b);
        if let Some((joint, angle)) = input.hold_joint_at {
            self.hold_joint_at(joint, angle);
        }
        if input.restart {
            self.restart_at(input.sensed.joints_rad);
        }
        match input.request {
            Some(SeqRequest::Start(selected)) => {
                events.push(self.request_start(selected, input.sensed));
            }
            Some(SeqRequest::StopAfterStep) => self.stop_requested = true,
            Some(SeqRequest::ResetAfterFaults) => self.reset_after_faults(),
            None => {}
        }
        let (next_reference, swing, other_share) =
            self.advance(input.sensed, input.dt_s, input.ahead, &mut events);
        self.reference_of(
            next_reference,
            swing,
            other_share,
            input.selected,
            input.dt_s,
            events,
        )
    }

    /// The phase's tick: the reference angles, the table's posture while a
    /// swing plays it, and the other foot's share.
    #[inline(always)]
    fn advance(
        &mut self,
        sensed: &Sensed,
        dt_s: f32,
        ahead: Option<&AheadSlot>,
        events: &mut SeqEvents,
    ) -> ([f32; JOINTS], Option<swing::Playing>, Option<f32>) {
        // The table's Φ at the swing's time while it plays (stance, t, Φ).
        let mut swing = None;
        let mut other_share = Some(1.0);
        let next_reference = match self.phase {
            Phase::Standing => self.blend_to,
            Phase::WaitingReady { stance } => self.wait_ready(sensed, stance, dt_s, ahead, events),
            Phase::Swing { stance, t_s } => {
                let (reference, playing, share) =
                    self.swing_tick(sensed, stance, t_s, dt_s, ahead, events);
                if let (Phase::Transfer { .. }, Some(slot)) = (self.phase, ahead) {
                    self.ask_transfer_start(slot);
                }
                swing = playing;
                other_share = Some(share);
                reference
            }
            Phase::Transfer { stance, t_s } => self.transfer_tick(stance, t_s, dt_s, ahead, events),
            Phase::SafeHold { t_s } => {
                other_share = None;
                self.hold_tick(sensed, t_s, dt_s, ahead)
            }
        };
        (next_reference, swing, other_share)
    }

    /// The whole reference of the tick: `next_reference` with its rates,
    /// the table's motion while a swing plays it, the ankle plan.
    #[inline(always)]
    fn reference_of(
        &mut self,
        next_reference: [f32; JOINTS],
        swing: Option<swing::Playing>,
        other_share: Option<f32>,
        selected: impl Selection,
        dt_s: f32,
        events: SeqEvents,
    ) -> Reference {
        let mut rate = [0.0; JOINTS];
        if dt_s > 0.0 {
            for ((r, &n), &o) in rate.iter_mut().zip(&next_reference).zip(&self.reference) {
                *r = (n - o) / dt_s;
            }
        }
        self.reference = next_reference;
        let step = self.step.as_ref();
        let motion = swing.and_then(|(_, t, phi, ahead)| match ahead {
            Some(known) => known,
            None => table_motion(step?, t, phi?),
        });
        self.ankle_plan = match self.phase {
            Phase::SafeHold { .. } => self.ankle_plan,
            // The first tick of a swing plans nothing yet (as before the
            // table is read).
            Phase::Swing { .. } => swing.map_or([f32::NAN; 2], |(s, t, phi, _)| {
                let phi1 = match (step, phi) {
                    (Some(tb), Some(p)) if t <= tb.duration_s() => p[0],
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
                ankles_in_start_posture(self.table.as_ref(), self.stance)
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
            status: self.status(),
            events,
        }
    }

    fn begin_blend(&mut self, to: [f32; JOINTS]) {
        self.blend_from = self.reference;
        self.blend_to = to;
    }

    fn blended(&self, fraction: f32) -> [f32; JOINTS] {
        let s = smoothstep(fraction);
        let mut out = self.blend_from;
        for (o, &b) in out.iter_mut().zip(&self.blend_to) {
            *o += s * (b - *o);
        }
        out
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
