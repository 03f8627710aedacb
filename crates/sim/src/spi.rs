//! What every simulated SPI device shares: the bus error type and the
//! flattening of an embedded-hal transaction into the bytes the chip sees.
//!
//! A [`SpiDevice`](embedded_hal::spi::SpiDevice) transaction is one
//! chip-select window. Whatever mix of operations the driver uses, the chip
//! sees one continuous stream of clocked bytes: this module turns the
//! operations into that stream (MOSI), lets the device model answer it byte
//! for byte (MISO), and hands the answer back to the operations that read.

use embedded_hal::spi::{self, Operation};

/// A simulated SPI bus failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SimSpiError {
    /// What embedded-hal calls it.
    pub kind: spi::ErrorKind,
}

impl spi::Error for SimSpiError {
    fn kind(&self) -> spi::ErrorKind {
        self.kind
    }
}

impl core::fmt::Display for SimSpiError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "simulated SPI error: {}", self.kind)
    }
}

impl std::error::Error for SimSpiError {}

/// Bus failures queued on a simulated chip by fault injection: the next
/// `count` transactions fail with `kind`, and the chip sees nothing of
/// them.
#[derive(Clone, Copy, Debug)]
pub struct BusFaults {
    count: u32,
    kind: spi::ErrorKind,
}

impl Default for BusFaults {
    fn default() -> Self {
        Self {
            count: 0,
            kind: spi::ErrorKind::Other,
        }
    }
}

impl BusFaults {
    /// The next `n` transactions fail with `kind` (replacing what was
    /// queued).
    pub fn fail_next(&mut self, n: u32, kind: spi::ErrorKind) {
        self.count = n;
        self.kind = kind;
    }

    /// Takes one transaction: `Err` while failures are queued.
    pub fn take(&mut self) -> Result<(), SimSpiError> {
        if self.count > 0 {
            self.count -= 1;
            return Err(SimSpiError { kind: self.kind });
        }
        Ok(())
    }
}

/// One chip-select window that reached the chip: `window` answers the
/// MOSI stream byte for byte, and its answer goes back to the operations
/// that read.
pub fn answer(operations: &mut [Operation<'_, u8>], window: impl FnOnce(&[u8]) -> Vec<u8>) {
    let miso = window(&mosi_bytes(operations));
    deliver_miso(operations, &miso);
}

/// The bytes shifted out on MOSI during the whole transaction. Bytes a
/// `Read` clocks (and the tail of a shorter `Transfer` write buffer) are
/// 0x00, as most HALs send.
pub fn mosi_bytes(operations: &[Operation<'_, u8>]) -> Vec<u8> {
    let mut out = Vec::new();
    for op in operations {
        match op {
            Operation::Read(buf) => out.extend(std::iter::repeat_n(0u8, buf.len())),
            Operation::Write(buf) => out.extend_from_slice(buf),
            Operation::Transfer(read, write) => {
                let n = read.len().max(write.len());
                out.extend((0..n).map(|i| write.get(i).copied().unwrap_or(0)));
            }
            Operation::TransferInPlace(buf) => out.extend_from_slice(buf),
            Operation::DelayNs(_) => {}
        }
    }
    out
}

/// Hands the MISO stream back to the operations that read, in order.
pub fn deliver_miso(operations: &mut [Operation<'_, u8>], miso: &[u8]) {
    let mut pos = 0usize;
    let take = |dst: &mut [u8], clocked: usize, pos: &mut usize| {
        for (i, d) in dst.iter_mut().enumerate().take(clocked) {
            *d = miso.get(*pos + i).copied().unwrap_or(0xFF);
        }
        *pos += clocked;
    };
    for op in operations.iter_mut() {
        match op {
            Operation::Read(buf) => {
                let n = buf.len();
                take(buf, n, &mut pos);
            }
            Operation::Write(buf) => pos += buf.len(),
            Operation::Transfer(read, write) => {
                let n = read.len().max(write.len());
                take(read, n, &mut pos);
            }
            Operation::TransferInPlace(buf) => {
                let n = buf.len();
                take(buf, n, &mut pos);
            }
            Operation::DelayNs(_) => {}
        }
    }
}

/// Bits of a byte stream, MSB first (SPI mode 0/1 with MSB-first framing).
pub fn bits_msb_first(bytes: &[u8]) -> Vec<bool> {
    bytes
        .iter()
        .flat_map(|b| (0..8).rev().map(move |i| b & (1 << i) != 0))
        .collect()
}

/// Packs bits MSB first into bytes (a trailing partial byte is padded with
/// zeros; callers give whole bytes).
pub fn bytes_msb_first(bits: &[bool]) -> Vec<u8> {
    bits.chunks(8)
        .map(|c| {
            c.iter()
                .enumerate()
                .fold(0u8, |acc, (i, &b)| acc | (u8::from(b) << (7 - i)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_round_trip_and_operation_order() {
        let bytes = [0xA5, 0x3C];
        assert_eq!(bytes_msb_first(&bits_msb_first(&bytes)), bytes);
        let mut r = [0u8; 2];
        let w = [1u8, 2, 3];
        let mut ip = [9u8];
        {
            let mut ops = [
                Operation::Write(&[7]),
                Operation::Transfer(&mut r, &w),
                Operation::TransferInPlace(&mut ip),
            ];
            assert_eq!(mosi_bytes(&ops), vec![7, 1, 2, 3, 9]);
            deliver_miso(&mut ops, &[10, 11, 12, 13, 14]);
        }
        assert_eq!(r, [11, 12]);
        assert_eq!(ip, [14]);
    }
}
