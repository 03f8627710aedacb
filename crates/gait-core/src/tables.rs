//! Gait tables: the precomputed reference trajectories that live in flash,
//! in a documented, versioned, checksummed binary format.
//!
//! The controller never plays a table it has not verified: [`GaitTable::parse`]
//! checks the magic, the format version, the gait kind, the IK options, the
//! length, a CRC-32 over the whole image and that every angle is finite,
//! before any sample can be read. The optimiser writes tables with [`encode`]
//! (the one definition of the format, shared by writer and reader).
//!
//! # Format, version 2 (all little-endian)
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 4 | magic `b"EXGT"` |
//! | 4 | 2 | format version, `2` |
//! | 6 | 1 | gait kind: 0 walk, 1 stair ascent, 2 stair descent |
//! | 7 | 1 | reserved, 0 |
//! | 8 | 4 | sample period, µs |
//! | 12 | 2 | sample count n (2 ≤ n ≤ [`MAX_TABLE_SAMPLES`]) |
//! | 14 | 2 | reserved, 0 |
//! | 16 | 4 | IK stance-knee cap, f32 rad ([`IkOptions::stance_knee_max_rad`]; finite, in (0, π/2]) |
//! | 20 | 1 | IK knee range ([`IkOptions::knee_range`]): 0 [`KneeRange::Reach`], 1 [`KneeRange::Human`] |
//! | 21 | 3 | reserved, 0 |
//! | 24 | 20 n | n samples of Φ (5 × f32, rad; the paper's absolute angles, link 1 = stance shank) |
//! | 24 + 20 n | 4 | CRC-32/ISO-HDLC of bytes 0 … 23 + 20 n |
//!
//! The IK options are the ones the table's postures were generated with
//! (bytes 16–20): the controller plans the weight transfer between steps
//! with them ([`GaitTable::ik_options`]), so that its IK describes the
//! table's postures the way the generator's did. They are checked with
//! [`IkOptions::new`]; a table whose options that refuses is refused
//! ([`TableError::BadIkOptions`]).
//!
//! Version 1 (a 16-byte header without the IK options) is refused
//! ([`TableError::UnknownVersion`]): its tables must be regenerated.
//!
//! A step in a table is always "the swing leg moves": the controller maps
//! links 1–2 to whichever leg stands and links 4–5 to the one that swings.

use crate::ik::{IkOptions, KneeRange};
use crate::model::LINKS;

/// First four bytes of every table.
pub const MAGIC: [u8; 4] = *b"EXGT";
/// The format version this reader understands.
pub const FORMAT_VERSION: u16 = 2;
/// Bytes before the samples (a multiple of 8: the samples stay aligned).
pub const HEADER_LEN: usize = 24;
/// Offset of the IK stance-knee cap (f32, rad) in the header.
pub const IK_CAP_OFFSET: usize = 16;
/// Offset of the IK knee-range tag (one byte) in the header.
pub const IK_RANGE_OFFSET: usize = 20;
/// Bytes per sample (five f32).
pub const SAMPLE_LEN: usize = 4 * LINKS;
/// Largest sample count a table may hold (10.23 s at 100 Hz).
pub const MAX_TABLE_SAMPLES: usize = 1024;

/// The CRC used: CRC-32/ISO-HDLC (the zlib/Ethernet CRC-32).
const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Which movement a table describes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GaitKind {
    /// Level walking.
    Walk,
    /// Stair ascent, one step per stair.
    StairUp,
    /// Stair descent, one step per stair.
    StairDown,
}

impl GaitKind {
    fn from_byte(b: u8) -> Option<Self> {
        match b {
            0 => Some(Self::Walk),
            1 => Some(Self::StairUp),
            2 => Some(Self::StairDown),
            _ => None,
        }
    }

    fn byte(self) -> u8 {
        match self {
            Self::Walk => 0,
            Self::StairUp => 1,
            Self::StairDown => 2,
        }
    }
}

/// The knee range's tag in the header.
fn knee_range_from_byte(b: u8) -> Option<KneeRange> {
    match b {
        0 => Some(KneeRange::Reach),
        1 => Some(KneeRange::Human),
        _ => None,
    }
}

fn knee_range_byte(r: KneeRange) -> u8 {
    match r {
        KneeRange::Reach => 0,
        KneeRange::Human => 1,
    }
}

/// Why a table image was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TableError {
    /// Shorter than its header says, or longer.
    BadLength,
    /// Not a gait table.
    BadMagic,
    /// A format version this reader does not know.
    UnknownVersion(u16),
    /// An unknown gait kind byte.
    UnknownKind(u8),
    /// Sample count or period out of range.
    BadHeader,
    /// The CRC does not match: the image is corrupt.
    BadCrc,
    /// A sample holds NaN or infinity.
    NonFinite,
    /// The IK options are refused: an unknown knee-range tag, or a
    /// stance-knee cap that [`IkOptions::new`] refuses (not finite, not in
    /// (0, π/2] rad).
    BadIkOptions,
    /// The output buffer is too small (writer).
    BufferTooSmall,
}

impl core::fmt::Display for TableError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BadLength => f.write_str("table length does not match its header"),
            Self::BadMagic => f.write_str("not a gait table (bad magic)"),
            Self::UnknownVersion(v) => write!(f, "unknown table format version {v}"),
            Self::UnknownKind(k) => write!(f, "unknown gait kind {k}"),
            Self::BadHeader => f.write_str("sample count or period out of range"),
            Self::BadCrc => f.write_str("CRC mismatch: table corrupt"),
            Self::NonFinite => f.write_str("table holds a non-finite angle"),
            Self::BadIkOptions => f.write_str(
                "table IK options refused (unknown knee range, or stance-knee cap not in (0, pi/2] rad)",
            ),
            Self::BufferTooSmall => f.write_str("output buffer too small"),
        }
    }
}

/// A verified table (borrowing its image, typically in flash).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaitTable<'a> {
    kind: GaitKind,
    period_us: u32,
    ik: IkOptions<f32>,
    samples: &'a [u8],
    count: usize,
    /// What its bundle says of the stance hip's torque residual, N·m
    /// (0: nothing; [`GaitTable::with_stance_hip_residual_nm`]).
    stance_hip_residual_nm: u8,
}

/// Total image length for `n` samples.
pub const fn image_len(n: usize) -> usize {
    HEADER_LEN + n * SAMPLE_LEN + 4
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    let s = b.get(at..at + 2)?;
    Some(u16::from_le_bytes([*s.first()?, *s.get(1)?]))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    let s = b.get(at..at + 4)?;
    let a: [u8; 4] = s.try_into().ok()?;
    Some(u32::from_le_bytes(a))
}

fn f32_at(b: &[u8], at: usize) -> Option<f32> {
    u32_at(b, at).map(f32::from_bits)
}

/// The IK options of a header, checked by [`IkOptions::new`].
fn ik_options_at(image: &[u8]) -> Result<IkOptions<f32>, TableError> {
    let cap = f32_at(image, IK_CAP_OFFSET).ok_or(TableError::BadLength)?;
    let range_byte = image
        .get(IK_RANGE_OFFSET)
        .copied()
        .ok_or(TableError::BadLength)?;
    let range = knee_range_from_byte(range_byte).ok_or(TableError::BadIkOptions)?;
    IkOptions::new(cap, range).map_err(|_| TableError::BadIkOptions)
}

impl<'a> GaitTable<'a> {
    /// Verifies an image and returns the table; nothing of an image that
    /// fails any check can be read.
    pub fn parse(image: &'a [u8]) -> Result<Self, TableError> {
        if image.len() < image_len(0) {
            return Err(TableError::BadLength);
        }
        if image.get(0..4) != Some(&MAGIC[..]) {
            return Err(TableError::BadMagic);
        }
        let version = u16_at(image, 4).ok_or(TableError::BadLength)?;
        if version != FORMAT_VERSION {
            return Err(TableError::UnknownVersion(version));
        }
        let kind_byte = image.get(6).copied().ok_or(TableError::BadLength)?;
        let kind = GaitKind::from_byte(kind_byte).ok_or(TableError::UnknownKind(kind_byte))?;
        let period_us = u32_at(image, 8).ok_or(TableError::BadLength)?;
        let count = usize::from(u16_at(image, 12).ok_or(TableError::BadLength)?);
        if !(2..=MAX_TABLE_SAMPLES).contains(&count) || period_us == 0 || period_us > 1_000_000 {
            return Err(TableError::BadHeader);
        }
        let ik = ik_options_at(image)?;
        if image.len() != image_len(count) {
            return Err(TableError::BadLength);
        }
        let body_end = image_len(count) - 4;
        let body = image.get(..body_end).ok_or(TableError::BadLength)?;
        let stored = u32_at(image, body_end).ok_or(TableError::BadLength)?;
        if CRC32.checksum(body) != stored {
            return Err(TableError::BadCrc);
        }
        let samples = image
            .get(HEADER_LEN..body_end)
            .ok_or(TableError::BadLength)?;
        // Bounded: count ≤ MAX_TABLE_SAMPLES, checked above.
        for chunk in samples.chunks_exact(4) {
            let bits: [u8; 4] = chunk.try_into().map_err(|_| TableError::BadLength)?;
            if !f32::from_le_bytes(bits).is_finite() {
                return Err(TableError::NonFinite);
            }
        }
        Ok(Self {
            kind,
            period_us,
            ik,
            samples,
            count,
            stance_hip_residual_nm: 0,
        })
    }

    /// The table with the torque-residual limit its gait's healthy closed
    /// loop allows at the stance hip of a swing, N·m (0: none given, the
    /// device's own limit applies). It is not part of the table's image:
    /// the generator measures it on the device's closed loop, a bundle
    /// carries it in the gait's directory entry and the device's own
    /// tables in their code ([`crate::flash_tables`]). The supervisor
    /// holds it within its own bounds (`docs/safety.md`, 0x0404).
    #[must_use]
    pub const fn with_stance_hip_residual_nm(mut self, nm: u8) -> Self {
        self.stance_hip_residual_nm = nm;
        self
    }

    /// The stance hip's torque-residual limit of this gait's swings, N·m;
    /// NaN where none was given.
    pub fn stance_hip_residual_nm(&self) -> f32 {
        if self.stance_hip_residual_nm == 0 {
            f32::NAN
        } else {
            f32::from(self.stance_hip_residual_nm)
        }
    }

    /// The movement this table describes.
    pub fn kind(&self) -> GaitKind {
        self.kind
    }

    /// The IK options the table's postures were generated with (verified
    /// by [`IkOptions::new`]).
    pub fn ik_options(&self) -> IkOptions<f32> {
        self.ik
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Always false for a verified table (it holds at least two samples).
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Sample period, s.
    pub fn period_s(&self) -> f32 {
        self.period_us as f32 * 1e-6
    }

    /// Duration from the first to the last sample, s.
    pub fn duration_s(&self) -> f32 {
        self.period_s() * (self.count.saturating_sub(1)) as f32
    }

    /// Sample `k` (Φ, rad), or `None` past the end.
    pub fn sample(&self, k: usize) -> Option<[f32; LINKS]> {
        let base = k.checked_mul(SAMPLE_LEN)?;
        // One bounds check for the whole sample (a check per word cost
        // some 60 instructions a sample on the M4), then fixed-size words.
        let bytes: &[u8; SAMPLE_LEN] =
            self.samples.get(base..base + SAMPLE_LEN)?.try_into().ok()?;
        let mut out = [0.0f32; LINKS];
        for (o, w) in out.iter_mut().zip(bytes.chunks_exact(4)) {
            let word: [u8; 4] = w.try_into().ok()?;
            *o = f32::from_le_bytes(word);
        }
        Some(out)
    }

    /// The first posture (the one a step must start from).
    pub fn first(&self) -> [f32; LINKS] {
        self.sample(0).unwrap_or([0.0; LINKS])
    }

    /// The last posture (landing).
    pub fn last(&self) -> [f32; LINKS] {
        self.sample(self.count.saturating_sub(1))
            .unwrap_or([0.0; LINKS])
    }

    /// Φ at time `t_s` after the step start, linearly interpolated between
    /// samples and held at the ends. Constant time: no search.
    pub fn at_time(&self, t_s: f32) -> [f32; LINKS] {
        interpolate(self.count, self.period_s(), t_s, |k| self.sample(k))
    }
}

/// Φ at `t_s` of the samples `sample(0 … count − 1)` taken every
/// `period_s`, linearly interpolated and held at the ends: a table's
/// [`GaitTable::at_time`], and the same rule for samples kept elsewhere (a
/// step re-planned on the board). Constant time: no search.
#[inline]
pub fn interpolate(
    count: usize,
    period_s: f32,
    t_s: f32,
    sample: impl Fn(usize) -> Option<[f32; LINKS]>,
) -> [f32; LINKS] {
    let x = if t_s.is_finite() && t_s > 0.0 {
        t_s / period_s
    } else {
        0.0
    };
    let last = count.saturating_sub(1);
    let k = (x as usize).min(last);
    let w = if k >= last { 0.0 } else { x - k as f32 };
    let a = sample(k).unwrap_or([0.0; LINKS]);
    let b = sample((k + 1).min(last)).unwrap_or(a);
    let mut out = a;
    for ((o, &ai), &bi) in out.iter_mut().zip(&a).zip(&b) {
        *o = ai + w * (bi - ai);
    }
    out
}

/// Writes a table image into `out`; returns its length. `ik`: the IK
/// options the samples were generated with. Refuses samples and options
/// that the reader would refuse.
pub fn encode(
    kind: GaitKind,
    period_us: u32,
    ik: IkOptions<f32>,
    samples: &[[f32; LINKS]],
    out: &mut [u8],
) -> Result<usize, TableError> {
    let n = samples.len();
    if !(2..=MAX_TABLE_SAMPLES).contains(&n) || period_us == 0 || period_us > 1_000_000 {
        return Err(TableError::BadHeader);
    }
    let ik = IkOptions::new(ik.stance_knee_max_rad, ik.knee_range)
        .map_err(|_| TableError::BadIkOptions)?;
    if samples.iter().flatten().any(|v| !v.is_finite()) {
        return Err(TableError::NonFinite);
    }
    let len = image_len(n);
    let img = out.get_mut(..len).ok_or(TableError::BufferTooSmall)?;
    let count = u16::try_from(n).map_err(|_| TableError::BadHeader)?;
    let mut header = [0u8; HEADER_LEN];
    for (dst, src) in header.iter_mut().zip(
        MAGIC
            .iter()
            .chain(&FORMAT_VERSION.to_le_bytes())
            .chain(&[kind.byte(), 0])
            .chain(&period_us.to_le_bytes())
            .chain(&count.to_le_bytes())
            .chain(&[0, 0])
            .chain(&ik.stance_knee_max_rad.to_le_bytes())
            .chain(&[knee_range_byte(ik.knee_range), 0, 0, 0]),
    ) {
        *dst = *src;
    }
    let body_end = len - 4;
    if let Some(head) = img.get_mut(..HEADER_LEN) {
        head.copy_from_slice(&header);
    }
    if let Some(body) = img.get_mut(HEADER_LEN..body_end) {
        for (chunk, v) in body.chunks_exact_mut(4).zip(samples.iter().flatten()) {
            chunk.copy_from_slice(&v.to_le_bytes());
        }
    }
    let crc = CRC32.checksum(img.get(..body_end).ok_or(TableError::BufferTooSmall)?);
    if let Some(tail) = img.get_mut(body_end..) {
        tail.copy_from_slice(&crc.to_le_bytes());
    }
    Ok(len)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image() -> Result<([u8; image_len(3)], usize), TableError> {
        let mut buf = [0u8; image_len(3)];
        let s = [
            [0.0, 0.1, 0.0, 3.0, 3.2],
            [0.1, 0.0, 0.05, 2.9, 3.3],
            [0.2, -0.1, 0.1, 2.8, 3.4],
        ];
        let n = encode(GaitKind::StairUp, 10_000, IkOptions::paper(), &s, &mut buf)?;
        Ok((buf, n))
    }

    #[test]
    fn round_trip_and_interpolation() -> Result<(), TableError> {
        let (buf, n) = image()?;
        assert_eq!(n, buf.len());
        let t = GaitTable::parse(&buf)?;
        assert_eq!(t.kind(), GaitKind::StairUp);
        assert_eq!(t.len(), 3);
        assert!((t.duration_s() - 0.02).abs() < 1e-7);
        assert_eq!(t.sample(1).map(|s| s[3]), Some(2.9));
        assert!(t.sample(3).is_none());
        let mid = t.at_time(0.015);
        assert!((mid[0] - 0.15).abs() < 1e-6);
        assert_eq!(t.at_time(-1.0), t.first());
        assert_eq!(t.at_time(f32::NAN), t.first());
        assert_eq!(t.at_time(99.0), t.last());
        Ok(())
    }

    #[test]
    fn every_corruption_is_refused() -> Result<(), TableError> {
        let (buf, _) = image()?;
        // Any single flipped bit anywhere is caught (header checks or CRC).
        for byte in 0..buf.len() {
            for bit in 0..8 {
                let mut b = buf;
                b[byte] ^= 1 << bit;
                assert!(
                    GaitTable::parse(&b).is_err(),
                    "flip at {byte}:{bit} accepted"
                );
            }
        }
        assert_eq!(
            GaitTable::parse(&buf[..buf.len() - 1]),
            Err(TableError::BadLength)
        );
        let mut v = buf;
        v[4] = 3;
        assert_eq!(GaitTable::parse(&v), Err(TableError::UnknownVersion(3)));
        Ok(())
    }

    #[test]
    fn flash_tables_verify() -> Result<(), TableError> {
        let w = crate::flash_tables::walk()?;
        assert_eq!(w.kind(), GaitKind::Walk);
        assert!((w.duration_s() - 2.24).abs() < 1e-4);
        let s = crate::flash_tables::stair_up()?;
        assert_eq!(s.kind(), GaitKind::StairUp);
        assert!((s.duration_s() - 2.28).abs() < 1e-4);
        Ok(())
    }

    #[test]
    fn writer_refuses_what_the_reader_would() {
        let mut buf = [0u8; 256];
        let nan = [[f32::NAN; LINKS], [0.0; LINKS]];
        assert_eq!(
            encode(GaitKind::Walk, 10_000, IkOptions::paper(), &nan, &mut buf),
            Err(TableError::NonFinite)
        );
        let one = [[0.0; LINKS]];
        assert_eq!(
            encode(GaitKind::Walk, 10_000, IkOptions::paper(), &one, &mut buf),
            Err(TableError::BadHeader)
        );
        let many = [[0.0; LINKS]; 20];
        assert_eq!(
            encode(GaitKind::Walk, 10_000, IkOptions::paper(), &many, &mut buf),
            Err(TableError::BufferTooSmall)
        );
    }
}
