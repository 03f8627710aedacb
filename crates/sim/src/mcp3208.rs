//! A simulated Microchip MCP3208 8-channel 12-bit ADC reading the
//! force-sensing resistors, written from the datasheet (section 5/6):
//!
//! - DOUT is high-impedance until the chip has seen the start bit: the
//!   first 1 clocked in on DIN after CS falls. The next four bits are
//!   SGL/DIFF and D2 D1 D0. The input is sampled over the next clock and a
//!   half; on the falling edge after that the chip drives the null bit (0),
//!   then B11…B0 MSB first (so, counting from the start bit at s, the null
//!   bit is bit s+6 and B11 is bit s+7). If clocks continue it repeats the
//!   result LSB first (B1…B11), then drives zeros.
//! - SGL/DIFF = 0 selects a pseudo-differential pair (CH0−CH1, CH1−CH0, …);
//!   the result is IN+ − IN−, floored at 0.
//!
//! High-impedance bits read back as `hi_z_level` (default 1, as with a
//! pull-up), so a driver that forgets to mask them is caught.
//!
//! Each channel converts a force from a [`SharedF64`] (N) through a linear
//! sensor-plus-amplifier model `counts = offset + gain·N`, clamped to the
//! 12-bit range; faults force the rails (open: 0, short: 4095).

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::spi::{self, ErrorType, Operation, SpiDevice};

use crate::shared::SharedF64;
use crate::spi::{BusFaults, SimSpiError, answer, bits_msb_first, bytes_msb_first};

/// Largest count.
pub const FULL_SCALE: u16 = 4095;

/// A force sensor's conversion to counts (what a calibration on the
/// controller side has to invert).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceSensorCal {
    /// Counts at zero force (kept above 0 so an open sensor is told apart).
    pub offset_counts: f64,
    /// Counts per newton.
    pub counts_per_n: f64,
}

impl ForceSensorCal {
    /// A foot sensor: 200 counts unloaded, 1.75 counts/N (≈ 2,200 N to
    /// full scale: a landing on one foot peaks well above body weight).
    pub const FOOT: Self = Self {
        offset_counts: 200.0,
        counts_per_n: 1.75,
    };
    /// A crutch-tip sensor: 200 counts unloaded, 7 counts/N (≈ 560 N).
    pub const CRUTCH: Self = Self {
        offset_counts: 200.0,
        counts_per_n: 7.0,
    };

    /// Counts for a force (rounded, clamped to 0…4095; NaN reads 0).
    pub fn counts(&self, newtons: f64) -> u16 {
        let c = (self.offset_counts + self.counts_per_n * newtons).round();
        if c.is_nan() {
            0
        } else {
            c.clamp(0.0, f64::from(FULL_SCALE)) as u16
        }
    }

    /// The force a count stands for (the exact inverse of the unclamped map).
    pub fn newtons(&self, counts: u16) -> f64 {
        (f64::from(counts) - self.offset_counts) / self.counts_per_n
    }
}

/// An injected channel fault.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChannelFault {
    /// Sensor or cable open: the input is pulled to ground (0 counts).
    Open,
    /// Shorted to the reference: 4095 counts.
    Short,
    /// The sensor reads this force, N, whatever it carries (over range:
    /// an overload or a failing bridge amplifier).
    Reads(f64),
    /// The sensor reads this much more than it carries, N (a spike).
    Adds(f64),
}

#[derive(Clone, Debug)]
struct Input {
    source: SharedF64,
    cal: ForceSensorCal,
    fault: Option<ChannelFault>,
}

/// The chip's state.
#[derive(Debug)]
struct Chip {
    inputs: [Option<Input>; 8],
    hi_z_level: bool,
    bus_faults: BusFaults,
    conversions: u64,
    noise: crate::noise::Noise,
}

impl Chip {
    fn new() -> Self {
        Self {
            inputs: Default::default(),
            hi_z_level: true,
            bus_faults: BusFaults::default(),
            conversions: 0,
            noise: crate::noise::Noise::none(),
        }
    }

    /// What a single-ended conversion of `channel` gives now.
    fn counts(&self, channel: usize) -> u16 {
        match self.inputs.get(channel) {
            Some(Some(input)) => match input.fault {
                Some(ChannelFault::Open) => 0,
                Some(ChannelFault::Short) => FULL_SCALE,
                Some(ChannelFault::Reads(n)) => input.cal.counts(n),
                Some(ChannelFault::Adds(n)) => input.cal.counts(input.source.get() + n),
                None => input.cal.counts(input.source.get()),
            },
            _ => 0,
        }
    }

    /// A conversion: the input's counts plus measurement noise (not on an
    /// open, shorted or unconnected input: those sit at a rail).
    fn noisy_counts(&self, channel: usize) -> u16 {
        let c = self.counts(channel);
        match self.inputs.get(channel) {
            Some(Some(input))
                if !matches!(input.fault, Some(ChannelFault::Open | ChannelFault::Short)) =>
            {
                let v = (i64::from(c) + self.noise.sample()).clamp(0, i64::from(FULL_SCALE));
                u16::try_from(v).unwrap_or(c)
            }
            _ => c,
        }
    }

    fn convert(&self, single: bool, d: usize) -> u16 {
        if single {
            self.noisy_counts(d)
        } else {
            // Pairs (0,1), (2,3), …; odd code swaps polarity.
            let pair = d & !1;
            let (p, n) = if d & 1 == 0 {
                (pair, pair + 1)
            } else {
                (pair + 1, pair)
            };
            self.noisy_counts(p).saturating_sub(self.noisy_counts(n))
        }
    }

    fn window(&mut self, mosi: &[u8]) -> Vec<u8> {
        let din = bits_msb_first(mosi);
        let mut dout = vec![self.hi_z_level; din.len()];
        if let Some(s) = din.iter().position(|&b| b) {
            let bit = |i: usize| din.get(s + i).copied();
            if let (Some(sgl), Some(d2), Some(d1), Some(d0)) = (bit(1), bit(2), bit(3), bit(4)) {
                let ch = usize::from(d2) << 2 | usize::from(d1) << 1 | usize::from(d0);
                let value = self.convert(sgl, ch);
                self.conversions += 1;
                for (i, out) in dout.iter_mut().enumerate().skip(s + 6) {
                    let k = i - (s + 6);
                    *out = match k {
                        0 => false, // null bit
                        1..=12 => value & (1 << (12 - k)) != 0,
                        13..=23 => value & (1 << (k - 12)) != 0, // LSB first, B1…B11
                        _ => false,
                    };
                }
            }
        }
        bytes_msb_first(&dout)
    }
}

/// One simulated MCP3208. Clones are handles on the same chip: give one to
/// the driver and keep one to inject faults.
#[derive(Clone, Debug)]
pub struct SimMcp3208(Rc<RefCell<Chip>>);

impl Default for SimMcp3208 {
    fn default() -> Self {
        Self::new()
    }
}

impl SimMcp3208 {
    /// An ADC with nothing connected (unconnected inputs read 0).
    pub fn new() -> Self {
        Self(Rc::new(RefCell::new(Chip::new())))
    }

    /// Connects a force sensor to `channel` (0…7; others are ignored).
    pub fn connect(&self, channel: usize, source: SharedF64, cal: ForceSensorCal) {
        if let Some(slot) = self.0.borrow_mut().inputs.get_mut(channel) {
            *slot = Some(Input {
                source,
                cal,
                fault: None,
            });
        }
    }

    /// Level read on MISO while DOUT is high-impedance (default high).
    pub fn set_hi_z_level(&self, high: bool) {
        self.0.borrow_mut().hi_z_level = high;
    }

    /// Fault on one channel (`None` repairs it).
    pub fn set_fault(&self, channel: usize, fault: Option<ChannelFault>) {
        if let Some(Some(input)) = self.0.borrow_mut().inputs.get_mut(channel) {
            input.fault = fault;
        }
    }

    /// Measurement noise on every conversion of a connected, healthy
    /// input: a uniform ±`counts` (the datasheet's INL/DNL and input noise
    /// are about ±1 LSB; force sensors and their wiring add more), seeded.
    pub fn set_noise(&self, counts: u16, seed: u64) {
        self.0.borrow_mut().noise = crate::noise::Noise::new(counts, seed);
    }

    /// Fault: the next `n` transactions fail on the bus with `kind`.
    pub fn fail_transactions(&self, n: u32, kind: spi::ErrorKind) {
        self.0.borrow_mut().bus_faults.fail_next(n, kind);
    }

    /// Conversions performed (start bits seen).
    pub fn conversions(&self) -> u64 {
        self.0.borrow().conversions
    }

    /// What a single-ended conversion of `channel` gives now.
    pub fn counts(&self, channel: usize) -> u16 {
        self.0.borrow().counts(channel)
    }
}

impl ErrorType for SimMcp3208 {
    type Error = SimSpiError;
}

impl SpiDevice<u8> for SimMcp3208 {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), SimSpiError> {
        let mut chip = self.0.borrow_mut();
        chip.bus_faults.take()?;
        answer(operations, |mosi| chip.window(mosi));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn datasheet_frame_with_and_without_leading_zeros() {
        let f = SharedF64::new(100.0);
        let mut adc = SimMcp3208::new();
        adc.set_hi_z_level(false);
        let cal = ForceSensorCal {
            offset_counts: 200.0,
            counts_per_n: 3.5,
        };
        adc.connect(5, f.clone(), cal);
        let value = cal.counts(100.0); // 550 = 0x226
        assert_eq!(value, 550);
        // Figure 6-1: 0000_011D2 | D1D0xx_xxxx | xxxx_xxxx; channel 5 = 101.
        let mut b = [0b0000_0111, 0b0100_0000, 0];
        adc.transaction(&mut [Operation::TransferInPlace(&mut b)])
            .unwrap_or_else(|_| unreachable!());
        assert_eq!(b[1] & 0x1F, 0x02); // null bit 0, then B11..B8 = 0010
        assert_eq!(b[2], 0x26);
        // Start bit as the very first bit: result shifts 5 bits earlier.
        let mut b = [0b1110_1000, 0, 0];
        adc.transaction(&mut [Operation::TransferInPlace(&mut b)])
            .unwrap_or_else(|_| unreachable!());
        let bits = u32::from_be_bytes([0, b[0], b[1], b[2]]);
        // null bit at index 6 → B11 at index 7..B0 at 18 of 24: shift 5.
        assert_eq!((bits >> 5) & 0xFFF, 550);
        assert_eq!((bits >> 17) & 1, 0); // null bit
    }

    #[test]
    fn differential_pair() {
        let a = SharedF64::new(100.0);
        let b = SharedF64::new(50.0);
        let adc = SimMcp3208::new();
        adc.connect(2, a, ForceSensorCal::CRUTCH);
        adc.connect(3, b, ForceSensorCal::CRUTCH);
        let chip = adc.0.borrow();
        assert_eq!(chip.convert(false, 2), 350);
        assert_eq!(chip.convert(false, 3), 0);
    }
}
