//! The device's own calibration, recorded on it and kept in a flash sector
//! of its own: each encoder's raw counts at its joint's zero pose, and each
//! foot and crutch load cell's ADC counts unloaded (their sensitivity is
//! the load cell's datasheet figure, [`crate::sensors::LoadCellSpec`]).
//!
//! **Recording** (`docs/operation.md`, "Calibrating the device"): the
//! device stands on its calibration jig in the reference posture, every
//! hip, knee and ankle at its zero pose, nothing on the feet and crutches;
//! the technician holds MODE and GO while switching on. The board reads
//! every encoder and force channel [`SAMPLES`] times ([`measure`]), checks
//! that nothing moved and that each value is plausible ([`Record::from_readings`]),
//! and writes the record with its CRC.
//!
//! **At boot** the record is verified ([`Record::parse`]: magic, version,
//! CRC, plausibility) and applied ([`DeviceConfig::calibrated`]); a
//! missing, corrupt or implausible record latches fault 0x0605 and the
//! motors stay off. The values in `lib.rs` (`ENCODER_CALIBRATION`, the
//! load cells' nominal zero) are the simulated device's
//! ([`Record::of_device`]).
//!
//! # Format, version 1 (little-endian, 32 bytes)
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 4 | magic `b"EXGC"` |
//! | 4 | 2 | version, `1` |
//! | 6 | 2 | reserved, 0 |
//! | 8 | 12 | encoder zero counts, u16 × 6 (left hip, left knee, right hip, right knee, left ankle, right ankle) |
//! | 20 | 8 | load cells' unloaded counts, u16 × 4 (left foot, right foot, left crutch, right crutch) |
//! | 28 | 4 | CRC-32/ISO-HDLC of bytes 0 … 27 |

use gait_control::controller::{ENCODERS, Hardware};
use gait_control::drivers::mcp3208::Channel;

use crate::sensors::{LoadCellSpec, OPEN_BELOW_COUNTS, SHORT_ABOVE_COUNTS};
use crate::{DeviceConfig, DeviceError};

/// First four bytes of a record.
pub const MAGIC: [u8; 4] = *b"EXGC";
/// The record version this reader understands.
pub const VERSION: u16 = 1;
/// Bytes of a record.
pub const RECORD_LEN: usize = 32;
/// Force channels recorded (feet, then crutches).
pub const FORCES: usize = 4;
/// Readings of each channel a recording takes.
pub const SAMPLES: usize = 64;
/// Largest spread of one encoder's readings while recording, counts
/// (0.18°): more, and the device moved.
pub const ENCODER_STILL_COUNTS: u16 = 8;
/// Largest spread of one load cell's readings while recording, counts.
pub const FORCE_STILL_COUNTS: u16 = 20;
/// Largest departure of a load cell's unloaded counts from its datasheet
/// zero, counts (about 25 N on a foot cell): more is a loaded sensor or a
/// broken amplifier.
pub const FORCE_ZERO_TOLERANCE_COUNTS: f32 = 150.0;

const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// A device's calibration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Record {
    /// Each encoder's raw counts at its joint's zero pose.
    pub encoder_zero_counts: [u16; ENCODERS],
    /// Each load cell's ADC counts unloaded.
    pub force_zero_counts: [u16; FORCES],
}

/// Why a record was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Refusal {
    /// No record: erased flash, or not a record.
    Missing,
    /// A record version this reader does not know.
    UnknownVersion(u16),
    /// The CRC does not match.
    BadCrc,
    /// An encoder's zero is not a 14-bit count (encoder index).
    EncoderZero(u8),
    /// A load cell's unloaded counts are out of range or too far from its
    /// datasheet zero (force index).
    ForceZero(u8),
    /// An encoder moved while recording (encoder index).
    EncoderMoved(u8),
    /// A load cell's reading changed while recording (force index).
    ForceMoved(u8),
    /// A sensor could not be read while recording (encoder index, or 6 +
    /// force index).
    ReadFailed(u8),
}

impl Refusal {
    /// A short name, without `core::fmt` (the QEMU image prints it).
    #[must_use]
    pub const fn reason(&self) -> &'static str {
        match self {
            Self::Missing => "missing",
            Self::UnknownVersion(_) => "unknown-version",
            Self::BadCrc => "crc",
            Self::EncoderZero(_) => "encoder-zero",
            Self::ForceZero(_) => "force-zero",
            Self::EncoderMoved(_) => "encoder-moved",
            Self::ForceMoved(_) => "force-moved",
            Self::ReadFailed(_) => "read-failed",
        }
    }
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

/// The device's load cells, feet then crutches.
fn cells(device: &DeviceConfig) -> [LoadCellSpec; FORCES] {
    [
        device.foot_sensor,
        device.foot_sensor,
        device.crutch_sensor,
        device.crutch_sensor,
    ]
}

impl Record {
    /// The calibration the device configuration holds (the simulated
    /// device's: its encoders' zero offsets, its load cells' nominal zero).
    #[must_use]
    pub fn of_device(device: &DeviceConfig) -> Self {
        Self {
            encoder_zero_counts: device.encoders.map(|c| c.zero_offset_counts),
            force_zero_counts: cells(device).map(|c| libm::roundf(c.zero_counts) as u16),
        }
    }

    /// Each value plausible for `device`.
    pub fn check(&self, device: &DeviceConfig) -> Result<(), Refusal> {
        for (i, &z) in (0u8..).zip(&self.encoder_zero_counts) {
            if z >= 1 << 14 {
                return Err(Refusal::EncoderZero(i));
            }
        }
        for ((i, &z), cell) in (0u8..).zip(&self.force_zero_counts).zip(cells(device)) {
            let inside = z > OPEN_BELOW_COUNTS && z < SHORT_ABOVE_COUNTS;
            if !inside || (f32::from(z) - cell.zero_counts).abs() > FORCE_ZERO_TOLERANCE_COUNTS {
                return Err(Refusal::ForceZero(i));
            }
        }
        Ok(())
    }

    /// The record's bytes.
    #[must_use]
    pub fn encode(&self) -> [u8; RECORD_LEN] {
        let mut b = [0u8; RECORD_LEN];
        let words = self
            .encoder_zero_counts
            .iter()
            .chain(&self.force_zero_counts);
        let version = VERSION.to_le_bytes();
        let head = MAGIC.iter().chain(&version).chain(&[0, 0]);
        for (d, s) in b.iter_mut().zip(head) {
            *d = *s;
        }
        for (chunk, w) in b
            .get_mut(8..28)
            .unwrap_or(&mut [])
            .chunks_exact_mut(2)
            .zip(words)
        {
            chunk.copy_from_slice(&w.to_le_bytes());
        }
        let crc = CRC32.checksum(b.get(..28).unwrap_or(&[]));
        if let Some(t) = b.get_mut(28..) {
            t.copy_from_slice(&crc.to_le_bytes());
        }
        b
    }

    /// The record at the start of `sector`, verified for `device`.
    pub fn parse(sector: &[u8], device: &DeviceConfig) -> Result<Self, Refusal> {
        let b = sector.get(..RECORD_LEN).ok_or(Refusal::Missing)?;
        if b.get(..4) != Some(&MAGIC[..]) {
            return Err(Refusal::Missing);
        }
        let version = u16_at(b, 4).ok_or(Refusal::Missing)?;
        if version != VERSION {
            return Err(Refusal::UnknownVersion(version));
        }
        let stored = b
            .get(28..32)
            .and_then(|s| s.try_into().ok())
            .map(u32::from_le_bytes);
        if stored != Some(CRC32.checksum(b.get(..28).unwrap_or(&[]))) {
            return Err(Refusal::BadCrc);
        }
        let mut r = Self {
            encoder_zero_counts: [0; ENCODERS],
            force_zero_counts: [0; FORCES],
        };
        let slots = r
            .encoder_zero_counts
            .iter_mut()
            .chain(r.force_zero_counts.iter_mut());
        for (k, slot) in slots.enumerate() {
            *slot = u16_at(b, 8 + 2 * k).ok_or(Refusal::Missing)?;
        }
        r.check(device)?;
        Ok(r)
    }

    /// The record of readings taken in the reference posture, unloaded:
    /// `encoders[k]` and `forces[k]` are [`SAMPLES`] readings of each
    /// channel. Refused when anything moved or is implausible.
    pub fn from_readings(
        device: &DeviceConfig,
        encoders: &[[u16; SAMPLES]; ENCODERS],
        forces: &[[u16; SAMPLES]; FORCES],
    ) -> Result<Self, Refusal> {
        let mut r = Self {
            encoder_zero_counts: [0; ENCODERS],
            force_zero_counts: [0; FORCES],
        };
        for ((i, zero), readings) in (0u8..).zip(r.encoder_zero_counts.iter_mut()).zip(encoders) {
            let first = readings.first().copied().unwrap_or(0);
            // Wrap-aware offsets from the first reading (14-bit counts).
            let mut sum = 0i32;
            for &v in readings {
                let d = (i32::from(v) - i32::from(first) + 8192).rem_euclid(16384) - 8192;
                if d.unsigned_abs() > u32::from(ENCODER_STILL_COUNTS) {
                    return Err(Refusal::EncoderMoved(i));
                }
                sum += d;
            }
            let mean = libm::roundf(sum as f32 / SAMPLES as f32) as i32;
            *zero = (i32::from(first) + mean).rem_euclid(16384) as u16;
        }
        for ((i, zero), readings) in (0u8..).zip(r.force_zero_counts.iter_mut()).zip(forces) {
            let lo = readings.iter().copied().min().unwrap_or(0);
            let hi = readings.iter().copied().max().unwrap_or(0);
            if hi - lo > FORCE_STILL_COUNTS {
                return Err(Refusal::ForceMoved(i));
            }
            let sum: u32 = readings.iter().map(|&v| u32::from(v)).sum();
            *zero = libm::roundf(sum as f32 / SAMPLES as f32) as u16;
        }
        r.check(device)?;
        Ok(r)
    }
}

impl DeviceConfig {
    /// This device with its own calibration: the encoders' zero offsets
    /// and the load cells' unloaded counts of `record` (their sensitivity
    /// and rated range stay the datasheet's).
    pub fn calibrated(&self, record: &Record) -> Result<Self, DeviceError> {
        let mut cfg = *self;
        for (c, &z) in cfg.encoders.iter_mut().zip(&record.encoder_zero_counts) {
            c.zero_offset_counts = z;
        }
        let zeroed = |cell: LoadCellSpec, z: u16| LoadCellSpec {
            zero_counts: f32::from(z),
            ..cell
        };
        let [lf, rf, lc, rc] = record.force_zero_counts;
        let specs = [
            zeroed(cfg.foot_sensor, lf),
            zeroed(cfg.foot_sensor, rf),
            zeroed(cfg.crutch_sensor, lc),
            zeroed(cfg.crutch_sensor, rc),
        ];
        for ((slot, spec), i) in cfg
            .controller
            .force_calibration
            .iter_mut()
            .zip(specs)
            .zip(0usize..)
        {
            *slot = spec
                .calibration()
                .map_err(|e| DeviceError::ForceCalibration(i, e))?;
        }
        Ok(cfg)
    }
}

/// [`SAMPLES`] readings of each encoder and of each load cell.
pub type Readings = ([[u16; SAMPLES]; ENCODERS], [[u16; SAMPLES]; FORCES]);

/// Takes [`SAMPLES`] readings of every encoder and force channel through
/// the board's drivers (the recording procedure's measurement).
pub fn measure<ENC, ADC, PWM, DIR, EN, IN, OUT>(
    hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
) -> Result<Readings, Refusal>
where
    ENC: embedded_hal::spi::SpiDevice<u8>,
    ADC: embedded_hal::spi::SpiDevice<u8>,
{
    let mut enc = [[0u16; SAMPLES]; ENCODERS];
    let mut force = [[0u16; SAMPLES]; FORCES];
    let ch = hw.force_channels;
    let channels: [Channel; FORCES] =
        [ch.left_foot, ch.right_foot, ch.left_crutch, ch.right_crutch];
    for k in 0..SAMPLES {
        for ((i, e), readings) in (0u8..).zip(hw.encoders.iter_mut()).zip(enc.iter_mut()) {
            let r = e.read_angle().map_err(|_| Refusal::ReadFailed(i))?;
            if let Some(slot) = readings.get_mut(k) {
                *slot = r.raw_counts;
            }
        }
        for ((i, &c), readings) in (0u8..).zip(&channels).zip(force.iter_mut()) {
            let v = hw.adc.read_raw(c).map_err(|_| Refusal::ReadFailed(6 + i))?;
            if let Some(slot) = readings.get_mut(k) {
                *slot = v;
            }
        }
    }
    Ok((enc, force))
}
