//! A fixed-size log that keeps the newest `N` records, with no panic path.
//!
//! Written here rather than taken from heapless: `heapless::HistoryBuf`
//! indexes its storage (`data[write_at]`, `buffer[write_at..]`) with bounds
//! checks the optimiser cannot remove, and the motor-board image must hold no
//! panic path (`docs/safety.md`, "No panic path"). Every access here is a
//! `get`/`get_mut` whose failure is a no-op.

/// The newest `N` records of type `T`, oldest first when read.
#[derive(Debug, Clone)]
pub struct RingLog<T: Copy, const N: usize> {
    items: [Option<T>; N],
    /// Slot the next record goes to.
    next: usize,
    /// Records held (at most `N`).
    len: usize,
}

impl<T: Copy, const N: usize> RingLog<T, N> {
    /// An empty log.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            items: [None; N],
            next: 0,
            len: 0,
        }
    }

    /// Appends `item`, dropping the oldest record when full.
    pub fn push(&mut self, item: T) {
        if let Some(slot) = self.items.get_mut(self.next) {
            *slot = Some(item);
        }
        self.next = if self.next + 1 >= N { 0 } else { self.next + 1 };
        self.len = (self.len + 1).min(N);
    }

    /// Records held.
    #[must_use]
    pub const fn len(&self) -> usize {
        self.len
    }

    /// Whether the log is empty.
    #[must_use]
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The records, oldest first.
    pub fn iter(&self) -> impl DoubleEndedIterator<Item = &T> + '_ {
        // The oldest record sits `len` slots behind `next`.
        let start = (self.next + N - self.len) % N.max(1);
        (0..self.len).filter_map(move |k| {
            let i = start + k;
            let i = if i >= N { i - N } else { i };
            self.items.get(i).and_then(Option::as_ref)
        })
    }
}

impl<T: Copy, const N: usize> Default for RingLog<T, N> {
    fn default() -> Self {
        Self::new()
    }
}
