//! Fault codes, their reactions, and a fixed-size set of them.
//!
//! One [`FaultCode`] per row of the fault table in `docs/safety.md`. The
//! numeric codes are stable (they appear in logs and service reports): the
//! high byte is the group, the low byte the fault within the group.
//!
//! | group | what |
//! |---|---|
//! | `0x01xx` | joint motion (position, velocity, tracking) |
//! | `0x02xx` | angle encoders |
//! | `0x03xx` | force sensors |
//! | `0x04xx` | motor outputs |
//! | `0x05xx` | operator inputs (e-stop, buttons) |
//! | `0x06xx` | the controller itself (timing, values it computed) |

/// What the controller must do about the latched faults, least severe
/// first (so `max` over a set of reactions is the one to apply).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reaction {
    /// Nothing latched: carry on.
    #[default]
    None,
    /// Warning class: let the current step finish, then hold the standing
    /// posture; refuse to start another step until a reset.
    FinishStepThenHold,
    /// Fatal: at once, ramp to a position hold of the current posture
    /// (motors stay powered: a limp exoskeleton drops its pilot).
    SafeHold,
    /// Only for the emergency stop and motor output-stage faults: disable
    /// every motor output now.
    DisableMotors,
}

/// One fault of the fault table. `#[repr(u16)]`: the discriminant is the
/// stable numeric code ([`FaultCode::code`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u16)]
pub enum FaultCode {
    /// An actuated joint's angle is outside the supervisor's envelope
    /// (Table I limits with margins).
    JointPositionLimit = 0x0101,
    /// An actuated joint's filtered velocity exceeds its limit.
    JointVelocityLimit = 0x0102,
    /// |angle − reference| above the limit for too long.
    TrackingError = 0x0103,
    /// A passive ankle's angle is outside its envelope.
    AnklePositionLimit = 0x0104,
    /// The stance ankle rests on its dorsiflexion stop (the heel lifts:
    /// the toe rocker) while the plan keeps it well below: the pilot leans
    /// further forward than the gait was planned for.
    UnplannedHeelOff = 0x0105,
    /// Joint encoder: too many bad frames, the last a bus error.
    EncoderBusError = 0x0201,
    /// Joint encoder: too many bad frames, the last a parity error.
    EncoderParity = 0x0202,
    /// Joint encoder: too many bad frames, the last with the error flag.
    EncoderErrorFlag = 0x0203,
    /// Joint encoder: raw counts unchanged while the joint is driven.
    EncoderFrozen = 0x0204,
    /// Joint encoder: too many bad frames, the last an impossible jump.
    EncoderJump = 0x0205,
    /// Joint encoder: a frame reported good carries an impossible value
    /// (raw counts beyond 14 bits, angle not finite or outside (−π, π]).
    EncoderInvalidValue = 0x0206,
    /// Ankle encoder: any of the encoder faults above on a passive ankle.
    AnkleEncoder = 0x0207,
    /// Force sensor: too many bad samples, the last a bus error.
    ForceBusError = 0x0301,
    /// Force sensor: too many bad samples, the last an open circuit.
    ForceOpen = 0x0302,
    /// Force sensor: too many bad samples, the last a short circuit.
    ForceShorted = 0x0303,
    /// Force sensor: too many bad samples, the last out of the rated range
    /// (immediately if the value is not finite).
    ForceOutOfRange = 0x0304,
    /// Motor command at or above its torque limit for too long.
    MotorSaturated = 0x0401,
    /// The motor driver's I²t model latched a thermal fault.
    MotorThermal = 0x0402,
    /// A motor output stage write failed (PWM or pin).
    MotorOutputStage = 0x0403,
    /// The emergency-stop input is pressed.
    EStopPressed = 0x0501,
    /// The emergency-stop input could not be read (treated as pressed).
    EStopInputFault = 0x0502,
    /// A MODE/GO button input is faulty.
    ButtonInputFault = 0x0503,
    /// Too many missed tick deadlines within the window.
    DeadlineMissed = 0x0601,
    /// A value the controller computed is not usable: a reference angle,
    /// a motor command, applied torque or limit is not finite, or a limit
    /// is not positive.
    ControlValueInvalid = 0x0602,
}

impl FaultCode {
    /// Number of fault codes.
    pub const COUNT: usize = 24;

    /// Every fault code, in bit order of [`FaultSet`].
    pub const ALL: [Self; Self::COUNT] = [
        Self::JointPositionLimit,
        Self::JointVelocityLimit,
        Self::TrackingError,
        Self::AnklePositionLimit,
        Self::EncoderBusError,
        Self::EncoderParity,
        Self::EncoderErrorFlag,
        Self::EncoderFrozen,
        Self::EncoderJump,
        Self::EncoderInvalidValue,
        Self::AnkleEncoder,
        Self::ForceBusError,
        Self::ForceOpen,
        Self::ForceShorted,
        Self::ForceOutOfRange,
        Self::MotorSaturated,
        Self::MotorThermal,
        Self::MotorOutputStage,
        Self::EStopPressed,
        Self::EStopInputFault,
        Self::ButtonInputFault,
        Self::DeadlineMissed,
        Self::ControlValueInvalid,
        Self::UnplannedHeelOff,
    ];

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

    /// Position in [`FaultCode::ALL`], i.e. the bit in a [`FaultSet`].
    #[must_use]
    pub const fn index(self) -> u8 {
        match self {
            Self::JointPositionLimit => 0,
            Self::JointVelocityLimit => 1,
            Self::TrackingError => 2,
            Self::AnklePositionLimit => 3,
            Self::EncoderBusError => 4,
            Self::EncoderParity => 5,
            Self::EncoderErrorFlag => 6,
            Self::EncoderFrozen => 7,
            Self::EncoderJump => 8,
            Self::EncoderInvalidValue => 9,
            Self::AnkleEncoder => 10,
            Self::ForceBusError => 11,
            Self::ForceOpen => 12,
            Self::ForceShorted => 13,
            Self::ForceOutOfRange => 14,
            Self::MotorSaturated => 15,
            Self::MotorThermal => 16,
            Self::MotorOutputStage => 17,
            Self::EStopPressed => 18,
            Self::EStopInputFault => 19,
            Self::ButtonInputFault => 20,
            Self::DeadlineMissed => 21,
            Self::ControlValueInvalid => 22,
            Self::UnplannedHeelOff => 23,
        }
    }

    /// The reaction this fault demands while it is latched.
    #[must_use]
    pub const fn reaction(self) -> Reaction {
        match self {
            // Passive ankles, sensors needed only to start a swing, and
            // the buttons: not needed to hold, so finish the step first.
            Self::AnklePositionLimit
            | Self::UnplannedHeelOff
            | Self::AnkleEncoder
            | Self::ForceBusError
            | Self::ForceOpen
            | Self::ForceShorted
            | Self::ForceOutOfRange
            | Self::ButtonInputFault => Reaction::FinishStepThenHold,
            Self::JointPositionLimit
            | Self::JointVelocityLimit
            | Self::TrackingError
            | Self::EncoderBusError
            | Self::EncoderParity
            | Self::EncoderErrorFlag
            | Self::EncoderFrozen
            | Self::EncoderJump
            | Self::EncoderInvalidValue
            | Self::MotorSaturated
            | Self::MotorThermal
            | Self::DeadlineMissed
            | Self::ControlValueInvalid => Reaction::SafeHold,
            Self::MotorOutputStage | Self::EStopPressed | Self::EStopInputFault => {
                Reaction::DisableMotors
            }
        }
    }

    /// Short name for logs and the service tool.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::JointPositionLimit => "joint position limit",
            Self::JointVelocityLimit => "joint velocity limit",
            Self::TrackingError => "tracking error",
            Self::AnklePositionLimit => "ankle position limit",
            Self::UnplannedHeelOff => "unplanned heel-off",
            Self::EncoderBusError => "encoder bus error",
            Self::EncoderParity => "encoder parity error",
            Self::EncoderErrorFlag => "encoder error flag",
            Self::EncoderFrozen => "encoder frozen",
            Self::EncoderJump => "encoder impossible jump",
            Self::EncoderInvalidValue => "encoder invalid value",
            Self::AnkleEncoder => "ankle encoder fault",
            Self::ForceBusError => "force sensor bus error",
            Self::ForceOpen => "force sensor open",
            Self::ForceShorted => "force sensor shorted",
            Self::ForceOutOfRange => "force sensor out of range",
            Self::MotorSaturated => "motor command saturated",
            Self::MotorThermal => "motor thermal fault",
            Self::MotorOutputStage => "motor output stage fault",
            Self::EStopPressed => "emergency stop pressed",
            Self::EStopInputFault => "emergency stop input fault",
            Self::ButtonInputFault => "button input fault",
            Self::DeadlineMissed => "tick deadline missed",
            Self::ControlValueInvalid => "control value invalid",
        }
    }

    const fn bit(self) -> u32 {
        1 << self.index()
    }
}

/// A set of fault codes (one bit per code).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FaultSet(u32);

impl FaultSet {
    /// The empty set.
    pub const EMPTY: Self = Self(0);

    /// The empty set.
    #[must_use]
    pub const fn new() -> Self {
        Self::EMPTY
    }

    /// Adds `code`.
    pub const fn insert(&mut self, code: FaultCode) {
        self.0 |= code.bit();
    }

    /// Removes `code`.
    pub const fn remove(&mut self, code: FaultCode) {
        self.0 &= !code.bit();
    }

    /// Whether `code` is in the set.
    #[must_use]
    pub const fn contains(&self, code: FaultCode) -> bool {
        self.0 & code.bit() != 0
    }

    /// Whether the set is empty.
    #[must_use]
    pub const fn is_empty(&self) -> bool {
        self.0 == 0
    }

    /// Number of codes in the set.
    #[must_use]
    pub const fn len(&self) -> usize {
        self.0.count_ones() as usize
    }

    /// Codes in both sets.
    #[must_use]
    pub const fn intersection(self, other: Self) -> Self {
        Self(self.0 & other.0)
    }

    /// Codes in either set.
    #[must_use]
    pub const fn union(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    /// The raw bits (bit *i* is `FaultCode::ALL[i]`), for compact logs.
    #[must_use]
    pub const fn bits(&self) -> u32 {
        self.0
    }

    /// The codes in the set, in [`FaultCode::ALL`] order.
    pub fn iter(&self) -> impl Iterator<Item = FaultCode> + '_ {
        FaultCode::ALL.iter().copied().filter(|c| self.contains(*c))
    }

    /// The most severe reaction over the set ([`Reaction::None`] if empty).
    #[must_use]
    pub fn reaction(&self) -> Reaction {
        self.iter()
            .map(FaultCode::reaction)
            .max()
            .unwrap_or(Reaction::None)
    }
}

impl FromIterator<FaultCode> for FaultSet {
    fn from_iter<I: IntoIterator<Item = FaultCode>>(iter: I) -> Self {
        let mut set = Self::new();
        for c in iter {
            set.insert(c);
        }
        set
    }
}
