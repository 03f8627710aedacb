//! A simulated ams AS5048A magnetic angle encoder on its own chip select.
//!
//! Written from the datasheet (SPI interface, register map), not from
//! gait-control's driver:
//!
//! - 16-bit frames, MSB first. Command: bit 15 even parity over bits 0..14,
//!   bit 14 R/W (1 = read), bits 13..0 address. Response: bit 15 even parity,
//!   bit 14 error flag (EF), bits 13..0 data.
//! - The chip executes the command latched at the rising edge of CSn and
//!   answers it in the **next** frame. With CSn held low for more than 16
//!   clocks it behaves as a shift register (daisy chain): after its own 16
//!   output bits it shifts out what it received, and only the last 16 bits
//!   in are the command. A window that is not a multiple of 16 clocks is a
//!   framing error.
//! - A command with bad parity, an unknown address or a framing error set
//!   the matching bit of the error register (framing 0, invalid command 1,
//!   parity 2) and EF in every response until Clear Error Flag (0x0001) is
//!   read; the answer to that read carries the error bits with EF clear.
//! - A write command is followed by a data frame (also with parity); the
//!   zero-position registers (0x0016: high 8 bits, 0x0017: low 6 bits) are
//!   subtracted from the angle, like the chip's OTP zero.
//!
//! The magnet's angle comes from a [`SharedF64`] (the joint angle in rad,
//! written by the harness each tick) through a per-joint mounting offset and
//! direction, quantised to 14 bits.

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::spi::{self, ErrorType, Operation, SpiDevice};

use crate::shared::SharedF64;
use crate::spi::{BusFaults, SimSpiError, answer, bits_msb_first, bytes_msb_first};

/// Counts per revolution.
const COUNTS: i64 = 1 << 14;
const MASK: u16 = 0x3FFF;

/// Register addresses (datasheet register map).
pub mod addr {
    /// No operation.
    pub const NOP: u16 = 0x0000;
    /// Clear Error Flag.
    pub const CLEAR_ERROR_FLAG: u16 = 0x0001;
    /// Programming control.
    pub const PROGRAMMING_CONTROL: u16 = 0x0003;
    /// OTP zero position, high 8 bits.
    pub const ZERO_HIGH: u16 = 0x0016;
    /// OTP zero position, low 6 bits.
    pub const ZERO_LOW: u16 = 0x0017;
    /// Diagnostics and AGC.
    pub const DIAGNOSTICS: u16 = 0x3FFD;
    /// CORDIC magnitude.
    pub const MAGNITUDE: u16 = 0x3FFE;
    /// Angle (zero position applied).
    pub const ANGLE: u16 = 0x3FFF;
}

/// Error register bits (what Clear Error Flag returns).
pub mod error_bit {
    /// Framing error.
    pub const FRAMING: u16 = 1 << 0;
    /// Invalid command.
    pub const INVALID_COMMAND: u16 = 1 << 1;
    /// Parity error.
    pub const PARITY: u16 = 1 << 2;
}

/// Which way the magnet turns with the joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mounting {
    /// Counts grow with the joint angle.
    Positive,
    /// Counts fall as the joint angle grows.
    Negative,
}

/// How the encoder is mounted on its joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncoderMount {
    /// Raw counts at joint angle 0.
    pub zero_counts: u16,
    /// Direction.
    pub mounting: Mounting,
}

/// Adds even parity in bit 15 to a 15-bit word.
fn with_parity(word: u16) -> u16 {
    let w = word & 0x7FFF;
    if w.count_ones() % 2 == 1 {
        w | 0x8000
    } else {
        w
    }
}

/// The chip's state.
#[derive(Debug)]
struct Chip {
    angle: SharedF64,
    mount: EncoderMount,
    /// The response loaded for the next frame.
    output: u16,
    error_bits: u16,
    pending_write: Option<u16>,
    zero_high: u16,
    zero_low: u16,
    programming_control: u16,
    magnitude: u16,
    agc: u8,
    weak_field: bool,
    // Fault injection.
    bus_faults: BusFaults,
    corrupt_answers: u32,
    frozen: Option<u16>,
    jump_counts: i64,
    transactions: u64,
    noise: crate::noise::Noise,
}

impl Chip {
    /// An encoder reading `angle` (rad) through `mount`. Powers up with
    /// offset compensation finished, a healthy field and no error.
    fn new(angle: SharedF64, mount: EncoderMount) -> Self {
        Self {
            angle,
            mount,
            output: 0,
            error_bits: 0,
            pending_write: None,
            zero_high: 0,
            zero_low: 0,
            programming_control: 0,
            magnitude: 0x0F00,
            agc: 0x80,
            weak_field: false,
            bus_faults: BusFaults::default(),
            corrupt_answers: 0,
            frozen: None,
            jump_counts: 0,
            transactions: 0,
            noise: crate::noise::Noise::none(),
        }
    }

    /// The raw sensor counts for the current angle (before the chip's zero
    /// position), with freeze and jump applied.
    fn raw_counts(&self) -> u16 {
        if let Some(c) = self.frozen {
            return c;
        }
        self.live_counts()
    }

    fn live_counts(&self) -> u16 {
        let per_rad = COUNTS as f64 / std::f64::consts::TAU;
        let a = self.angle.get();
        let a = if a.is_finite() { a } else { 0.0 };
        let signed = match self.mount.mounting {
            Mounting::Positive => (a * per_rad).round() as i64,
            Mounting::Negative => -(a * per_rad).round() as i64,
        };
        let c =
            (i64::from(self.mount.zero_counts) + signed + self.jump_counts + self.noise.sample())
                .rem_euclid(COUNTS);
        u16::try_from(c).unwrap_or(0)
    }

    /// The ANGLE register: raw counts minus the programmed zero position.
    fn angle_register(&self) -> u16 {
        let zero = ((self.zero_high & 0xFF) << 6) | (self.zero_low & 0x3F);
        self.raw_counts().wrapping_sub(zero) & MASK
    }

    fn diagnostics_register(&self) -> u16 {
        let ocf = 1 << 8;
        let comp_high = if self.weak_field { 1 << 11 } else { 0 };
        u16::from(self.agc) | ocf | comp_high
    }

    /// Fault: set bits of the error register (see [`error_bit`]), as if the
    /// chip had seen a bad frame; EF appears in the next response.
    fn raise_error(&mut self, bits: u16) {
        self.error_bits |= bits & 0b111;
        self.output |= 1 << 14;
        self.output = with_parity(self.output);
    }

    /// Fault: the reading sticks at its present value (`true`) or follows
    /// the joint again (`false`).
    fn freeze(&mut self, frozen: bool) {
        self.frozen = if frozen {
            Some(self.live_counts())
        } else {
            None
        };
    }

    /// Fault: the reading jumps by `counts` and stays offset (cumulative).
    fn jump(&mut self, counts: i32) {
        self.jump_counts += i64::from(counts);
        if let Some(f) = self.frozen {
            let c = (i64::from(f) + i64::from(counts)).rem_euclid(COUNTS);
            self.frozen = Some(u16::try_from(c).unwrap_or(0));
        }
    }

    /// Fault: the magnet is too far (weak field: COMP high, low magnitude).
    fn set_weak_field(&mut self, weak: bool) {
        self.weak_field = weak;
        self.magnitude = if weak { 0x0040 } else { 0x0F00 };
        self.agc = if weak { 0xFF } else { 0x80 };
    }

    /// The response frame carrying `data` (EF if any error bit is set).
    fn respond(&self, data: u16) -> u16 {
        let ef = if self.error_bits != 0 { 1 << 14 } else { 0 };
        with_parity((data & MASK) | ef)
    }

    /// Executes the command latched at the end of a frame.
    fn execute(&mut self, frame: u16) {
        if frame.count_ones() % 2 == 1 {
            self.error_bits |= error_bit::PARITY;
            self.pending_write = None;
            self.output = self.respond(0);
            return;
        }
        if let Some(target) = self.pending_write.take() {
            let data = frame & MASK;
            let old = self.register(target).unwrap_or(0);
            match target {
                addr::ZERO_HIGH => self.zero_high = data & 0xFF,
                addr::ZERO_LOW => self.zero_low = data & 0x3F,
                _ => self.programming_control = data & 0xFF,
            }
            self.output = self.respond(old);
            return;
        }
        let read = frame & (1 << 14) != 0;
        let a = frame & MASK;
        if read {
            if a == addr::CLEAR_ERROR_FLAG {
                let bits = self.error_bits;
                self.error_bits = 0;
                self.output = with_parity(bits);
                return;
            }
            match self.register(a) {
                Some(v) => {
                    let mut out = self.respond(v);
                    if a != addr::NOP && self.corrupt_answers > 0 {
                        self.corrupt_answers -= 1;
                        out ^= 1 << 3;
                    }
                    self.output = out;
                }
                None => {
                    self.error_bits |= error_bit::INVALID_COMMAND;
                    self.output = self.respond(0);
                }
            }
        } else {
            match a {
                addr::PROGRAMMING_CONTROL | addr::ZERO_HIGH | addr::ZERO_LOW => {
                    self.pending_write = Some(a);
                    let old = self.register(a).unwrap_or(0);
                    self.output = self.respond(old);
                }
                _ => {
                    self.error_bits |= error_bit::INVALID_COMMAND;
                    self.output = self.respond(0);
                }
            }
        }
    }

    fn register(&self, a: u16) -> Option<u16> {
        match a {
            addr::NOP => Some(0),
            addr::PROGRAMMING_CONTROL => Some(self.programming_control),
            addr::ZERO_HIGH => Some(self.zero_high),
            addr::ZERO_LOW => Some(self.zero_low),
            addr::DIAGNOSTICS => Some(self.diagnostics_register()),
            addr::MAGNITUDE => Some(self.magnitude),
            addr::ANGLE => Some(self.angle_register()),
            _ => None,
        }
    }

    /// One chip-select window of clocked bytes; returns MISO.
    fn window(&mut self, mosi: &[u8]) -> Vec<u8> {
        let bits_in = bits_msb_first(mosi);
        let n = bits_in.len();
        let out_word: Vec<bool> = (0..16).rev().map(|i| self.output & (1 << i) != 0).collect();
        // Shift register: our 16 output bits, then what came in, delayed.
        let bits_out: Vec<bool> = (0..n)
            .map(|i| {
                if i < 16 {
                    out_word.get(i).copied().unwrap_or(false)
                } else {
                    bits_in.get(i - 16).copied().unwrap_or(false)
                }
            })
            .collect();
        if n == 0 {
            return Vec::new();
        }
        if !n.is_multiple_of(16) {
            self.error_bits |= error_bit::FRAMING;
            self.pending_write = None;
            self.output = self.respond(0);
        } else {
            let cmd = bits_in
                .get(n - 16..)
                .unwrap_or(&[])
                .iter()
                .fold(0u16, |acc, &b| (acc << 1) | u16::from(b));
            self.execute(cmd);
        }
        bytes_msb_first(&bits_out)
    }
}

/// One simulated AS5048A. Clones are handles on the same chip: give one to
/// the driver and keep one to inject faults.
#[derive(Clone, Debug)]
pub struct SimAs5048a(Rc<RefCell<Chip>>);

impl SimAs5048a {
    /// An encoder reading `angle` (rad) through `mount`. Powers up with
    /// offset compensation finished, a healthy field and no error.
    pub fn new(angle: SharedF64, mount: EncoderMount) -> Self {
        Self(Rc::new(RefCell::new(Chip::new(angle, mount))))
    }

    /// The raw sensor counts for the current angle (before the chip's zero
    /// position), with freeze and jump applied.
    pub fn raw_counts(&self) -> u16 {
        self.0.borrow().raw_counts()
    }

    /// What the ANGLE register reads now (zero position applied; noise
    /// sampled once, so record with noise off).
    pub fn angle_register(&self) -> u16 {
        self.0.borrow().angle_register()
    }

    /// Transactions seen (including failed ones).
    pub fn transactions(&self) -> u64 {
        self.0.borrow().transactions
    }

    /// The error register as the chip holds it now.
    pub fn error_bits(&self) -> u16 {
        self.0.borrow().error_bits
    }

    /// Fault: the next `n` transactions fail on the bus with `kind` (the
    /// chip sees nothing of them).
    pub fn fail_transactions(&self, n: u32, kind: spi::ErrorKind) {
        self.0.borrow_mut().bus_faults.fail_next(n, kind);
    }

    /// Fault: the answers to the next `n` register reads (other than NOP)
    /// arrive with one data bit flipped, so their parity is wrong.
    pub fn corrupt_answers(&self, n: u32) {
        self.0.borrow_mut().corrupt_answers = n;
    }

    /// Fault: set bits of the error register (see [`error_bit`]), as if the
    /// chip had seen a bad frame; EF appears from the next response on.
    pub fn raise_error(&self, bits: u16) {
        self.0.borrow_mut().raise_error(bits);
    }

    /// Fault: the reading sticks at its present value (`true`) or follows
    /// the joint again (`false`).
    pub fn freeze(&self, frozen: bool) {
        self.0.borrow_mut().freeze(frozen);
    }

    /// Fault: the reading jumps by `counts` and stays offset (cumulative).
    pub fn jump(&self, counts: i32) {
        self.0.borrow_mut().jump(counts);
    }

    /// Measurement noise: every reading off by a uniform ±`counts` (the
    /// datasheet's output noise is about 0.06° RMS, 3 counts peak), seeded.
    pub fn set_noise(&self, counts: u16, seed: u64) {
        self.0.borrow_mut().noise = crate::noise::Noise::new(counts, seed);
    }

    /// Fault: the magnet is too far (weak field: COMP high, low magnitude,
    /// AGC at maximum).
    pub fn set_weak_field(&self, weak: bool) {
        self.0.borrow_mut().set_weak_field(weak);
    }
}

impl ErrorType for SimAs5048a {
    type Error = SimSpiError;
}

impl SpiDevice<u8> for SimAs5048a {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), SimSpiError> {
        let mut chip = self.0.borrow_mut();
        chip.transactions += 1;
        chip.bus_faults.take()?;
        answer(operations, |mosi| chip.window(mosi));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(dev: &mut SimAs5048a, word: u16) -> u16 {
        let mut b = word.to_be_bytes();
        dev.transaction(&mut [Operation::TransferInPlace(&mut b)])
            .unwrap_or_else(|_| unreachable!());
        u16::from_be_bytes(b)
    }

    #[test]
    fn parity_of_known_commands() {
        // Datasheet examples: read ANGLE = 0xFFFF, read NOP = 0xC000.
        assert_eq!(with_parity((1 << 14) | addr::ANGLE), 0xFFFF);
        assert_eq!(with_parity(1 << 14), 0xC000);
        // Clear Error Flag read: 0x4001 has two ones → parity 0.
        assert_eq!(with_parity((1 << 14) | addr::CLEAR_ERROR_FLAG), 0x4001);
    }

    #[test]
    fn answer_comes_one_frame_late_and_zero_position_applies() {
        let angle = SharedF64::new(0.0);
        let mut dev = SimAs5048a::new(
            angle.clone(),
            EncoderMount {
                zero_counts: 1000,
                mounting: Mounting::Positive,
            },
        );
        assert_eq!(frame(&mut dev, 0xFFFF), 0); // power-up output
        assert_eq!(frame(&mut dev, 0xC000), with_parity(1000));
        // Program the zero position to 1000 = 0b1111_101000 → high 15, low 40.
        let w = |a: u16| with_parity(a);
        frame(&mut dev, w(addr::ZERO_HIGH));
        frame(&mut dev, w(15));
        frame(&mut dev, w(addr::ZERO_LOW));
        frame(&mut dev, w(40));
        frame(&mut dev, 0xFFFF);
        assert_eq!(frame(&mut dev, 0xC000), with_parity(0));
    }

    #[test]
    fn bad_parity_and_framing_set_the_flag() {
        let mut dev = SimAs5048a::new(
            SharedF64::new(0.0),
            EncoderMount {
                zero_counts: 0,
                mounting: Mounting::Positive,
            },
        );
        frame(&mut dev, 0x7FFF); // read ANGLE without parity bit
        let r = frame(&mut dev, 0xC000);
        assert_ne!(r & (1 << 14), 0);
        frame(&mut dev, with_parity((1 << 14) | addr::CLEAR_ERROR_FLAG));
        let r = frame(&mut dev, 0xC000);
        assert_eq!(r, with_parity(error_bit::PARITY));
        // 24 clocks in one window: framing error.
        let mut b = [0xC0, 0x00, 0x00];
        dev.transaction(&mut [Operation::TransferInPlace(&mut b)])
            .unwrap_or_else(|_| unreachable!());
        assert_eq!(dev.error_bits(), error_bit::FRAMING);
        assert_eq!(dev.transactions(), 5);
    }

    #[test]
    fn long_window_shifts_the_input_through() {
        let mut dev = SimAs5048a::new(
            SharedF64::new(0.0),
            EncoderMount {
                zero_counts: 77,
                mounting: Mounting::Positive,
            },
        );
        let mut b = [0xFF, 0xFF, 0xC0, 0x00];
        dev.transaction(&mut [Operation::TransferInPlace(&mut b)])
            .unwrap_or_else(|_| unreachable!());
        // First half-word: power-up output; second: the first command echoed.
        assert_eq!(b, [0x00, 0x00, 0xFF, 0xFF]);
        // Only the last 16 bits (NOP) were the command.
        assert_eq!(frame(&mut dev, 0xC000), 0);
    }
}
