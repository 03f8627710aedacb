//! Status LEDs and the buzzer on [`OutputPin`]s.
//!
//! A [`Pattern`] is a pure function of the tick counter, so the pattern
//! logic needs no timer of its own and is the same on the board, in the
//! simulator and in tests. [`Indicator`] writes a pin only when its level
//! changes, to keep GPIO traffic out of the tick budget.

use embedded_hal::digital::OutputPin;

/// Length of one flash of a blink code, ticks (ms at 1 kHz).
pub const CODE_ON_TICKS: u32 = 200;
/// Gap between flashes of a blink code, ticks.
pub const CODE_GAP_TICKS: u32 = 200;
/// Pause after the last flash of a blink code, ticks.
pub const CODE_PAUSE_TICKS: u32 = 1000;
/// Length of one beep of a burst, ticks.
pub const BEEP_ON_TICKS: u32 = 80;
/// Gap between beeps of a burst, ticks.
pub const BEEP_GAP_TICKS: u32 = 80;

/// What an LED or the buzzer shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Pattern {
    /// Dark / silent.
    #[default]
    Off,
    /// Lit / sounding.
    On,
    /// Square wave: on for `on_ticks` of every `period_ticks`.
    Blink {
        /// Period, ticks.
        period_ticks: u32,
        /// On time per period, ticks.
        on_ticks: u32,
    },
    /// Repeating blink code: `count` flashes, then a pause.
    Code {
        /// Number of flashes per cycle.
        count: u8,
    },
    /// `count` short beeps (or flashes) once, starting at tick `start`,
    /// then off.
    Burst {
        /// Tick at which the burst starts.
        start: u32,
        /// Number of beeps.
        count: u8,
    },
    /// One tone (or flash) of `on_ticks`, starting at tick `start`.
    Tone {
        /// Tick at which the tone starts.
        start: u32,
        /// Length, ticks.
        on_ticks: u32,
    },
}

impl Pattern {
    /// Level at tick `tick` (`true` = on). Total: no division by zero, no
    /// overflow.
    #[must_use]
    pub fn level(&self, tick: u32) -> bool {
        match *self {
            Self::Off => false,
            Self::On => true,
            Self::Blink {
                period_ticks,
                on_ticks,
            } => match tick.checked_rem(period_ticks) {
                Some(phase) => phase < on_ticks,
                None => false,
            },
            Self::Code { count } => {
                let slot = CODE_ON_TICKS + CODE_GAP_TICKS;
                let cycle = u32::from(count) * slot + CODE_PAUSE_TICKS;
                let phase = tick % cycle;
                phase < u32::from(count) * slot && phase % slot < CODE_ON_TICKS
            }
            Self::Burst { start, count } => {
                let slot = BEEP_ON_TICKS + BEEP_GAP_TICKS;
                match tick.checked_sub(start) {
                    Some(phase) => phase < u32::from(count) * slot && phase % slot < BEEP_ON_TICKS,
                    None => false,
                }
            }
            Self::Tone { start, on_ticks } => tick
                .checked_sub(start)
                .is_some_and(|phase| phase < on_ticks),
        }
    }
}

/// One LED or buzzer output.
#[derive(Debug)]
pub struct Indicator<PIN> {
    pin: PIN,
    /// Level last written successfully; `None` forces the next write.
    written: Option<bool>,
}

impl<PIN: OutputPin> Indicator<PIN> {
    /// Wraps an output pin; the first [`Indicator::update`] writes it.
    pub const fn new(pin: PIN) -> Self {
        Self { pin, written: None }
    }

    /// Gives the pin back.
    pub fn destroy(self) -> PIN {
        self.pin
    }

    /// Shows `pattern` at `tick`. Writes the pin only on a change (and
    /// again after a failed write).
    pub fn update(&mut self, pattern: Pattern, tick: u32) -> Result<(), PIN::Error> {
        let level = pattern.level(tick);
        if self.written == Some(level) {
            return Ok(());
        }
        self.written = None;
        if level {
            self.pin.set_high()?;
        } else {
            self.pin.set_low()?;
        }
        self.written = Some(level);
        Ok(())
    }
}
