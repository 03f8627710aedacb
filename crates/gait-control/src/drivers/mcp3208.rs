//! MCP3208 12-bit, 8-channel SPI ADC reading the force sensors under the
//! feet and in the crutch tips, and the hip and knee drives' current
//! monitors.
//!
//! Wire format (Microchip MCP3204/3208 datasheet, section 6.1, "Using the
//! MCP3204/3208 with microcontroller SPI ports"): one chip-select window of
//! three bytes. Byte 0 is `0b0000_0 1 1 D2` (five leading zeros, start bit,
//! SGL/DIFF = 1 for single-ended, D2); byte 1 is `D1 D0` in bits 7..6; byte 2
//! is don't-care. The reply carries the null bit and B11..B8 in the low 5
//! bits of byte 1 (the null bit is bit 4) and B7..B0 in byte 2.
//!
//! Force sensors are checked before they are believed: a reading at the rails
//! means an open or shorted sensor or cable, and a force outside the sensor's
//! rated range is reported, never clamped, so the crutch-load metric and the
//! landing detector never run on invented numbers.

use embedded_hal::spi::{Operation, SpiDevice};

/// Largest 12-bit count.
pub const MAX_COUNTS: u16 = 0x0FFF;

/// An input channel, single-ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Channel {
    /// CH0
    Ch0 = 0,
    /// CH1
    Ch1 = 1,
    /// CH2
    Ch2 = 2,
    /// CH3
    Ch3 = 3,
    /// CH4
    Ch4 = 4,
    /// CH5
    Ch5 = 5,
    /// CH6
    Ch6 = 6,
    /// CH7
    Ch7 = 7,
}

/// Builds the 3-byte single-ended conversion request for `channel`.
#[must_use]
pub const fn encode_request(channel: Channel) -> [u8; 3] {
    let ch = channel as u8;
    [0b0000_0110 | ((ch >> 2) & 1), (ch & 0b11) << 6, 0x00]
}

/// Extracts the 12-bit result from the 3 reply bytes (ignores the bits
/// that are not part of the result, so it is total).
#[must_use]
pub const fn decode_reply(reply: [u8; 3]) -> u16 {
    (((reply[1] & 0x0F) as u16) << 8) | reply[2] as u16
}

/// Why a force reading (or a drive-current one: [`DriveCurrentCalibration`])
/// was not believed.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ForceFault {
    /// Counts below the open-circuit threshold: sensor or cable open.
    OpenCircuit {
        /// The raw counts read.
        counts: u16,
    },
    /// Counts above the short-circuit threshold: sensor or cable shorted.
    ShortCircuit {
        /// The raw counts read.
        counts: u16,
    },
    /// The calibrated force lies outside the sensor's rated range.
    OutOfRange {
        /// The raw counts read.
        counts: u16,
        /// The force the calibration gives, unclamped.
        newtons: f32,
    },
}

/// Why a calibration was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CalibrationError {
    /// Table counts must be strictly increasing and forces finite.
    NotMonotonic,
    /// The thresholds must satisfy open < short ≤ 4095 and min < max force.
    BadBounds,
}

/// Counts → newtons for one force sensor: a piecewise-linear table of `N ≥ 2`
/// points (FSRs are strongly non-linear), linear extrapolation from the end
/// segments, and validity bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ForceCalibration<const N: usize> {
    counts: [u16; N],
    newtons: [f32; N],
    open_below_counts: u16,
    short_above_counts: u16,
    min_newtons: f32,
    max_newtons: f32,
}

impl<const N: usize> ForceCalibration<N> {
    /// Checks and builds a calibration. `open_below_counts`: readings below
    /// it are an open circuit; `short_above_counts`: readings above it are a
    /// short; `[min_newtons, max_newtons]`: the rated range.
    pub fn new(
        counts: [u16; N],
        newtons: [f32; N],
        open_below_counts: u16,
        short_above_counts: u16,
        min_newtons: f32,
        max_newtons: f32,
    ) -> Result<Self, CalibrationError> {
        if N < 2 {
            return Err(CalibrationError::NotMonotonic);
        }
        let increasing = counts.windows(2).all(|w| match w {
            [a, b] => a < b,
            _ => false,
        });
        if !increasing || !newtons.iter().all(|n| n.is_finite()) {
            return Err(CalibrationError::NotMonotonic);
        }
        if open_below_counts >= short_above_counts
            || short_above_counts > MAX_COUNTS
            || !(min_newtons.is_finite() && max_newtons.is_finite() && min_newtons < max_newtons)
        {
            return Err(CalibrationError::BadBounds);
        }
        Ok(Self {
            counts,
            newtons,
            open_below_counts,
            short_above_counts,
            min_newtons,
            max_newtons,
        })
    }

    /// Interpolated force for `counts`, without any validity check.
    #[must_use]
    pub fn interpolate(&self, counts: u16) -> f32 {
        // Choose the segment: the last one whose start is ≤ counts, or the
        // first one for counts below the table. Fixed N iterations.
        let mut seg = 0usize;
        for i in 1..N.saturating_sub(1) {
            if self.counts.get(i).is_some_and(|&c| c <= counts) {
                seg = i;
            }
        }
        let (Some(&c0), Some(&c1), Some(&n0), Some(&n1)) = (
            self.counts.get(seg),
            self.counts.get(seg + 1),
            self.newtons.get(seg),
            self.newtons.get(seg + 1),
        ) else {
            // Unreachable for N ≥ 2 (checked in `new`); NaN fails validation.
            return f32::NAN;
        };
        let t = (f32::from(counts) - f32::from(c0)) / (f32::from(c1) - f32::from(c0));
        n0 + t * (n1 - n0)
    }

    /// Counts → newtons with the open/short and range checks.
    pub fn convert(&self, counts: u16) -> Result<f32, ForceFault> {
        if counts < self.open_below_counts {
            return Err(ForceFault::OpenCircuit { counts });
        }
        if counts > self.short_above_counts {
            return Err(ForceFault::ShortCircuit { counts });
        }
        let newtons = self.interpolate(counts);
        // `!(a <= x && x <= b)` so that NaN is out of range too.
        if !(self.min_newtons <= newtons && newtons <= self.max_newtons) {
            return Err(ForceFault::OutOfRange { counts, newtons });
        }
        Ok(newtons)
    }
}

/// Counts → joint torque for one drive's current monitor: the servo
/// amplifier's analog output of its actual current, scaled and offset onto
/// an ADC channel, times the joint torque per ampere. Linear (an amplifier's
/// output is, unlike a force-sensing resistor), and checked like a force
/// sensor: a reading at a rail is a broken monitor, not a current.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DriveCurrentCalibration {
    zero_counts: u16,
    nm_per_count: f32,
    open_below_counts: u16,
    short_above_counts: u16,
}

impl DriveCurrentCalibration {
    /// `zero_counts`: the reading at 0 A; `nm_per_count`: joint torque per
    /// count (flexion positive, finite, non-zero); readings below
    /// `open_below_counts` or above `short_above_counts` are a broken
    /// monitor (open < zero < short ≤ 4095).
    pub fn new(
        zero_counts: u16,
        nm_per_count: f32,
        open_below_counts: u16,
        short_above_counts: u16,
    ) -> Result<Self, CalibrationError> {
        let ordered = open_below_counts < zero_counts
            && zero_counts < short_above_counts
            && short_above_counts <= MAX_COUNTS;
        if !ordered || !nm_per_count.is_finite() || nm_per_count == 0.0 {
            return Err(CalibrationError::BadBounds);
        }
        Ok(Self {
            zero_counts,
            nm_per_count,
            open_below_counts,
            short_above_counts,
        })
    }

    /// Counts → joint torque, N·m, with the rail checks.
    pub fn convert(&self, counts: u16) -> Result<f32, ForceFault> {
        if counts < self.open_below_counts {
            return Err(ForceFault::OpenCircuit { counts });
        }
        if counts > self.short_above_counts {
            return Err(ForceFault::ShortCircuit { counts });
        }
        Ok((f32::from(counts) - f32::from(self.zero_counts)) * self.nm_per_count)
    }
}

super::read_status! {
    /// The outcome of one force conversion, without the bus's own error
    /// type: the kind of a driver error, which the supervisor counts as it
    /// is ([`crate::supervisor::ForceStatus`]).
    ReadStatus {
        /// A reading within the rated range.
        Ok,
        /// Counts below the open-circuit threshold.
        Open,
        /// Counts above the short-circuit threshold.
        Shorted,
        /// The calibrated force is outside the rated range.
        OutOfRange,
    }
}

/// Driver errors.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<E> {
    /// The SPI bus or chip select failed.
    Bus(E),
    /// The sensor reading is not valid.
    Sensor(ForceFault),
}

impl<E> Error<E> {
    /// What kind of failure this is ([`ReadStatus`], never `Ok`).
    pub fn kind(&self) -> ReadStatus {
        match self {
            Self::Bus(_) => ReadStatus::BusError,
            Self::Sensor(f) => f.status(),
        }
    }
}

impl ForceFault {
    /// What kind of failure this is ([`ReadStatus`], never `Ok`).
    #[must_use]
    pub const fn status(&self) -> ReadStatus {
        match self {
            Self::OpenCircuit { .. } => ReadStatus::Open,
            Self::ShortCircuit { .. } => ReadStatus::Shorted,
            Self::OutOfRange { .. } => ReadStatus::OutOfRange,
        }
    }
}

/// An MCP3208 on its own chip select.
#[derive(Debug)]
pub struct Mcp3208<SPI> {
    spi: SPI,
}

impl<SPI, E> Mcp3208<SPI>
where
    SPI: SpiDevice<u8, Error = E>,
{
    /// Wraps a configured SPI device (mode 0 or 3, ≤ 1 MHz at 2.7 V).
    pub const fn new(spi: SPI) -> Self {
        Self { spi }
    }

    /// Gives the SPI device back.
    pub fn destroy(self) -> SPI {
        self.spi
    }

    /// One single-ended conversion: raw 12-bit counts.
    pub fn read_raw(&mut self, channel: Channel) -> Result<u16, Error<E>> {
        self.exchange(encode_request(channel)).map(decode_reply)
    }

    /// One 3-byte conversion window: `request` out, the reply back.
    pub fn exchange(&mut self, request: [u8; 3]) -> Result<[u8; 3], Error<E>> {
        let mut buf = request;
        self.spi
            .transaction(&mut [Operation::TransferInPlace(&mut buf)])
            .map_err(Error::Bus)?;
        Ok(buf)
    }

    /// One drive-current conversion, as joint torque, checked.
    pub fn read_drive_torque(
        &mut self,
        channel: Channel,
        calibration: &DriveCurrentCalibration,
    ) -> Result<f32, Error<E>> {
        let counts = self.read_raw(channel)?;
        calibration.convert(counts).map_err(Error::Sensor)
    }

    /// One conversion, calibrated and checked.
    pub fn read_force<const N: usize>(
        &mut self,
        channel: Channel,
        calibration: &ForceCalibration<N>,
    ) -> Result<f32, Error<E>> {
        let counts = self.read_raw(channel)?;
        calibration.convert(counts).map_err(Error::Sensor)
    }
}

/// Where the four force sensors sit on the ADC (board wiring decides).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ForceChannels {
    /// Left foot sole.
    pub left_foot: Channel,
    /// Right foot sole.
    pub right_foot: Channel,
    /// Left crutch tip.
    pub left_crutch: Channel,
    /// Right crutch tip.
    pub right_crutch: Channel,
}

gait_core::impl_fingerprint!(DriveCurrentCalibration {
    zero_counts,
    nm_per_count,
    open_below_counts,
    short_above_counts,
});
gait_core::impl_fingerprint!([const N: usize] ForceCalibration<N> {
    counts,
    newtons,
    open_below_counts,
    short_above_counts,
    min_newtons,
    max_newtons,
});
