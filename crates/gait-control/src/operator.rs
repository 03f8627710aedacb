//! The clinician's two-button scheme (MODE and GO) as a pure state machine.
//!
//! Fed once per tick with the debounced samples of both buttons and the
//! controller's status; returns the selected gait, at most one request, and
//! the LED/buzzer feedback. It touches no hardware and keeps no time of its
//! own beyond counting its calls, so it is tested and simulated as is.
//! `docs/operation.md` describes the same rules for clinicians.
//!
//! Rules, in the order they are applied each tick:
//!
//! 1. GO pressed while walking → [`Request::StopAfterStep`]. Stopping is
//!    never suppressed, not even while both buttons are held.
//! 2. Both buttons held together → a *combination*: every other single-button
//!    action is suppressed until both are released. Held for
//!    `reset_hold_ticks` (3 s) → [`Request::ResetFaults`] if the controller
//!    reports a safe posture and is not walking, a refusal otherwise; one
//!    decision per hold (until both buttons are up).
//! 3. GO long press while standing (not walking, no step) → [`Request::Start`]
//!    with the selected gait, unless a fault is active (refused). A short GO
//!    press while standing does nothing.
//! 4. MODE short press (released before the long-press time) while standing
//!    → next gait in the patient's allowed list. Ignored (refusal beeps)
//!    while walking or while a step is in progress; a long MODE press does
//!    nothing.

use crate::drivers::buttons::{Event, Sample};
use crate::drivers::status::Pattern;

/// The gaits a clinician can choose from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Gait {
    /// Level walking.
    Walk,
    /// Climbing stairs up.
    StairUp,
    /// Climbing stairs down.
    StairDown,
}

impl Gait {
    /// Blink code of the gait LED: 1, 2 or 3 flashes.
    #[must_use]
    pub const fn code(self) -> u8 {
        match self {
            Self::Walk => 1,
            Self::StairUp => 2,
            Self::StairDown => 3,
        }
    }
}

/// Longest allowed-gait list: a patient's bundle holds at most this many
/// gaits (`gait_core::bundle::MAX_GAITS`).
pub const MAX_GAITS: usize = 16;

/// Why an operator configuration was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// The allowed list is empty.
    Empty,
    /// The allowed list has more than [`MAX_GAITS`] entries.
    TooMany,
    /// A gait appears twice.
    Duplicate,
}

/// One gait a clinician can choose: its movement, where its table is in
/// the sequencer's [`crate::sequencer::GaitTables`], and how many flashes
/// the gait LED shows for it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GaitChoice {
    /// The movement.
    pub kind: Gait,
    /// Its table's slot.
    pub slot: u8,
    /// Flashes of the gait LED (1 …).
    pub flashes: u8,
}

/// What fills the unused end of a list (never chosen: the list's length
/// bounds the choice).
const UNUSED: GaitChoice = GaitChoice {
    kind: Gait::Walk,
    slot: 0,
    flashes: 1,
};

/// The gaits this patient is cleared for, in MODE order (first = default).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AllowedGaits {
    choices: [GaitChoice; MAX_GAITS],
    len: u8,
}

impl AllowedGaits {
    /// The device's own gaits, one table per movement (slots 0, 1, 2 for
    /// walk, stair up, stair down: [`crate::sequencer::GaitTables::by_kind`]),
    /// each showing its movement's code ([`Gait::code`]).
    pub fn new(list: &[Gait]) -> Result<Self, ConfigError> {
        let mut choices = [UNUSED; MAX_GAITS];
        for (c, g) in choices.iter_mut().zip(list) {
            *c = GaitChoice {
                kind: *g,
                slot: g.code().saturating_sub(1),
                flashes: g.code(),
            };
        }
        Self::checked(choices, list.len())
    }

    /// A patient's gaits in the bundle's order: gait *i* is `kinds[i]` in
    /// slot *i*, shown by *i* + 1 flashes.
    pub fn in_order(kinds: &[Gait]) -> Result<Self, ConfigError> {
        let mut choices = [UNUSED; MAX_GAITS];
        for ((c, g), i) in choices.iter_mut().zip(kinds).zip(0u8..) {
            *c = GaitChoice {
                kind: *g,
                slot: i,
                flashes: i + 1,
            };
        }
        Self::checked(choices, kinds.len())
    }

    /// The choices as given (slots distinct, at most [`MAX_GAITS`]).
    pub fn from_choices(list: &[GaitChoice]) -> Result<Self, ConfigError> {
        let mut choices = [UNUSED; MAX_GAITS];
        for (c, g) in choices.iter_mut().zip(list) {
            *c = *g;
        }
        Self::checked(choices, list.len())
    }

    fn checked(choices: [GaitChoice; MAX_GAITS], len: usize) -> Result<Self, ConfigError> {
        if len == 0 {
            return Err(ConfigError::Empty);
        }
        if len > MAX_GAITS {
            return Err(ConfigError::TooMany);
        }
        let used = choices.get(..len).unwrap_or(&[]);
        for (i, c) in used.iter().enumerate() {
            if used.iter().skip(i + 1).any(|d| d.slot == c.slot) {
                return Err(ConfigError::Duplicate);
            }
        }
        Ok(Self {
            choices,
            // len ≤ MAX_GAITS = 16, checked above.
            len: len as u8,
        })
    }

    /// Number of allowed gaits (≥ 1).
    #[must_use]
    pub const fn len(&self) -> usize {
        self.len as usize
    }

    /// Never true: an empty list is refused by `new`.
    #[must_use]
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The gait at `index` (wrapped into range; total).
    #[must_use]
    pub fn get(&self, index: usize) -> Gait {
        self.choice(index).kind
    }

    /// The choice at `index` (wrapped into range; total).
    #[must_use]
    pub fn choice(&self, index: usize) -> GaitChoice {
        let len = self.len().max(1);
        self.choices.get(index % len).copied().unwrap_or(UNUSED)
    }
}

/// Operator scheme settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OperatorConfig {
    /// The patient's gaits.
    pub allowed: AllowedGaits,
    /// How long MODE+GO must be held to reset faults, ticks (3000 at 1 kHz).
    pub reset_hold_ticks: u32,
}

/// What the controller tells the operator scheme each tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ControllerStatus {
    /// A gait is running (from start until it has come to a stop).
    pub walking: bool,
    /// A step is being taken right now.
    pub step_in_progress: bool,
    /// The pilot stands still, both feet down, crutches loaded: a fault reset
    /// cannot make the exoskeleton move unexpectedly.
    pub safe_posture: bool,
    /// The supervisor holds an active fault.
    pub faulted: bool,
}

/// One tick's input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Input {
    /// Debounced MODE button.
    pub mode: Sample,
    /// Debounced GO button.
    pub go: Sample,
    /// Controller status.
    pub status: ControllerStatus,
}

/// A request to the sequencer / supervisor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Request {
    /// Start the given gait (the sequencer still checks readiness).
    Start(GaitChoice),
    /// Finish the current step, then stand.
    StopAfterStep,
    /// Clear the supervisor's latched faults.
    ResetFaults,
}

/// LED and buzzer patterns to show.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Feedback {
    /// Green gait LED.
    pub gait_led: Pattern,
    /// Red fault LED.
    pub fault_led: Pattern,
    /// Buzzer.
    pub buzzer: Pattern,
}

/// One tick's output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Output {
    /// The gait MODE has selected.
    pub selected: Gait,
    /// Its table's slot.
    pub selected_slot: u8,
    /// At most one request per tick.
    pub request: Option<Request>,
    /// What to show.
    pub feedback: Feedback,
    /// The tick counter to drive the patterns with.
    pub tick: u32,
}

/// Fast blink: stop requested / reset combination being held.
pub const FAST_BLINK: Pattern = Pattern::Blink {
    period_ticks: 250,
    on_ticks: 125,
};
/// Length of the "faults reset" tone, ticks.
pub const RESET_TONE_TICKS: u32 = 1000;

/// The state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Operator {
    cfg: OperatorConfig,
    selected: usize,
    tick: u32,
    combo: bool,
    combo_ticks: u32,
    combo_done: bool,
    stop_requested: bool,
    buzzer: Pattern,
}

impl Operator {
    /// Starts with the first allowed gait selected and everything quiet.
    #[must_use]
    pub const fn new(cfg: OperatorConfig) -> Self {
        Self {
            cfg,
            selected: 0,
            tick: 0,
            combo: false,
            combo_ticks: 0,
            combo_done: false,
            stop_requested: false,
            buzzer: Pattern::Off,
        }
    }

    /// The selected gait.
    #[must_use]
    pub fn selected(&self) -> Gait {
        self.cfg.allowed.get(self.selected)
    }

    /// The selected gait, with its slot and flashes.
    #[must_use]
    pub fn choice(&self) -> GaitChoice {
        self.cfg.allowed.choice(self.selected)
    }

    fn beep(&mut self, count: u8) {
        self.buzzer = Pattern::Burst {
            start: self.tick,
            count,
        };
    }

    /// One tick. Bounded work, no loops.
    pub fn tick(&mut self, input: &Input) -> Output {
        self.tick = self.tick.wrapping_add(1);
        let Input { mode, go, status } = *input;
        let standing = !status.walking && !status.step_in_progress;
        if !status.walking {
            self.stop_requested = false;
        }
        let mut request = None;

        // 1. Stop is never suppressed.
        if status.walking && go.event == Some(Event::Pressed) {
            request = Some(Request::StopAfterStep);
            self.stop_requested = true;
            self.beep(1);
        }

        // 2. The combination.
        let both = mode.pressed && go.pressed;
        if both {
            self.combo = true;
        }
        if self.combo {
            if both {
                self.combo_ticks = self.combo_ticks.saturating_add(1);
                if !self.combo_done && self.combo_ticks >= self.cfg.reset_hold_ticks {
                    self.combo_done = true;
                    // A reset while moving is refused even if the posture
                    // flag says safe: the two inputs contradict each other.
                    if status.safe_posture && standing && request.is_none() {
                        request = Some(Request::ResetFaults);
                        self.buzzer = Pattern::Tone {
                            start: self.tick,
                            on_ticks: RESET_TONE_TICKS,
                        };
                    } else {
                        self.beep(3);
                    }
                }
            } else {
                self.combo_ticks = 0;
            }
            if !mode.pressed && !go.pressed {
                self.combo = false;
                self.combo_done = false;
                self.combo_ticks = 0;
            }
        } else {
            // 3. GO long press starts.
            if go.event == Some(Event::LongPress) && standing {
                if status.faulted {
                    self.beep(3);
                } else {
                    request = Some(Request::Start(self.choice()));
                    self.beep(2);
                }
            }
            // 4. MODE short press cycles.
            if let Some(Event::Released {
                was_long: false, ..
            }) = mode.event
            {
                if standing {
                    self.selected = (self.selected + 1) % self.cfg.allowed.len().max(1);
                    self.beep(1);
                } else {
                    self.beep(3);
                }
            }
        }

        Output {
            selected: self.selected(),
            selected_slot: self.choice().slot,
            request,
            feedback: self.feedback(&status),
            tick: self.tick,
        }
    }

    fn feedback(&self, status: &ControllerStatus) -> Feedback {
        let gait_led = if status.faulted {
            Pattern::Off
        } else if self.stop_requested {
            FAST_BLINK
        } else if status.walking {
            Pattern::On
        } else {
            Pattern::Code {
                count: self.choice().flashes,
            }
        };
        // Blink while the combination is being held and has not yet acted.
        let fault_led = if self.combo && self.combo_ticks > 0 && !self.combo_done {
            FAST_BLINK
        } else if status.faulted {
            Pattern::On
        } else {
            Pattern::Off
        };
        Feedback {
            gait_led,
            fault_led,
            buzzer: self.buzzer,
        }
    }
}
