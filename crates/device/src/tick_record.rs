//! The inputs of control ticks as the simulator records them and the QEMU
//! image replays them (`cargo xtask qemu`, "tick: phase=…" lines): what the
//! board's peripherals presented to the controller in one tick, and the
//! motor commands the host's controller computed from them, so the target
//! can be timed phase by phase on real gaits and its commands compared
//! with the host's.
//!
//! A file is a header and segments, all little-endian:
//!
//! | bytes | what |
//! |---|---|
//! | 0..4 | magic `EXTR` |
//! | 4..6 | format version ([`VERSION`]) |
//! | 6..8 | segment count |
//!
//! and per segment an 8-byte header (gait: 0 walk, 1 stair ascent, 2 stair
//! descent; 3 bytes reserved; tick count as `u32`) followed by that many
//! [`TickRecord`]s of [`RECORD_LEN`] bytes each.

use gait_control::operator::Gait;

/// File magic.
pub const MAGIC: [u8; 4] = *b"EXTR";
/// Format version.
pub const VERSION: u16 = 1;
/// File header length, bytes.
pub const FILE_HEADER_LEN: usize = 8;
/// Segment header length, bytes.
pub const SEGMENT_HEADER_LEN: usize = 8;
/// One record's length, bytes.
pub const RECORD_LEN: usize = 2 * 6 + 2 * 8 + 2 + 4 * 4;

/// The peripherals' state in one tick and the host's motor commands.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TickRecord {
    /// Raw AS5048A counts, joint order then left and right ankle.
    pub encoder_counts: [u16; 6],
    /// MCP3208 counts, CH0..CH7.
    pub adc_counts: [u16; 8],
    /// The MODE button is pressed.
    pub mode_pressed: bool,
    /// The GO button is pressed.
    pub go_pressed: bool,
    /// The e-stop is pressed.
    pub e_stop_pressed: bool,
    /// The board's timer flagged the previous tick as overrun.
    pub deadline_missed: bool,
    /// The host controller's motor commands this tick, N·m (joint order).
    pub host_command_nm: [f32; 4],
}

/// Reads a little-endian `u16` at `at`, if it is there.
fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes([*b.get(at)?, *b.get(at + 1)?]))
}

/// Reads a little-endian `u32` at `at`, if it is there.
fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes([
        *b.get(at)?,
        *b.get(at + 1)?,
        *b.get(at + 2)?,
        *b.get(at + 3)?,
    ]))
}

impl TickRecord {
    /// The record's bytes.
    #[must_use]
    pub fn encode(&self) -> [u8; RECORD_LEN] {
        let mut out = [0u8; RECORD_LEN];
        let words = self.encoder_counts.iter().chain(&self.adc_counts);
        for (slot, w) in out.chunks_exact_mut(2).zip(words) {
            slot.copy_from_slice(&w.to_le_bytes());
        }
        let flags = u8::from(self.mode_pressed)
            | u8::from(self.go_pressed) << 1
            | u8::from(self.e_stop_pressed) << 2
            | u8::from(self.deadline_missed) << 3;
        if let Some(f) = out.get_mut(28) {
            *f = flags;
        }
        if let Some(tail) = out.get_mut(30..) {
            for (slot, c) in tail.chunks_exact_mut(4).zip(self.host_command_nm) {
                slot.copy_from_slice(&c.to_le_bytes());
            }
        }
        out
    }

    /// The record in `b` (its first [`RECORD_LEN`] bytes), if `b` is long
    /// enough.
    #[must_use]
    pub fn decode(b: &[u8]) -> Option<Self> {
        let mut r = Self::default();
        for (i, c) in r.encoder_counts.iter_mut().enumerate() {
            *c = u16_at(b, 2 * i)?;
        }
        for (i, c) in r.adc_counts.iter_mut().enumerate() {
            *c = u16_at(b, 12 + 2 * i)?;
        }
        let flags = *b.get(28)?;
        r.mode_pressed = flags & 1 != 0;
        r.go_pressed = flags & 2 != 0;
        r.e_stop_pressed = flags & 4 != 0;
        r.deadline_missed = flags & 8 != 0;
        for (i, c) in r.host_command_nm.iter_mut().enumerate() {
            *c = f32::from_bits(u32_at(b, 30 + 4 * i)?);
        }
        Some(r)
    }
}

/// The gait's byte in a segment header.
#[must_use]
pub const fn gait_byte(gait: Gait) -> u8 {
    match gait {
        Gait::Walk => 0,
        Gait::StairUp => 1,
        Gait::StairDown => 2,
    }
}

/// The gait of a segment header's byte.
#[must_use]
pub const fn gait_of(byte: u8) -> Option<Gait> {
    match byte {
        0 => Some(Gait::Walk),
        1 => Some(Gait::StairUp),
        2 => Some(Gait::StairDown),
        _ => None,
    }
}

/// The file header for `segments` segments.
#[must_use]
pub fn file_header(segments: u16) -> [u8; FILE_HEADER_LEN] {
    let [v0, v1] = VERSION.to_le_bytes();
    let [s0, s1] = segments.to_le_bytes();
    let [m0, m1, m2, m3] = MAGIC;
    [m0, m1, m2, m3, v0, v1, s0, s1]
}

/// A segment header.
#[must_use]
pub fn segment_header(gait: Gait, ticks: u32) -> [u8; SEGMENT_HEADER_LEN] {
    let [t0, t1, t2, t3] = ticks.to_le_bytes();
    [gait_byte(gait), 0, 0, 0, t0, t1, t2, t3]
}

/// One segment of a file: its gait and its records' bytes.
#[derive(Clone, Copy, Debug)]
pub struct Segment<'a> {
    /// The gait the controller was built for.
    pub gait: Gait,
    /// The records, [`RECORD_LEN`] bytes each.
    pub records: &'a [u8],
}

impl<'a> Segment<'a> {
    /// The records in order.
    pub fn ticks(&self) -> impl Iterator<Item = TickRecord> + 'a {
        self.records
            .chunks_exact(RECORD_LEN)
            .filter_map(TickRecord::decode)
    }
}

/// Why a file was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileError {
    /// Not a tick-record file of this version.
    Header,
    /// A segment header or its records run past the end, or a gait byte
    /// is unknown.
    Segment,
}

/// The segments of `file`, checked up front; `Ok` of an empty file (no
/// recording built in) is no segments.
pub fn segments(file: &[u8]) -> Result<impl Iterator<Item = Segment<'_>>, FileError> {
    let count = if file.is_empty() {
        0
    } else {
        if file.get(0..4) != Some(&MAGIC[..]) || u16_at(file, 4) != Some(VERSION) {
            return Err(FileError::Header);
        }
        u16_at(file, 6).ok_or(FileError::Header)?
    };
    // Validate every segment first, so the iterator below cannot fail.
    let mut at = FILE_HEADER_LEN;
    for _ in 0..count {
        let (_, next) = segment_at(file, at).ok_or(FileError::Segment)?;
        at = next;
    }
    let mut at = FILE_HEADER_LEN;
    Ok((0..count).filter_map(move |_| {
        let (seg, next) = segment_at(file, at)?;
        at = next;
        Some(seg)
    }))
}

/// The segment whose header starts at `at`, and where the next one starts.
fn segment_at(file: &[u8], at: usize) -> Option<(Segment<'_>, usize)> {
    let gait = gait_of(*file.get(at)?)?;
    let ticks = usize::try_from(u32_at(file, at + 4)?).ok()?;
    let start = at + SEGMENT_HEADER_LEN;
    let end = start.checked_add(ticks.checked_mul(RECORD_LEN)?)?;
    let records = file.get(start..end)?;
    Some((Segment { gait, records }, end))
}
