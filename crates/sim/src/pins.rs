//! Simulated input pins: a clinician's push button played from a script,
//! and the emergency stop.

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use embedded_hal::digital::{self, InputPin};

pub use crate::motor::SimPinError;
use crate::shared::SimClock;

/// Which electrical level a pressed contact gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PressedLevel {
    /// Pressed pulls the pin low (button to ground with a pull-up).
    Low,
    /// Pressed drives the pin high.
    High,
}

/// A push button whose state follows a script of `(tick, pressed)` changes
/// on a [`SimClock`]. Each change can bounce: for `bounce_ticks` ticks after
/// it the contact alternates every tick, starting from the old state, as a
/// mechanical contact chatters. Clones are handles on the same button (keep
/// one to extend the script or inject read faults).
#[derive(Clone, Debug)]
pub struct SimButton {
    clock: SimClock,
    script: Rc<RefCell<Vec<(u64, bool)>>>,
    level: PressedLevel,
    bounce_ticks: u64,
    read_errors: Rc<Cell<u32>>,
}

impl SimButton {
    /// A button on `clock`, released until the first scripted change.
    /// The script is sorted by tick.
    pub fn new(clock: SimClock, mut script: Vec<(u64, bool)>, level: PressedLevel) -> Self {
        script.sort_by_key(|&(t, _)| t);
        Self {
            clock,
            script: Rc::new(RefCell::new(script)),
            level,
            bounce_ticks: 0,
            read_errors: Rc::new(Cell::new(0)),
        }
    }

    /// With contact bounce after each change.
    pub fn with_bounce(mut self, ticks: u64) -> Self {
        self.bounce_ticks = ticks;
        self
    }

    /// Adds a change to the script.
    pub fn push(&self, tick: u64, pressed: bool) {
        let mut script = self.script.borrow_mut();
        script.push((tick, pressed));
        script.sort_by_key(|&(t, _)| t);
    }

    /// Fault: the next `n` reads fail.
    pub fn fail_reads(&self, n: u32) {
        self.read_errors.set(n);
    }

    /// Whether the contact is closed at tick `t` (bounce included).
    pub fn pressed_at(&self, t: u64) -> bool {
        let mut state = false;
        let mut previous = false;
        let mut since = u64::MAX;
        for &(tick, pressed) in self.script.borrow().iter() {
            if tick > t {
                break;
            }
            previous = state;
            state = pressed;
            since = t - tick;
        }
        if since < self.bounce_ticks && previous != state {
            // Tick 0 after the change still reads the old state, then
            // alternates until the bounce is over.
            if since % 2 == 0 { previous } else { state }
        } else {
            state
        }
    }

    fn read(&mut self) -> Result<bool, SimPinError> {
        let n = self.read_errors.get();
        if n > 0 {
            self.read_errors.set(n - 1);
            return Err(SimPinError);
        }
        Ok(self.pressed_at(self.clock.now()))
    }
}

impl digital::ErrorType for SimButton {
    type Error = SimPinError;
}

impl InputPin for SimButton {
    fn is_high(&mut self) -> Result<bool, SimPinError> {
        let pressed = self.read()?;
        Ok(pressed == (self.level == PressedLevel::High))
    }

    fn is_low(&mut self) -> Result<bool, SimPinError> {
        self.is_high().map(|h| !h)
    }
}

/// The emergency-stop input. The harness keeps a clone to press it; the
/// driver reads it. Wired normally closed by default: pressing opens the
/// loop and the pull-up reads high, so a cut wire also reads "pressed".
#[derive(Clone, Debug)]
pub struct SimEStop {
    pressed: Rc<Cell<bool>>,
    level: PressedLevel,
    read_errors: Rc<Cell<u32>>,
}

impl Default for SimEStop {
    fn default() -> Self {
        Self::new(PressedLevel::High)
    }
}

impl SimEStop {
    /// Released, with the given pressed level.
    pub fn new(level: PressedLevel) -> Self {
        Self {
            pressed: Rc::new(Cell::new(false)),
            level,
            read_errors: Rc::new(Cell::new(0)),
        }
    }

    /// Presses (`true`) or releases the stop.
    pub fn set_pressed(&self, pressed: bool) {
        self.pressed.set(pressed);
    }

    /// Whether it is pressed.
    pub fn is_pressed(&self) -> bool {
        self.pressed.get()
    }

    /// Fault: the next `n` reads fail.
    pub fn fail_reads(&self, n: u32) {
        self.read_errors.set(n);
    }
}

impl digital::ErrorType for SimEStop {
    type Error = SimPinError;
}

impl InputPin for SimEStop {
    fn is_high(&mut self) -> Result<bool, SimPinError> {
        let n = self.read_errors.get();
        if n > 0 {
            self.read_errors.set(n - 1);
            return Err(SimPinError);
        }
        Ok(self.pressed.get() == (self.level == PressedLevel::High))
    }

    fn is_low(&mut self) -> Result<bool, SimPinError> {
        self.is_high().map(|h| !h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn script_and_bounce() {
        let clock = SimClock::new();
        let b =
            SimButton::new(clock, vec![(10, true), (50, false)], PressedLevel::Low).with_bounce(4);
        let seq: Vec<bool> = (8..16).map(|t| b.pressed_at(t)).collect();
        assert_eq!(seq, [false, false, false, true, false, true, true, true]);
        assert!(!b.pressed_at(60));
        assert!(b.pressed_at(49));
    }
}
