//! Drivers, one module per part number (or per kind of plain GPIO use).
//!
//! Every driver is generic over embedded-hal 1.0 traits, never waits, never
//! allocates, and does a fixed amount of bus work per call, so a 1 kHz tick
//! can budget for it. Every error is typed (`Error<E>` with the bus error
//! kept as `Bus(E)`) so the supervisor can turn it into a fault code.

/// Declares a driver's `ReadStatus`, the outcome of one read without the
/// bus's own error type, which the supervisor counts as it is: `Ok` (the
/// default), `BusError` (the SPI transaction failed), then the driver's
/// own failures; and `ReadStatus::of`, a read's result as its status
/// (through the driver's `Error::kind`).
macro_rules! read_status {
    (
        $(#[$meta:meta])*
        ReadStatus {
            $(#[$ok_meta:meta])*
            Ok,
            $($(#[$failure_meta:meta])* $failure:ident,)+
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub enum ReadStatus {
            $(#[$ok_meta])*
            #[default]
            Ok,
            /// The SPI transaction failed.
            BusError,
            $($(#[$failure_meta])* $failure,)+
        }

        impl ReadStatus {
            /// The status of a read's result.
            pub fn of<T, E>(result: &Result<T, Error<E>>) -> Self {
                match result {
                    Ok(_) => Self::Ok,
                    Err(e) => e.kind(),
                }
            }
        }
    };
}
use read_status;

pub mod as5048a;
pub mod buttons;
pub mod mcp3208;
pub mod motor;
pub mod status;
