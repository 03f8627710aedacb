//! The state a tick's interrupt works on, shared with thread mode without
//! a panic path: placed once before the interrupt is unmasked, used by the
//! interrupt, taken back after it is masked. Every access is in a critical
//! section and borrows with `try_borrow_mut` (a borrow that fails is
//! reported, never a panic).

use core::cell::RefCell;

use cortex_m::interrupt::{self, Mutex};

/// A `static`'s slot for the tick's state.
pub struct TickState<T>(Mutex<RefCell<Option<T>>>);

impl<T> TickState<T> {
    /// Empty.
    #[must_use]
    pub const fn new() -> Self {
        Self(Mutex::new(RefCell::new(None)))
    }

    /// Puts `state` in the slot; `false` if it is borrowed (and `state` is
    /// dropped).
    pub fn place(&self, state: T) -> bool {
        interrupt::free(|cs| {
            self.0
                .borrow(cs)
                .try_borrow_mut()
                .map(|mut s| *s = Some(state))
                .is_ok()
        })
    }

    /// `f` on the state, if it is there and not borrowed.
    pub fn with<R>(&self, f: impl FnOnce(&mut T) -> R) -> Option<R> {
        interrupt::free(|cs| {
            let mut s = self.0.borrow(cs).try_borrow_mut().ok()?;
            s.as_mut().map(f)
        })
    }

    /// Takes the state out of the slot.
    pub fn take(&self) -> Option<T> {
        interrupt::free(|cs| self.0.borrow(cs).try_borrow_mut().ok()?.take())
    }
}

impl<T> Default for TickState<T> {
    fn default() -> Self {
        Self::new()
    }
}
