//! Fault codes, their reactions, and a fixed-size set of them.
//!
//! One [`FaultCode`] per row of the fault table in `docs/safety.md`, each
//! declared once (one row of `fault_table!` below: code, name, reaction,
//! detection bound, reset rule; `tests/integration/fault_table.rs` checks that the
//! doc agrees). The numeric codes are stable (they appear in logs and
//! service reports): the high byte is the group, the low byte the fault
//! within the group.
//!
//! | group | what |
//! |---|---|
//! | `0x01xx` | joint motion (position, velocity, tracking) |
//! | `0x02xx` | angle encoders |
//! | `0x03xx` | force sensors |
//! | `0x04xx` | motor outputs |
//! | `0x05xx` | operator inputs (e-stop, buttons) |
//! | `0x06xx` | the controller itself (timing, values it computed, flash data, the re-planner) |
//! | `0x07xx` | the pilot |

mod set;

pub use set::FaultSet;

/// What the controller must do about the latched faults, least severe
/// first (so `max` over a set of reactions is the one to apply).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reaction {
    /// Nothing latched: carry on.
    #[default]
    None,
    /// Only for the re-planner's faults: the step about to start plays its
    /// verified flash table instead of the re-planned samples, as it would
    /// without a re-planner. The sequencer does so in the tick that finds
    /// the fault, so the fault is logged, not latched: the steps go on and
    /// nothing needs a reset.
    PlayTable,
    /// Warning class: let the current step finish, then hold the standing
    /// posture; refuse to start another step until a reset.
    FinishStepThenHold,
    /// Fatal: at once, ramp to a position hold of the current posture
    /// (motors stay powered: a limp exoskeleton drops its pilot); in a
    /// swing, first to the landing where the faults allow ([`InSwing`]).
    SafeHold,
    /// Only for the emergency stop (pressed, or its input lost): disable
    /// every motor output now, their dynamic brakes holding the joints; in
    /// a swing once the swing foot is set down (at most
    /// `SequencerConfig::set_down_s`: a stop of category 1, the
    /// controller's `estop` module).
    DisableMotors,
}

/// Declares the fault table once: one row per fault, in bit order of
/// [`FaultSet`] (row *i* is bit *i*, `FaultCode::ALL[i]`). From the rows it
/// generates [`FaultCode`] (variants, docs, codes), [`FaultCode::COUNT`],
/// [`FaultCode::ALL`], [`FaultCode::index`], [`FaultCode::reaction`],
/// [`FaultCode::name`], [`FaultCode::detection_bound`], [`FaultCode::brakes_joint`],
/// [`FaultCode::held_in_place_first`], [`FaultCode::loses_angle`] and
/// [`FaultCode::reset_rule`].
macro_rules! fault_table {
    ($(
        $(#[$meta:meta])*
        $variant:ident = $code:literal {
            name: $name:literal,
            reaction: $reaction:path,
            detection_bound: $bound:literal,
            reset_allowed_when: $reset:literal
            $(, in_swing: $swing:path)?
            $(, brakes_joint: $brakes:literal)?
            $(, held_in_place_first: $held:literal)?
            $(, loses_angle: $lost:literal)? $(,)?
        }
    ),+ $(,)?) => {
        /// One fault of the fault table. `#[repr(u16)]`: the discriminant is
        /// the stable numeric code ([`FaultCode::code`]). Variants are in bit
        /// order of [`FaultSet`], not in code order.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        #[repr(u16)]
        pub enum FaultCode {
            $(
                $(#[$meta])*
                $variant = $code,
            )+
        }

        impl FaultCode {
            /// Number of fault codes.
            pub const COUNT: usize = [$(Self::$variant),+].len();

            /// Every fault code, in bit order of [`FaultSet`].
            pub const ALL: [Self; Self::COUNT] = [$(Self::$variant),+];

            /// Position in [`FaultCode::ALL`], i.e. the bit in a [`FaultSet`].
            #[must_use]
            pub const fn index(self) -> u8 {
                // The rows again, numbered 0, 1, 2, … in the order written.
                enum Row {
                    $($variant),+
                }
                match self {
                    $(Self::$variant => Row::$variant as u8),+
                }
            }

            /// The reaction this fault demands while it is latched.
            #[must_use]
            pub const fn reaction(self) -> Reaction {
                match self {
                    $(Self::$variant => $reaction),+
                }
            }

            /// Short name for logs and the service tool.
            #[must_use]
            pub const fn name(self) -> &'static str {
                match self {
                    $(Self::$variant => $name),+
                }
            }

            /// How soon the fault is detected once its condition appears
            /// (the "detection bound" column of `docs/safety.md`).
            #[must_use]
            pub const fn detection_bound(self) -> &'static str {
                match self {
                    $(Self::$variant => $bound),+
                }
            }

            /// When a clinician reset may clear the latched fault (the
            /// "reset allowed when" column of `docs/safety.md`).
            #[must_use]
            pub const fn reset_rule(self) -> &'static str {
                match self {
                    $(Self::$variant => $reset),+
                }
            }

            /// What a safe hold for this fault does to a step in the air
            /// ([`InSwing::HoldNow`] unless the row says otherwise).
            #[must_use]
            pub const fn in_swing(self) -> InSwing {
                match self {
                    $(Self::$variant => fault_table!(@in_swing $($swing)?)),+
                }
            }

            /// Whether the fault disables the drive of the joint it is
            /// raised on, so that joint's dynamic brake holds it while the
            /// others hold the posture (`false` unless the row says so): a
            /// drive that does not give the torque commanded.
            #[must_use]
            pub const fn brakes_joint(self) -> bool {
                match self {
                    $(Self::$variant => fault_table!(@brakes $($brakes)?)),+
                }
            }

            /// Whether, raised on a joint while another joint is already
            /// braked (or blind), the fault first holds its joint where it
            /// is, its drive on, and brakes it only when raised there again
            /// (`false` unless the row says so): most likely the braked
            /// joint dragged it (`docs/safety.md`, "Reactions").
            #[must_use]
            pub const fn held_in_place_first(self) -> bool {
                match self {
                    $(Self::$variant => fault_table!(@held $($held)?)),+
                }
            }

            /// Whether the fault means the joint's own encoder no longer
            /// tells its angle (`false` unless the row says so). Such a
            /// joint is braked only while the closed chain of double
            /// support cannot give its angle instead
            /// ([`crate::posture::joint_through_closed_chain`]); the
            /// others stay braked until a reset.
            #[must_use]
            pub const fn loses_angle(self) -> bool {
                match self {
                    $(Self::$variant => fault_table!(@lost $($lost)?)),+
                }
            }
        }
    };
    (@held) => { false };
    (@held $held:literal) => { $held };
    (@lost) => { false };
    (@lost $lost:literal) => { $lost };
    (@brakes) => { false };
    (@brakes $brakes:literal) => { $brakes };
    (@in_swing) => { InSwing::HoldNow };
    (@in_swing $swing:path) => { $swing };
}

/// What a safe hold does when it strikes in a swing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InSwing {
    /// Hold the posture at once: the actuators or the motion itself are in
    /// doubt (a stuck or saturated motor, a joint past its envelope or off
    /// its reference, a frozen reading control still believes); the swing
    /// foot is set down onto the ground below it
    /// (`SequencerConfig::set_down_depth_m`). A second foot down is what
    /// lets a weak stance hip share the torso with the other hip: holding
    /// the foot in the air after a saturated drive dropped 63 pilots of the
    /// campaign's 406 slipping gears (seed 1), setting it down 39
    /// (`docs/safety.md`).
    HoldNow,
    /// Play the step on to its landing, then hold: the timing slipped, but
    /// the sensors, the table and the motors are good, and a foot in the
    /// air is no posture to hold. In the fault campaign (`docs/campaign.md`,
    /// seed 1) no pilot falls after overruns in 96 runs; holding at once,
    /// 7 did.
    /// Not for a lost joint encoder: landing on a joint run on the model's
    /// torque alone fell more often than holding at once (57 against 34
    /// falls in 400 encoder-fault runs). Every hold late in a stair
    /// descent's swing lands first while the stance knee works
    /// (`Sequencer::in_swing_now`).
    LandFirst,
}

// The fault table, each fault once. Rows are in bit order of `FaultSet`
// (`FaultSet::bits` goes into logs): append new faults at the end, never
// reorder (0x0105 came after 0x0602, so it is last). `docs/safety.md`'s
// table lists the same rows in code order; `tests/integration/fault_table.rs` checks
// that the two agree.
//
// Reactions: the passive ankles, sensors needed only to start a swing, and
// the buttons are not needed to hold, so the step finishes first; the
// e-stop disables the motors; the rest hold, with the joint braked where
// its own drive or encoder is lost (`brakes_joint`).
fault_table! {
    /// An actuated joint's angle is outside the supervisor's envelope
    /// (Table I limits with margins).
    JointPositionLimit = 0x0101 {
        name: "joint position limit",
        reaction: Reaction::SafeHold,
        detection_bound: "same tick (1)",
        reset_allowed_when: "the angle is back inside",
    },
    /// An actuated joint's filtered velocity exceeds its limit.
    JointVelocityLimit = 0x0102 {
        name: "joint velocity limit",
        reaction: Reaction::SafeHold,
        detection_bound: "after a step to speed v: ⌈ln(1 − L/v) / ln 0.8⌉ ticks for limit L, \
            ±1 for quantisation (7 ticks at 8 rad/s on a hip)",
        reset_allowed_when: "the filtered velocity is under the limit",
    },
    /// |angle − reference| above the limit for too long.
    TrackingError = 0x0103 {
        name: "tracking error",
        reaction: Reaction::SafeHold,
        detection_bound: "100 ticks",
        reset_allowed_when: "the error is back under the limit",
    },
    /// A passive ankle's angle is outside its envelope.
    AnklePositionLimit = 0x0104 {
        name: "ankle position limit",
        reaction: Reaction::FinishStepThenHold,
        detection_bound: "same tick (1)",
        reset_allowed_when: "the angle is back inside",
    },
    /// Joint encoder: too many bad frames, the last a bus error.
    EncoderBusError = 0x0201 {
        name: "encoder bus error",
        reaction: Reaction::SafeHold,
        detection_bound: "3 ticks when persistent; at the 3rd bad frame within 100 ms",
        reset_allowed_when: "< 3 bad frames in the last 100 ticks",
        brakes_joint: true,
        loses_angle: true,
    },
    /// Joint encoder: too many bad frames, the last a parity error.
    EncoderParity = 0x0202 {
        name: "encoder parity error",
        reaction: Reaction::SafeHold,
        detection_bound: "as 0x0201",
        reset_allowed_when: "as 0x0201",
        brakes_joint: true,
        loses_angle: true,
    },
    /// Joint encoder: too many bad frames, the last with the error flag.
    EncoderErrorFlag = 0x0203 {
        name: "encoder error flag",
        reaction: Reaction::SafeHold,
        detection_bound: "as 0x0201",
        reset_allowed_when: "as 0x0201",
        brakes_joint: true,
        loses_angle: true,
    },
    /// Joint encoder: raw counts unchanged over the ticks the joint is
    /// driven.
    EncoderFrozen = 0x0204 {
        name: "encoder frozen",
        reaction: Reaction::SafeHold,
        detection_bound: "100 driven ticks",
        reset_allowed_when: "the counts change, or the joint has been still 0.5 s",
        brakes_joint: true,
        loses_angle: true,
    },
    /// Joint encoder: too many bad frames, the last an impossible jump.
    EncoderJump = 0x0205 {
        name: "encoder impossible jump",
        reaction: Reaction::SafeHold,
        detection_bound: "3 ticks when persistent; a single jumping frame is dropped and tolerated",
        reset_allowed_when: "as 0x0201",
        in_swing: InSwing::LandFirst,
    },
    /// Joint encoder: a frame reported good carries an impossible value
    /// (raw counts beyond 14 bits, angle not finite or outside (−π, π]).
    EncoderInvalidValue = 0x0206 {
        name: "encoder invalid value",
        reaction: Reaction::SafeHold,
        detection_bound: "same tick (1)",
        reset_allowed_when: "the frame is valid and < 3 bad frames in 100 ticks",
    },
    /// Ankle encoder: any of the encoder faults above on a passive ankle,
    /// one stuck on its dorsiflexion stop with its foot in the air (only
    /// the ground holds an ankle there), or a swing's stance ankle whose
    /// counts do not follow the shank the plan turns; control then stops
    /// taking its frames until they move.
    AnkleEncoder = 0x0207 {
        name: "ankle encoder fault",
        reaction: Reaction::FinishStepThenHold,
        detection_bound: "3 ticks (window rule); 1 tick (invalid value); \
            100 ticks (stuck on the stop in the air); the plan's 0.05 rad \
            (a walk's swing: 0.1–0.25 s)",
        reset_allowed_when: "as for the joint encoders",
    },
    /// Force sensor: too many bad samples, the last a bus error.
    ForceBusError = 0x0301 {
        name: "force sensor bus error",
        reaction: Reaction::FinishStepThenHold,
        detection_bound: "3 ticks when persistent",
        reset_allowed_when: "< 3 bad samples in the last 100 ticks",
    },
    /// Force sensor: too many bad samples, the last an open circuit.
    ForceOpen = 0x0302 {
        name: "force sensor open",
        reaction: Reaction::FinishStepThenHold,
        detection_bound: "as 0x0301",
        reset_allowed_when: "as 0x0301",
    },
    /// Force sensor: too many bad samples, the last a short circuit.
    ForceShorted = 0x0303 {
        name: "force sensor shorted",
        reaction: Reaction::FinishStepThenHold,
        detection_bound: "as 0x0301",
        reset_allowed_when: "as 0x0301",
    },
    /// Force sensor: too many bad samples, the last out of the rated range
    /// (immediately if the value is not finite).
    ForceOutOfRange = 0x0304 {
        name: "force sensor out of range",
        reaction: Reaction::FinishStepThenHold,
        detection_bound: "3 ticks; 1 tick if not finite",
        reset_allowed_when: "as 0x0301, and the value is finite",
    },
    /// Motor command at or above its torque limit for too long.
    MotorSaturated = 0x0401 {
        name: "motor command saturated",
        reaction: Reaction::SafeHold,
        detection_bound: "200 ticks",
        reset_allowed_when: "the command is under the limit",
    },
    /// The motor driver's I²t model latched a thermal fault.
    MotorThermal = 0x0402 {
        name: "motor thermal fault",
        reaction: Reaction::SafeHold,
        detection_bound: "same tick (1)",
        reset_allowed_when: "the driver's flag is clear \
            (`Motor::reset_fault` accepted: cooled below warning)",
    },
    /// A motor output stage write failed (PWM or pin): that drive alone is
    /// disabled (its brake holds the joint), the others hold the posture.
    /// Measured on the campaign's PWM and direction-pin runs (seed 1, 186):
    /// falls 3 → 2 and stops crossed 30 → 19 against disabling every drive.
    MotorOutputStage = 0x0403 {
        name: "motor output stage fault",
        reaction: Reaction::SafeHold,
        detection_bound: "same tick (1)",
        reset_allowed_when: "the driver's flag is clear",
        brakes_joint: true,
    },
    /// The emergency-stop input is pressed.
    EStopPressed = 0x0501 {
        name: "emergency stop pressed",
        reaction: Reaction::DisableMotors,
        detection_bound: "same tick (1)",
        reset_allowed_when: "released",
    },
    /// The emergency-stop input could not be read (treated as pressed).
    EStopInputFault = 0x0502 {
        name: "emergency stop input fault",
        reaction: Reaction::DisableMotors,
        detection_bound: "same tick (1)",
        reset_allowed_when: "readable again",
    },
    /// A MODE/GO button input is faulty.
    ButtonInputFault = 0x0503 {
        name: "button input fault",
        reaction: Reaction::FinishStepThenHold,
        detection_bound: "same tick (1)",
        reset_allowed_when: "the fault is gone",
    },
    /// Too many missed tick deadlines within the window.
    DeadlineMissed = 0x0601 {
        name: "tick deadline missed",
        reaction: Reaction::SafeHold,
        detection_bound: "at the 3rd miss within 1 s",
        reset_allowed_when: "< 3 misses in the last 1000 ticks",
        in_swing: InSwing::LandFirst,
    },
    /// A value the controller computed is not usable: a reference angle,
    /// a motor command, applied torque or limit is not finite, or a limit
    /// is not positive.
    ControlValueInvalid = 0x0602 {
        name: "control value invalid",
        reaction: Reaction::SafeHold,
        detection_bound: "same tick (1)",
        reset_allowed_when: "every such value is valid",
    },
    /// The stance ankle rests on its dorsiflexion stop (the heel lifts:
    /// the toe rocker) while the plan keeps it well below: the pilot leans
    /// further forward than the gait was planned for.
    UnplannedHeelOff = 0x0105 {
        name: "unplanned heel-off",
        reaction: Reaction::FinishStepThenHold,
        detection_bound: "50 ticks",
        reset_allowed_when: "the ankle is off the stop or the plan reaches it",
    },
    /// The board restarted after a panic (the panic handler resets it and
    /// leaves a mark in RAM the reset keeps): whatever step was running is
    /// lost, so the controller starts in a hold of the posture it finds.
    RestartedAfterPanic = 0x0603 {
        name: "restarted after a panic",
        reaction: Reaction::SafeHold,
        detection_bound: "first tick after the restart (1)",
        reset_allowed_when: "a clinician resets in a safe posture",
    },
    /// A hip or knee does not move as its command and the model say it
    /// should: the torque reaching the joint is not the torque commanded
    /// (a drive stuck on an old set value, a weak drive, a slipping
    /// gearbox). The joint's drive is disabled, so its dynamic brake holds
    /// it, and the others hold the posture; raised while another joint is
    /// already braked, the joint is first held where it is with its drive.
    MotorResponse = 0x0404 {
        name: "motor not following its command",
        reaction: Reaction::SafeHold,
        detection_bound: "10 ticks over the limit; the residual's 3 Hz low-pass: a sudden torque \
            error of 125 N·m in about 170 ticks, 200 N·m in about 100",
        reset_allowed_when: "the residual is under the limit",
        brakes_joint: true,
        held_in_place_first: true,
    },
    /// A hip or knee drive's current, read from its amplifier's monitor
    /// output, is not the torque it was given: a set value stuck, a share
    /// of the current missing. Found at the drive's own joint in
    /// milliseconds (0x0404 finds it through the motion, later and often
    /// first at a joint it dragged); that drive is disabled, its brake
    /// holds the joint, the others hold the posture.
    DriveCurrentMismatch = 0x0405 {
        name: "drive current not following its command",
        reaction: Reaction::SafeHold,
        detection_bound: "3 samples of that drive in a row (one every 4 ticks): 9 ticks from the \
            first, at most 12 from the onset",
        reset_allowed_when: "the drive's samples match (a braked drive is checked again once \
            enabled)",
        brakes_joint: true,
    },
    /// A drive's current monitor reads at a rail, or cannot be read: the
    /// drive still works, but one of its checks is lost.
    DriveCurrentMonitor = 0x0406 {
        name: "drive current monitor fault",
        reaction: Reaction::FinishStepThenHold,
        detection_bound: "3 bad samples of that monitor among its last 25 (100 ticks); \
            1 tick if reported Ok but not finite",
        reset_allowed_when: "< 3 bad samples among that monitor's last 25",
    },
    /// The patient's gait bundle in its flash sector failed verification
    /// (CRC, version, device fingerprint, patient model, a table): nothing
    /// of it is played. The board holds the posture it finds and GO does
    /// nothing; only a verified bundle, written and booted, clears it.
    BundleRefused = 0x0604 {
        name: "gait bundle refused",
        reaction: Reaction::SafeHold,
        detection_bound: "at boot, before the first tick",
        reset_allowed_when: "never: restart with a verified bundle in its sector",
    },
    /// The calibration record in its flash sector (encoder zero offsets,
    /// force-sensor calibrations) is missing, corrupt or implausible: no
    /// angle or force can be trusted, so the motors stay off (their
    /// brakes hold) until a verified record is written and booted.
    CalibrationRefused = 0x0605 {
        name: "calibration refused",
        reaction: Reaction::DisableMotors,
        detection_bound: "at boot, before the first tick",
        reset_allowed_when: "never: record the calibration and restart",
    },
    /// The idle-time re-planner did not answer by the sequencer's latency
    /// (the tick left it too little time, or it ran past its bound): the
    /// step starts on its table at the latency.
    ReplanLate = 0x0606 {
        name: "re-plan late",
        reaction: Reaction::PlayTable,
        detection_bound: "the re-plan latency (200 ticks after the request)",
        reset_allowed_when: "not latched: logged, the next step is re-planned afresh",
    },
    /// The re-planner's step failed the device's admission check (drive,
    /// envelope, a sample not finite): the step starts on its table.
    ReplanRefused = 0x0607 {
        name: "re-plan refused",
        reaction: Reaction::PlayTable,
        detection_bound: "the re-plan latency (the answer is read then)",
        reset_allowed_when: "not latched: logged, the next step is re-planned afresh",
    },
    /// The windowed checks (`supervisor/windowed.rs`: velocities, frozen
    /// counts, tracking, the torque residual, the ankles' and forces'
    /// rules), which run between two ticks, fell behind by more than the
    /// findings of two ticks hold (`check_slot`): some of their faults were
    /// dropped. A single late answer is a missed deadline (0x0601).
    ChecksLate = 0x0608 {
        name: "windowed checks behind",
        reaction: Reaction::SafeHold,
        detection_bound: "the tick that finds the findings overflowed",
        reset_allowed_when: "the findings fit again",
        in_swing: InSwing::LandFirst,
    },
    /// A planned ankle's shank tips forward of its plan ever faster: the
    /// pilot no longer balances the body over the foot through the
    /// crutches (stopped, or leans past what they hold). In a swing the
    /// step lands first, ahead, where the body goes: two feet down hold
    /// it on their own.
    PilotFallingForward = 0x0701 {
        name: "pilot falling forward",
        reaction: Reaction::SafeHold,
        detection_bound: "30 ticks moving away at 0.25 rad/s from 0.1 rad ahead of the plan \
            (0.05 in a swing) with the crutches idle, 0.2 (0.25) pushing",
        reset_allowed_when: "the ankle is back near its plan or stops moving away",
        in_swing: InSwing::LandFirst,
    },
    /// A planned ankle's shank tips back from its plan ever faster: as
    /// 0x0701, backwards. In a swing the foot is set down where it is
    /// (behind the stance foot early in the step, where the body goes);
    /// late in the swing the step lands.
    PilotFallingBack = 0x0702 {
        name: "pilot falling back",
        reaction: Reaction::SafeHold,
        detection_bound: "30 ticks moving away at 0.25 rad/s from 0.1 rad behind the plan \
            (0.05 in a swing) with the crutches idle, 0.2 (0.25) pushing",
        reset_allowed_when: "the ankle is back near its plan or stops moving away",
        in_swing: InSwing::HoldNow,
    },
    /// The crutches stay at their resting load through a swing: the pilot
    /// no longer pushes on them, so nothing balances the body over the
    /// stance foot (in a stair descent it sinks back onto the tread it
    /// left). In a swing the foot is set down where it is, over that
    /// tread early in the step; late in the swing the step lands.
    PilotNotBalancing = 0x0703 {
        name: "pilot not balancing",
        reaction: Reaction::SafeHold,
        detection_bound: "800 ticks of a swing with the crutches within 10 N of the least \
            they carried lately",
        reset_allowed_when: "no swing is under way (in the hold: at once)",
        in_swing: InSwing::HoldNow,
    },
}

// A `FaultSet` has one bit per code in a `u64`.
const _: () = assert!(FaultCode::COUNT <= u64::BITS as usize);

impl FaultCode {
    /// The stable numeric code.
    #[must_use]
    pub const fn code(self) -> u16 {
        self as u16
    }

    /// The fault for a numeric code, if there is one.
    #[must_use]
    pub fn from_code(code: u16) -> Option<Self> {
        Self::ALL.iter().copied().find(|f| f.code() == code)
    }

    pub(crate) const fn bit(self) -> u64 {
        1 << self.index()
    }
}
