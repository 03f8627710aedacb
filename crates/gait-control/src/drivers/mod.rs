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
