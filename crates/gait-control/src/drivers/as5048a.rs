//! AS5048A 14-bit absolute magnetic angle encoder over SPI (one per joint).
//!
//! Wire format (ams AS5048A datasheet, "SPI Interface"): 16-bit frames, MSB
//! first, SPI mode 1. In a command frame bit 15 is even parity over bits
//! 0..=14, bit 14 is R/W (1 = read) and bits 0..=13 the register address. In
//! a response frame bit 15 is parity, bit 14 the error flag (EF: the previous
//! command failed) and bits 0..=13 the data.
//!
//! # Read sequence (why two chip-select frames, not one)
//!
//! The chip executes a command on the rising edge of CSn and answers it in
//! the *next* frame. With CSn held low for 32 clocks the part behaves as a
//! daisy-chain shift register and the second half-word on MISO is the
//! command shifted through, not the answer. A single
//! [`SpiDevice::transaction`] keeps CS asserted for all of its operations, so
//! a register read is two transactions, each one 16-bit frame:
//!
//! 1. `transaction([TransferInPlace(command)])` — the reply (the answer to
//!    whatever came before) is discarded;
//! 2. `transaction([TransferInPlace(NOP read = 0xC000)])` — the reply is the
//!    answer to step 1 and is decoded.
//!
//! Frames travel as two `u8` words, most significant byte first, so any HAL's
//! 8-bit SPI works (the bits on the wire are the same as a 16-bit frame).
//!
//! # Errors
//!
//! Parity errors and the error flag are typed. When the chip raises EF the
//! driver immediately reads the Clear Error Flag register (which clears it)
//! and returns what it said in [`Error::ErrorFlag`]. Raw counts are exposed
//! in [`Reading`] so the supervisor can detect frozen values and impossible
//! jumps itself; this driver does not keep history.

use embedded_hal::spi::{Operation, SpiDevice};

/// Number of counts per revolution (14 bits).
pub const COUNTS_PER_REV: u16 = 1 << 14;
/// Mask of the 14 data / address bits.
pub const DATA_MASK: u16 = COUNTS_PER_REV - 1;

/// Register addresses used by this driver (datasheet, "Register Description").
pub mod reg {
    /// No operation; reading it collects the answer to the previous command.
    pub const NOP: u16 = 0x0000;
    /// Clear Error Flag: reading it returns and clears the error bits.
    pub const CLEAR_ERROR_FLAG: u16 = 0x0001;
    /// Diagnostics and automatic gain control.
    pub const DIAGNOSTICS_AGC: u16 = 0x3FFD;
    /// CORDIC magnitude.
    pub const MAGNITUDE: u16 = 0x3FFE;
    /// Angle with zero-position correction applied inside the chip.
    pub const ANGLE: u16 = 0x3FFF;
}

/// Bit 14 of a command: read (1) or write (0).
const RW_BIT: u16 = 1 << 14;
/// Bit 14 of a response: error flag.
const EF_BIT: u16 = 1 << 14;
/// Bit 15: even parity.
const PARITY_BIT: u16 = 1 << 15;

/// Why a response frame was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameError {
    /// The 16 bits do not have even parity: the frame was corrupted.
    Parity,
    /// The chip set EF: its previous command failed (see the error register).
    ErrorFlag,
}

/// Builds a command frame for register `addr` (only its low 14 bits are
/// used, so the function is total), with the R/W bit and even parity.
#[must_use]
pub const fn encode_command(addr: u16, read: bool) -> u16 {
    let mut frame = addr & DATA_MASK;
    if read {
        frame |= RW_BIT;
    }
    if odd_parity(frame) {
        frame |= PARITY_BIT;
    }
    frame
}

/// Whether `frame` has an odd number of ones. Folded to four bits and
/// looked up in a 16-bit table (0x6996: bit `n` is the parity of `n`):
/// the Cortex-M4 has no popcount, and `count_ones` costs twice as many
/// instructions on every frame the tick decodes.
const fn odd_parity(frame: u16) -> bool {
    let f = frame ^ (frame >> 8);
    let f = f ^ (f >> 4);
    (0x6996u16 >> (f & 0xF)) & 1 == 1
}

/// Decodes a response frame into its 14 data bits. Parity is checked first
/// (a corrupted frame says nothing reliable about EF), then the error flag.
/// Total: every `u16` gives `Ok` or an error.
pub const fn decode_response(frame: u16) -> Result<u16, FrameError> {
    if odd_parity(frame) {
        return Err(FrameError::Parity);
    }
    if frame & EF_BIT != 0 {
        return Err(FrameError::ErrorFlag);
    }
    Ok(frame & DATA_MASK)
}

/// Signed shortest change from `previous` to `current` raw counts, in
/// (−8192, 8192], wrap-aware. For the supervisor's frozen-value and
/// impossible-jump checks: at 1 kHz a joint at 10 rad/s moves 26 counts per
/// tick, so anything in the thousands is a bad read, not motion.
#[must_use]
pub const fn wrapped_delta(previous: u16, current: u16) -> i16 {
    Calibration {
        zero_offset_counts: previous,
        direction: Direction::Positive,
    }
    .signed_counts(current)
}

/// The chip's error register, as read from Clear Error Flag (0x0001).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorRegister {
    /// The chip saw a malformed frame (wrong number of clocks).
    pub framing: bool,
    /// The command addressed a register that does not exist.
    pub invalid_command: bool,
    /// The chip saw a command with bad parity.
    pub parity: bool,
}

impl ErrorRegister {
    /// Decodes the 14 data bits of the error register (bits 0, 1, 2).
    #[must_use]
    pub const fn from_bits(data: u16) -> Self {
        Self {
            framing: data & 0b001 != 0,
            invalid_command: data & 0b010 != 0,
            parity: data & 0b100 != 0,
        }
    }
}

/// The DIAGNOSTICS + AGC register (0x3FFD).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Diagnostics {
    /// Automatic gain control value: 0 = strong field, 255 = weak field.
    pub agc: u8,
    /// Offset compensation finished (must be set after power-up).
    pub offset_compensation_finished: bool,
    /// CORDIC overflow: the angle and magnitude are invalid.
    pub cordic_overflow: bool,
    /// Magnetic field too strong (magnet too close).
    pub comp_low: bool,
    /// Magnetic field too weak (magnet too far or missing).
    pub comp_high: bool,
}

impl Diagnostics {
    /// Decodes the 14 data bits of the diagnostics register.
    #[must_use]
    pub const fn from_bits(data: u16) -> Self {
        Self {
            agc: (data & 0xFF) as u8,
            offset_compensation_finished: data & (1 << 8) != 0,
            cordic_overflow: data & (1 << 9) != 0,
            comp_low: data & (1 << 10) != 0,
            comp_high: data & (1 << 11) != 0,
        }
    }

    /// True when the angle can be trusted: compensation done, no overflow,
    /// field within range.
    #[must_use]
    pub const fn is_healthy(&self) -> bool {
        self.offset_compensation_finished
            && !self.cordic_overflow
            && !self.comp_low
            && !self.comp_high
    }
}

/// Sense of rotation of the joint relative to the encoder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Direction {
    /// Joint angle grows with encoder counts.
    Positive,
    /// Joint angle shrinks as encoder counts grow (magnet seen from behind).
    Negative,
}

/// Per-joint calibration, measured once with the joint at its zero pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Calibration {
    /// Raw counts read at the joint's zero angle (only the low 14 bits count).
    pub zero_offset_counts: u16,
    /// Sense of rotation.
    pub direction: Direction,
}

impl Calibration {
    /// Signed counts from zero in (−8192, 8192], i.e. the angle in counts.
    /// Integer arithmetic so the half-open range is exact.
    #[must_use]
    pub const fn signed_counts(&self, raw: u16) -> i16 {
        let raw = raw & DATA_MASK;
        let zero = self.zero_offset_counts & DATA_MASK;
        let delta = match self.direction {
            Direction::Positive => raw.wrapping_sub(zero) & DATA_MASK,
            Direction::Negative => zero.wrapping_sub(raw) & DATA_MASK,
        };
        // delta in 0..16384; fold the upper half to negatives, 8192 stays +.
        if delta > COUNTS_PER_REV / 2 {
            delta as i16 - COUNTS_PER_REV as i16
        } else {
            delta as i16
        }
    }

    /// Joint angle in radians in (−π, π].
    #[must_use]
    pub fn counts_to_rad(&self, raw: u16) -> f32 {
        const RAD_PER_COUNT: f32 = 2.0 * core::f32::consts::PI / COUNTS_PER_REV as f32;
        f32::from(self.signed_counts(raw)) * RAD_PER_COUNT
    }
}

/// One angle sample: the raw counts (for the supervisor's frozen-value and
/// jump checks) and the calibrated joint angle.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Reading {
    /// Raw 14-bit counts as read from the ANGLE register.
    pub raw_counts: u16,
    /// Calibrated joint angle in radians, in (−π, π].
    pub angle_rad: f32,
}

/// An angle read's reply frame as a [`Reading`] under `calibration`, or
/// why it is not one (the same outcome as [`As5048a::read_angle`] gives
/// for that reply).
pub fn decode_angle(frame: u16, calibration: Calibration) -> Result<Reading, ReadStatus> {
    match decode_response(frame) {
        Ok(raw_counts) => Ok(Reading {
            raw_counts,
            angle_rad: calibration.counts_to_rad(raw_counts),
        }),
        Err(FrameError::Parity) => Err(ReadStatus::Parity),
        Err(FrameError::ErrorFlag) => Err(ReadStatus::ErrorFlag),
    }
}

super::read_status! {
    /// The outcome of one read, without the bus's own error type: the kind
    /// of a driver error, which the supervisor counts as it is
    /// ([`crate::supervisor::EncoderStatus`]).
    ReadStatus {
        /// A frame with good parity and no error flag.
        Ok,
        /// The reply failed its parity check.
        Parity,
        /// The chip raised its error flag.
        ErrorFlag,
    }
}

/// Driver errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<E> {
    /// The SPI bus or chip select failed.
    Bus(E),
    /// The response frame failed the parity check.
    Parity,
    /// The chip flagged an error; it has been cleared by reading the Clear
    /// Error Flag register, whose contents are given (`None` if that answer
    /// itself failed its parity check).
    ErrorFlag(Option<ErrorRegister>),
}

impl<E> Error<E> {
    /// What kind of failure this is ([`ReadStatus`], never `Ok`).
    pub fn kind(&self) -> ReadStatus {
        match self {
            Self::Bus(_) => ReadStatus::BusError,
            Self::Parity => ReadStatus::Parity,
            Self::ErrorFlag(_) => ReadStatus::ErrorFlag,
        }
    }
}

/// An AS5048A on its own chip select.
#[derive(Debug)]
pub struct As5048a<SPI> {
    spi: SPI,
    calibration: Calibration,
}

impl<SPI> As5048a<SPI> {
    /// Wraps a configured SPI device (mode 1, ≤ 10 MHz).
    pub const fn new(spi: SPI, calibration: Calibration) -> Self {
        Self { spi, calibration }
    }

    /// Gives the SPI device back.
    pub fn destroy(self) -> SPI {
        self.spi
    }

    /// The calibration in use.
    pub const fn calibration(&self) -> Calibration {
        self.calibration
    }
}

impl<SPI, E> As5048a<SPI>
where
    SPI: SpiDevice<u8, Error = E>,
{
    /// One 16-bit frame in its own chip-select window; returns the reply
    /// (the answer to the command before).
    pub fn frame(&mut self, command: u16) -> Result<u16, Error<E>> {
        let mut buf = command.to_be_bytes();
        self.spi
            .transaction(&mut [Operation::TransferInPlace(&mut buf)])
            .map_err(Error::Bus)?;
        Ok(u16::from_be_bytes(buf))
    }

    /// Reads a register: the command frame, then a NOP frame whose reply is
    /// the answer (see the module docs). On EF, clears the flag (two more
    /// frames) and reports the error register.
    pub fn read_register(&mut self, addr: u16) -> Result<u16, Error<E>> {
        let _previous = self.frame(encode_command(addr, true))?;
        let reply = self.frame(encode_command(reg::NOP, true))?;
        match decode_response(reply) {
            Ok(data) => Ok(data),
            Err(FrameError::Parity) => Err(Error::Parity),
            Err(FrameError::ErrorFlag) => Err(Error::ErrorFlag(self.clear_error()?)),
        }
    }

    /// Reads (and so clears) the error register. `Ok(None)` if its answer
    /// failed parity or still carried EF.
    pub fn clear_error(&mut self) -> Result<Option<ErrorRegister>, Error<E>> {
        let _previous = self.frame(encode_command(reg::CLEAR_ERROR_FLAG, true))?;
        let reply = self.frame(encode_command(reg::NOP, true))?;
        Ok(decode_response(reply).ok().map(ErrorRegister::from_bits))
    }

    /// Reads the angle register and returns its reply frame undecoded, for
    /// [`decode_angle`] (the tick decodes what an acquisition ahead of it
    /// read, `crate::acquisition`). On a reply with good parity and EF the
    /// flag is cleared at once, as [`Self::read_register`] does; a failed
    /// clear is a bus error.
    pub fn read_angle_frame(&mut self) -> Result<u16, Error<E>> {
        let _previous = self.frame(encode_command(reg::ANGLE, true))?;
        let reply = self.frame(encode_command(reg::NOP, true))?;
        if let Err(FrameError::ErrorFlag) = decode_response(reply) {
            self.clear_error()?;
        }
        Ok(reply)
    }

    /// Reads the angle: raw counts and the calibrated angle.
    pub fn read_angle(&mut self) -> Result<Reading, Error<E>> {
        let raw_counts = self.read_register(reg::ANGLE)?;
        Ok(Reading {
            raw_counts,
            angle_rad: self.calibration.counts_to_rad(raw_counts),
        })
    }

    /// Reads the CORDIC magnitude (field strength, raw 14 bits).
    pub fn read_magnitude(&mut self) -> Result<u16, Error<E>> {
        self.read_register(reg::MAGNITUDE)
    }

    /// Reads the diagnostics and AGC register.
    pub fn read_diagnostics(&mut self) -> Result<Diagnostics, Error<E>> {
        self.read_register(reg::DIAGNOSTICS_AGC)
            .map(Diagnostics::from_bits)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn odd_parity_is_the_parity_of_every_frame() {
        for f in 0..=u16::MAX {
            assert_eq!(super::odd_parity(f), f.count_ones() % 2 == 1, "{f:#06x}");
        }
    }
}
