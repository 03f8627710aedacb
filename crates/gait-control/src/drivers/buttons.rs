//! Debounced push buttons on [`InputPin`]s, sampled once per control tick.
//!
//! Debounce is an integrator (saturating up/down counter): each tick adds
//! one while the contact reads pressed and subtracts one while it reads
//! released; the debounced state becomes pressed when the counter reaches
//! `debounce_ticks` and released when it returns to 0. A burst of bounce
//! shorter than `debounce_ticks` therefore can never produce an event, and
//! noise slows a change down instead of causing a second one.
//!
//! A failed pin read counts as "not pressed" (a broken button must not start
//! a gait) and is reported in [`Sample::input_fault`] and counted.

use embedded_hal::digital::InputPin;

/// Which electrical level means "pressed".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ActiveLevel {
    /// Pressed pulls the pin low (button to ground, pull-up).
    Low,
    /// Pressed pulls the pin high.
    High,
}

/// Button timing, in control ticks (1 tick = 1 ms at 1 kHz).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ButtonConfig {
    /// Electrical level of "pressed".
    pub active: ActiveLevel,
    /// Integrator length: consecutive-equivalent ticks to accept a change
    /// (at least 1).
    pub debounce_ticks: u16,
    /// Held time (from the debounced press) that makes a long press.
    pub long_press_ticks: u32,
}

impl ButtonConfig {
    /// 20 ms debounce, 1 s long press, active low, at 1 kHz.
    pub const DEFAULT_1KHZ: Self = Self {
        active: ActiveLevel::Low,
        debounce_ticks: 20,
        long_press_ticks: 1000,
    };
}

/// A debounced button event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// The button went down (after debounce).
    Pressed,
    /// The button has been held for `long_press_ticks` (sent once per press).
    LongPress,
    /// The button came up.
    Released {
        /// Ticks from the debounced press to the debounced release.
        held_ticks: u32,
        /// Whether `LongPress` was sent during this press.
        was_long: bool,
    },
}

/// What one tick of a button produced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sample {
    /// The event of this tick, if any.
    pub event: Option<Event>,
    /// Debounced state after this tick.
    pub pressed: bool,
    /// Ticks the button has been (debounced) held, 0 when released.
    pub held_ticks: u32,
    /// The pin read failed this tick (treated as not pressed).
    pub input_fault: bool,
}

/// The pin-free debounce and press-timing logic (pure, for tests and sim).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Debouncer {
    cfg: ButtonConfig,
    integrator: u16,
    pressed: bool,
    held_ticks: u32,
    long_sent: bool,
}

impl Debouncer {
    /// Starts released.
    #[must_use]
    pub const fn new(cfg: ButtonConfig) -> Self {
        Self {
            cfg,
            integrator: 0,
            pressed: false,
            held_ticks: 0,
            long_sent: false,
        }
    }

    /// Feeds one raw sample (`true` = contact reads pressed).
    pub fn update(&mut self, raw_pressed: bool) -> Sample {
        let top = if self.cfg.debounce_ticks == 0 {
            1
        } else {
            self.cfg.debounce_ticks
        };
        self.integrator = if raw_pressed {
            self.integrator.saturating_add(1).min(top)
        } else {
            self.integrator.saturating_sub(1)
        };
        let mut event = None;
        if !self.pressed && self.integrator >= top {
            self.pressed = true;
            self.held_ticks = 0;
            self.long_sent = false;
            event = Some(Event::Pressed);
        } else if self.pressed && self.integrator == 0 {
            self.pressed = false;
            event = Some(Event::Released {
                held_ticks: self.held_ticks.saturating_add(1),
                was_long: self.long_sent,
            });
            self.held_ticks = 0;
        } else if self.pressed {
            self.held_ticks = self.held_ticks.saturating_add(1);
            if !self.long_sent && self.held_ticks >= self.cfg.long_press_ticks {
                self.long_sent = true;
                event = Some(Event::LongPress);
            }
        }
        Sample {
            event,
            pressed: self.pressed,
            held_ticks: self.held_ticks,
            input_fault: false,
        }
    }

    /// Debounced state.
    #[must_use]
    pub const fn is_pressed(&self) -> bool {
        self.pressed
    }
}

/// A button on a pin.
#[derive(Debug)]
pub struct Button<PIN> {
    pin: PIN,
    debouncer: Debouncer,
    input_errors: u32,
}

impl<PIN: InputPin> Button<PIN> {
    /// Wraps an input pin.
    pub const fn new(pin: PIN, cfg: ButtonConfig) -> Self {
        Self {
            pin,
            debouncer: Debouncer::new(cfg),
            input_errors: 0,
        }
    }

    /// Gives the pin back.
    pub fn destroy(self) -> PIN {
        self.pin
    }

    /// Samples the pin once; call exactly once per tick.
    pub fn tick(&mut self) -> Sample {
        let read = match self.debouncer.cfg.active {
            ActiveLevel::Low => self.pin.is_low(),
            ActiveLevel::High => self.pin.is_high(),
        };
        let (raw, fault) = match read {
            Ok(level) => (level, false),
            Err(_) => {
                self.input_errors = self.input_errors.saturating_add(1);
                (false, true)
            }
        };
        let mut sample = self.debouncer.update(raw);
        sample.input_fault = fault;
        sample
    }

    /// Pin read failures since start (saturating).
    pub const fn input_errors(&self) -> u32 {
        self.input_errors
    }
}
