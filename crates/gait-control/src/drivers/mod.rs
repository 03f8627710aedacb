//! Drivers, one module per part number (or per kind of plain GPIO use).
//!
//! Every driver is generic over embedded-hal 1.0 traits, never waits, never
//! allocates, and does a fixed amount of bus work per call, so a 1 kHz tick
//! can budget for it. Every error is typed (`Error<E>` with the bus error
//! kept as `Bus(E)`) so the supervisor can turn it into a fault code.

pub mod as5048a;
pub mod buttons;
pub mod mcp3208;
pub mod motor;
pub mod status;

/// A driver error that says what kind of failure it is, without the bus's
/// own error type: what the supervisor counts, as it is.
pub trait ErrorKind {
    /// The outcome of a read; its `Default` is a good read.
    type Status: Default;
    /// This error's kind (never the default).
    fn kind(&self) -> Self::Status;
}

/// The outcome of a read: good, or its error's kind.
pub fn status_of<T, E: ErrorKind>(result: &Result<T, E>) -> E::Status {
    match result {
        Ok(_) => E::Status::default(),
        Err(e) => e.kind(),
    }
}
