//! Shared cells between the plant and the simulated peripherals.
//!
//! The harness owns the plant and hands the drivers their peripherals; the
//! two sides meet through these cheap clonable handles (`Rc<Cell<_>>`). The
//! simulation is single-threaded and lock-step, so no locking is needed and
//! every read sees the value of the last publish.

use std::cell::Cell;
use std::rc::Rc;

/// A shared `f64` (an angle, a force, a torque), cloned handles see the same
/// value.
#[derive(Clone, Debug, Default)]
pub struct SharedF64(Rc<Cell<f64>>);

impl SharedF64 {
    /// A new cell holding `value`.
    pub fn new(value: f64) -> Self {
        Self(Rc::new(Cell::new(value)))
    }

    /// The current value.
    pub fn get(&self) -> f64 {
        self.0.get()
    }

    /// Replaces the value.
    pub fn set(&self, value: f64) {
        self.0.set(value);
    }
}

/// The simulation's tick counter (1 tick = one control period, 1 ms at
/// 1 kHz). Scripted inputs (buttons) read it; the harness advances it.
#[derive(Clone, Debug, Default)]
pub struct SimClock(Rc<Cell<u64>>);

impl SimClock {
    /// A clock at tick 0.
    pub fn new() -> Self {
        Self::default()
    }

    /// The current tick.
    pub fn now(&self) -> u64 {
        self.0.get()
    }

    /// Advances by one tick and returns the new tick.
    pub fn tick(&self) -> u64 {
        let next = self.0.get().saturating_add(1);
        self.0.set(next);
        next
    }

    /// Sets the tick (scenario set-up).
    pub fn set(&self, tick: u64) {
        self.0.set(tick);
    }
}
