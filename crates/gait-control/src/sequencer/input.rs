//! What a tick hands the sequencer ([`SeqInput`]) and what the sequencer
//! tells the tick besides the reference ([`SeqStatus`], [`SeqEvents`]).
//!
//! The supervisor's verdict reaches the sequencer as [`Orders`], made from
//! the verdict by a pure function ([`Orders::from_verdict`]) and obeyed at
//! the start of the next tick's update: the commands of the tick a fault is
//! found in are already computed (the guard only decides whether they are
//! written), so the earliest reference a reaction can change is the next
//! tick's, which is where the orders take effect.

use crate::ahead::AheadSlot;
use crate::faults::{FaultCode, InSwing, Reaction};
use crate::operator::Gait;
use crate::posture::{JOINTS, Side};
use crate::replan::ReplanResult;
use crate::supervisor::Verdict;

use super::{Phase, SequencerConfig};

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

/// The operator's word this tick (the clinician's reset once granted).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeqRequest<S> {
    /// Start the selected gait (standing, in its start posture).
    Start(S),
    /// Stop at the end of the current step (at once when only waiting).
    StopAfterStep,
    /// A clinician reset was granted: stand where the reference is, allow
    /// steps again.
    ResetAfterFaults,
}

/// Everything one tick gives the sequencer.
#[derive(Clone, Copy, Debug)]
pub struct SeqInput<'a, S> {
    /// This tick's readings.
    pub sensed: &'a Sensed,
    /// The clinician's selection (standing plans the ankles for its start
    /// posture).
    pub selected: S,
    /// The operator's request, if any.
    pub request: Option<SeqRequest<S>>,
    /// The last verdict's orders.
    pub orders: &'a Orders,
    /// The joints braked (by the last verdict, [`Verdict::braked_joints`]).
    pub braked: &'a [bool; JOINTS],
    /// A lost hip's or knee's angle the closed chain has just settled on
    /// (joint, rad): a hold keeps that joint there from now on instead of
    /// where it found it (a joint braked while nothing told its angle has
    /// moved since; its drive, back on, must hold it where it is).
    pub hold_joint_at: Option<(usize, f32)>,
    /// The controller's first tick: start afresh holding the measured
    /// posture.
    pub restart: bool,
    /// Tick period, s.
    pub dt_s: f32,
    /// Where the weight transfer and the swing ask the model task for their
    /// next tick's IK and share ([`crate::ahead`]); `None`: the sequencer
    /// works them out itself.
    pub ahead: Option<&'a AheadSlot>,
}

/// What a verdict asks of the sequencer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// Nothing.
    Carry,
    /// Finish the step, then hold; no new steps until a reset.
    FinishStepThenHold,
    /// Ramp to the measured posture and hold; in a swing, what the faults
    /// ask ([`InSwing`]), unless the swing is late enough to land first.
    SafeHold(InSwing),
    /// The hold after a restart or a refused bundle: which foot is up is
    /// read from the feet's sensors.
    HoldWhereFound,
    /// The motors are off: the reference follows the measured posture.
    FollowMeasured,
}

/// The last verdict's orders, with the readings of the tick it was given
/// in (the posture a hold holds is the one measured then).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orders {
    /// The e-stop struck in a swing with the drives on: hold now and set
    /// the swing foot down before the drives go off.
    pub estop_hold: bool,
    /// Joints to hold where they were measured
    /// ([`Verdict::rehold_joints`]).
    pub rehold: [bool; JOINTS],
    /// The reaction.
    pub order: Order,
    /// What the verdict's tick measured.
    pub measured: Measured,
}

/// What a hold needs of the readings of the verdict's tick (the crutches
/// left out: the controller's state stays under 4 KiB).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// Joint angles, joint order, rad: the posture a hold holds.
    pub joints_rad: [f32; JOINTS],
    /// Foot forces (0 left, 1 right), N.
    pub feet_n: [f32; 2],
    /// Ankle dorsiflexion (0 left, 1 right), rad.
    pub ankles_rad: [f32; 2],
}

impl Measured {
    /// Nothing known (every reading NaN).
    pub const UNKNOWN: Self = Self {
        joints_rad: [f32::NAN; JOINTS],
        feet_n: [f32::NAN; 2],
        ankles_rad: [f32::NAN; 2],
    };

    /// What a hold needs of `sensed`.
    #[must_use]
    pub const fn of(sensed: &Sensed) -> Self {
        Self {
            joints_rad: sensed.joints_rad,
            feet_n: sensed.feet_n,
            ankles_rad: sensed.ankles_rad,
        }
    }
}

impl Orders {
    /// No orders (before the first verdict).
    pub const NONE: Self = Self {
        estop_hold: false,
        rehold: [false; JOINTS],
        order: Order::Carry,
        measured: Measured::UNKNOWN,
    };

    /// The orders of `verdict`, given with `sensed` (`estop_hold`: the
    /// e-stop's set-down of a swing foot begins).
    #[must_use]
    pub fn from_verdict(verdict: &Verdict, estop_hold: bool, sensed: &Sensed) -> Self {
        let found_at_boot = verdict.latched.contains(FaultCode::RestartedAfterPanic)
            || verdict.latched.contains(FaultCode::BundleRefused);
        let order = match verdict.reaction {
            // The sequencer played the table itself when it found it.
            Reaction::None | Reaction::PlayTable => Order::Carry,
            Reaction::FinishStepThenHold => Order::FinishStepThenHold,
            Reaction::SafeHold if found_at_boot => Order::HoldWhereFound,
            Reaction::SafeHold => Order::SafeHold(verdict.latched.in_swing()),
            Reaction::DisableMotors => Order::FollowMeasured,
        };
        Self {
            estop_hold,
            rehold: verdict.rehold_joints,
            order,
            measured: Measured::of(sensed),
        }
    }
}

/// Where gait execution is, as the tick needs to know it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeqStatus {
    /// The phase.
    pub phase: Phase,
    /// The gait being played, or last played.
    pub gait: Gait,
    /// The leg whose foot is in the air and moved by the sequencer: the
    /// swing leg in a swing, and in a safe hold that struck in one until
    /// the set-down has found the ground (its joints move a leg, not the
    /// body: the supervisor's response check takes its swing inertias).
    pub swing_leg: Option<Side>,
    /// The swing leg once the table has it well in the air: lifted, and
    /// into the part of its time in the air where a contact would be the
    /// landing (the supervisor's stuck-ankle check).
    pub airborne_leg: Option<Side>,
    /// From when in the present swing a safe hold lands the step first, s
    /// (`SequencerConfig::lands_after` of the table's duration; infinite
    /// outside a swing).
    pub lands_first_from_s: f32,
}

impl SeqStatus {
    /// Standing, before the first tick.
    pub const STANDING: Self = Self {
        phase: Phase::Standing,
        gait: Gait::Walk,
        swing_leg: None,
        airborne_leg: None,
        lands_first_from_s: f32::INFINITY,
    };

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
        let knee_works = !braked.get(stance.hip() + 1).copied().unwrap_or(true);
        if t_s >= self.lands_first_from_s && knee_works {
            InSwing::LandFirst
        } else {
            asked
        }
    }

    /// This status once the sequencer has obeyed `orders` (at the start of
    /// its next update): what the tick whose verdict gave them reports,
    /// and what the operator and the closed chain see until that update.
    #[must_use]
    pub fn obeying(&self, orders: &Orders, braked: &[bool; JOINTS], cfg: &SequencerConfig) -> Self {
        let held = |swing_leg: Option<Side>| Self {
            phase: Phase::SafeHold { t_s: 0.0 },
            swing_leg,
            airborne_leg: None,
            ..*self
        };
        let swing_leg = if self.swinging() {
            self.swing_leg
        } else {
            None
        };
        let mut now = *self;
        if orders.estop_hold && !matches!(now.phase, Phase::SafeHold { .. }) {
            now = held(swing_leg);
        }
        match orders.order {
            Order::Carry | Order::FinishStepThenHold => now,
            _ if matches!(now.phase, Phase::SafeHold { .. })
                && orders.order != Order::FollowMeasured =>
            {
                now
            }
            Order::SafeHold(asked) => match self.in_swing_now(asked, braked) {
                InSwing::LandFirst if self.swinging() => now,
                InSwing::HoldNow => held(swing_leg),
                _ => held(None),
            },
            Order::HoldWhereFound => {
                held(restart_stance(&orders.measured, cfg.landing_contact_n).map(Side::other))
            }
            Order::FollowMeasured => Self {
                phase: Phase::SafeHold {
                    t_s: cfg.hold_ramp_s.max(0.0),
                },
                swing_leg: None,
                airborne_leg: None,
                ..now
            },
        }
    }

    /// A gait is running (waiting, swinging or transferring).
    #[must_use]
    pub const fn walking(&self) -> bool {
        matches!(
            self.phase,
            Phase::WaitingReady { .. } | Phase::Swing { .. } | Phase::Transfer { .. }
        )
    }

    /// A step is in progress (the swing or the weight transfer after it):
    /// no gait change, no new start.
    #[must_use]
    pub const fn step_in_progress(&self) -> bool {
        matches!(self.phase, Phase::Swing { .. } | Phase::Transfer { .. })
    }

    /// Standing or holding: no step under way, none waiting.
    #[must_use]
    pub const fn at_rest(&self) -> bool {
        matches!(self.phase, Phase::Standing | Phase::SafeHold { .. })
    }

    /// Playing a swing.
    #[must_use]
    pub const fn swinging(&self) -> bool {
        matches!(self.phase, Phase::Swing { .. })
    }

    /// A safe hold's set-down of the swing foot is under way.
    #[must_use]
    pub const fn set_down_pending(&self) -> bool {
        matches!(self.phase, Phase::SafeHold { .. }) && self.swing_leg.is_some()
    }
}

/// The stance leg of a hold after a restart, from the feet's sensors:
/// the loaded foot's when the other reads less than a contact (`None`
/// when both or neither carry, or a sensor cannot tell), and its stance
/// shank's lean read at its ankle.
pub(super) fn restart_stance(sensed: &Measured, contact_n: f32) -> Option<Side> {
    let [left, right] = sensed.feet_n;
    let carries = |f: f32| f >= contact_n;
    let lifted = |f: f32| f.is_finite() && f < contact_n;
    let stance = if carries(left) && lifted(right) {
        Side::Left
    } else if carries(right) && lifted(left) {
        Side::Right
    } else {
        return None;
    };
    let phi1 = sensed.ankles_rad.get(stance.ankle()).copied();
    phi1.is_some_and(f32::is_finite).then_some(stance)
}

/// Something that happened this tick (for the log and the crutch metric).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SeqEvent {
    /// A start was accepted: now waiting for readiness.
    StartAccepted(Gait, Side),
    /// A start was refused.
    StartRefused(RefuseReason),
    /// What came of the re-plan of the step about to start (with a
    /// re-planner).
    Replan(ReplanResult),
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

/// Most events one tick can have: a start's answer, then a landing and
/// the stop after it.
const MAX_EVENTS: usize = 3;

/// The events of one tick, in order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SeqEvents {
    events: [Option<SeqEvent>; MAX_EVENTS],
}

impl SeqEvents {
    pub(super) fn push(&mut self, e: SeqEvent) {
        if let Some(slot) = self.events.iter_mut().find(|s| s.is_none()) {
            *slot = Some(e);
        }
    }

    /// The events, in order.
    pub fn iter(&self) -> impl Iterator<Item = SeqEvent> + '_ {
        self.events.iter().flatten().copied()
    }

    /// Whether `e` happened this tick.
    #[must_use]
    pub fn contains(&self, e: &SeqEvent) -> bool {
        self.events.iter().flatten().any(|x| x == e)
    }
}
