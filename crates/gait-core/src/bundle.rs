//! A patient's table bundle: the body model the clinic fitted, the gaits
//! the clinician cleared for this patient (in the order MODE cycles
//! through them), each with its gait table, as one image in a flash sector
//! of its own, apart from the firmware.
//!
//! The board never plays a bundle it has not verified: [`Bundle::parse`]
//! checks the magic, the format version, the length, a CRC-32 over the
//! whole image, the device fingerprint it was generated for, the patient
//! block's hash and body model, and every gait's directory entry and table
//! (its CRC in the directory and the table's own checks,
//! [`GaitTable::parse`]), before anything of it can be read.
//!
//! # Format, version 1 (all little-endian)
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 4 | magic `b"EXGB"` |
//! | 4 | 2 | format version, `1` |
//! | 6 | 2 | gait count n (1 ≤ n ≤ [`MAX_GAITS`]) |
//! | 8 | 4 | total length L of the image, bytes |
//! | 12 | 4 | device fingerprint (`DeviceConfig::fingerprint` of the device generated for) |
//! | 16 | 4 | generator version, `major << 16 \| minor << 8 \| patch` |
//! | 20 | 4 | patient hash: CRC-32 of the patient block |
//! | 24 | 8 | reserved, 0 |
//! | 32 | 256 | patient block (below) |
//! | 288 | 56 n | directory: one entry per gait (below) |
//! | … | … | the tables, each a [`crate::tables`] image, 4-byte aligned |
//! | L − 4 | 4 | CRC-32/ISO-HDLC of bytes 0 … L − 5 |
//!
//! Patient block (f64): height, mass, thigh, shank and foot lengths (m,
//! kg), then the five links (length, centre of mass, mass, inertia), then
//! the joint limits (hip flexion, hip extension, knee flexion, knee
//! extension, ankle dorsiflexion, ankle plantarflexion, rad), zero-padded.
//!
//! Directory entry: name (16 bytes, ASCII, NUL-padded, not empty), gait
//! kind (one byte, as in the table), the stance hip's torque-residual
//! limit in the gait's swings (one byte, N·m; 0: the device's own limit;
//! [`GaitInfo::stance_hip_residual_nm`]), 2 reserved, then f32: step length
//! (m, horizontal), rise (m, signed: down is negative), tread (m, 0 on
//! level ground), step time (s), pace (closed-loop progression, m/s),
//! clearance (the table's lowest over the floor or nosing, m); then u32:
//! table offset, table length, table CRC (the table's own trailing CRC).

mod write;

pub use write::{GaitSource, bundle_len, encode};

use crate::model::{BodyModel, JointLimits, LINKS, Link};
use crate::tables::{GaitKind, GaitTable, TableError};

/// First four bytes of every bundle.
pub const MAGIC: [u8; 4] = *b"EXGB";
/// The format version this reader understands.
pub const FORMAT_VERSION: u16 = 1;
/// Most gaits a bundle may hold.
pub const MAX_GAITS: usize = 16;
/// Bytes of the header before the patient block.
pub const HEADER_LEN: usize = 32;
/// Bytes of the patient block.
pub const PATIENT_LEN: usize = 256;
/// Bytes of one directory entry.
pub const ENTRY_LEN: usize = 56;
/// Bytes of a gait's name.
pub const NAME_LEN: usize = 16;
/// Largest bundle image, bytes: one 128 KiB flash sector.
pub const MAX_BUNDLE_LEN: usize = 128 * 1024;

const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);
const DIRECTORY_AT: usize = HEADER_LEN + PATIENT_LEN;
/// f64 values in the patient block: 5 measures, 5 × 4 link values, 6 limits.
const PATIENT_VALUES: usize = 5 + 4 * LINKS + 6;

/// Why a bundle image was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BundleError {
    /// No bundle (erased flash or another file): the magic is wrong.
    BadMagic,
    /// A format version this reader does not know.
    UnknownVersion(u16),
    /// Shorter than its header says, longer than a sector, or a table
    /// outside the image.
    BadLength,
    /// The CRC over the image does not match: corrupt.
    BadCrc,
    /// Generated for another device (its fingerprint, this device's).
    ForeignDevice {
        /// The bundle's device fingerprint.
        bundle: u32,
        /// This device's.
        device: u32,
    },
    /// The patient block's hash does not match it.
    BadPatientHash,
    /// The patient's body model is refused by [`BodyModel::new`].
    BadPatient,
    /// No gait, or more than [`MAX_GAITS`].
    BadGaitCount,
    /// A directory entry is malformed (gait index): empty or non-ASCII
    /// name, unknown kind, a non-finite or negative figure, or a table CRC
    /// that is not the table's.
    BadEntry(u8),
    /// A gait's table is refused (gait index, why).
    Table(u8, TableError),
    /// A gait's table is not of the entry's kind (gait index).
    KindMismatch(u8),
    /// The output buffer is too small (writer).
    BufferTooSmall,
}

impl BundleError {
    /// A short name of the reason, without `core::fmt` (the board prints
    /// it, and float or `Debug` formatting would put panic paths into its
    /// image).
    #[must_use]
    pub const fn reason(&self) -> &'static str {
        match self {
            Self::BadMagic => "not-a-bundle",
            Self::UnknownVersion(_) => "unknown-version",
            Self::BadLength => "truncated",
            Self::BadCrc => "crc",
            Self::ForeignDevice { .. } => "foreign-device",
            Self::BadPatientHash => "patient-hash",
            Self::BadPatient => "patient-model",
            Self::BadGaitCount => "gait-count",
            Self::BadEntry(_) => "entry",
            Self::Table(..) => "table",
            Self::KindMismatch(_) => "kind-mismatch",
            Self::BufferTooSmall => "buffer",
        }
    }
}

impl core::fmt::Display for BundleError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BadMagic => f.write_str("not a gait bundle (bad magic)"),
            Self::UnknownVersion(v) => write!(f, "unknown bundle format version {v}"),
            Self::BadLength => f.write_str("truncated or overlong bundle"),
            Self::BadCrc => f.write_str("CRC mismatch: bundle corrupt"),
            Self::ForeignDevice { bundle, device } => write!(
                f,
                "bundle made for another device (fingerprint {bundle:#010x}, this device {device:#010x})"
            ),
            Self::BadPatientHash => f.write_str("patient block does not match its hash"),
            Self::BadPatient => f.write_str("patient body model refused"),
            Self::BadGaitCount => write!(f, "gait count not within 1-{MAX_GAITS}"),
            Self::BadEntry(i) => write!(f, "gait {i}: malformed directory entry"),
            Self::Table(i, e) => write!(f, "gait {i}: table refused: {e}"),
            Self::KindMismatch(i) => write!(f, "gait {i}: table kind differs from the entry's"),
            Self::BufferTooSmall => f.write_str("output buffer too small"),
        }
    }
}

/// The patient a bundle was made for: what the clinic measured and the
/// combined pilot-plus-exoskeleton model built from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patient {
    /// Standing height, m.
    pub height_m: f64,
    /// Body mass without the exoskeleton, kg.
    pub mass_kg: f64,
    /// Thigh, shank and foot lengths the model was built with, m.
    pub segments_m: [f64; 3],
    /// Pilot plus exoskeleton.
    pub model: BodyModel<f64>,
}

impl Patient {
    /// The patient block's values in their order (see the module docs).
    fn values(&self) -> [f64; PATIENT_VALUES] {
        let mut v = [0.0; PATIENT_VALUES];
        let l = self.model.limits();
        let head = [
            self.height_m,
            self.mass_kg,
            self.segments_m[0],
            self.segments_m[1],
            self.segments_m[2],
        ];
        let links = self
            .model
            .links()
            .iter()
            .flat_map(|k| [k.length_m, k.com_m, k.mass_kg, k.inertia_kgm2]);
        let limits = [
            l.hip_flexion_rad,
            l.hip_extension_rad,
            l.knee_flexion_rad,
            l.knee_extension_rad,
            l.ankle_dorsiflexion_rad,
            l.ankle_plantarflexion_rad,
        ];
        for (dst, src) in v
            .iter_mut()
            .zip(head.into_iter().chain(links).chain(limits))
        {
            *dst = src;
        }
        v
    }

    /// The patient block.
    pub fn block(&self) -> [u8; PATIENT_LEN] {
        let mut b = [0u8; PATIENT_LEN];
        for (chunk, v) in b.chunks_exact_mut(8).zip(self.values()) {
            chunk.copy_from_slice(&v.to_le_bytes());
        }
        b
    }

    /// The patient's hash: CRC-32 of its block.
    pub fn hash(&self) -> u32 {
        CRC32.checksum(&self.block())
    }

    fn from_block(block: &[u8]) -> Result<Self, BundleError> {
        let mut v = [0.0f64; PATIENT_VALUES];
        for (dst, chunk) in v.iter_mut().zip(block.chunks_exact(8)) {
            let bytes: [u8; 8] = chunk.try_into().map_err(|_| BundleError::BadLength)?;
            *dst = f64::from_le_bytes(bytes);
        }
        let at = |i: usize| v.get(i).copied().unwrap_or(f64::NAN);
        let link = |k: usize| Link {
            length_m: at(5 + 4 * k),
            com_m: at(6 + 4 * k),
            mass_kg: at(7 + 4 * k),
            inertia_kgm2: at(8 + 4 * k),
        };
        let lim = 5 + 4 * LINKS;
        let limits = JointLimits {
            hip_flexion_rad: at(lim),
            hip_extension_rad: at(lim + 1),
            knee_flexion_rad: at(lim + 2),
            knee_extension_rad: at(lim + 3),
            ankle_dorsiflexion_rad: at(lim + 4),
            ankle_plantarflexion_rad: at(lim + 5),
        };
        let model = BodyModel::new([link(0), link(1), link(2), link(3), link(4)], limits)
            .map_err(|_| BundleError::BadPatient)?;
        let measures = [at(0), at(1), at(2), at(3), at(4)];
        if measures.iter().any(|m| !m.is_finite() || *m <= 0.0) {
            return Err(BundleError::BadPatient);
        }
        Ok(Self {
            height_m: at(0),
            mass_kg: at(1),
            segments_m: [at(2), at(3), at(4)],
            model,
        })
    }
}

/// A gait's name: up to [`NAME_LEN`] ASCII characters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GaitName {
    bytes: [u8; NAME_LEN],
    len: usize,
}

impl GaitName {
    /// `name` if it is 1 … [`NAME_LEN`] printable ASCII characters.
    pub fn new(name: &str) -> Option<Self> {
        let b = name.as_bytes();
        if b.is_empty() || b.len() > NAME_LEN || !b.iter().all(|c| c.is_ascii_graphic()) {
            return None;
        }
        let mut bytes = [0u8; NAME_LEN];
        for (d, s) in bytes.iter_mut().zip(b) {
            *d = *s;
        }
        Some(Self {
            bytes,
            len: b.len(),
        })
    }

    fn from_field(field: &[u8]) -> Option<Self> {
        let len = field.iter().position(|&c| c == 0).unwrap_or(field.len());
        let (name, pad) = field.split_at_checked(len)?;
        if pad.iter().any(|&c| c != 0) {
            return None;
        }
        Self::new(core::str::from_utf8(name).ok()?)
    }

    /// The name.
    pub fn as_str(&self) -> &str {
        self.bytes
            .get(..self.len)
            .and_then(|b| core::str::from_utf8(b).ok())
            .unwrap_or("")
    }
}

/// What a bundle says of one gait besides its table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaitInfo {
    /// The gait's name (what the clinician and `exogait` call it).
    pub name: GaitName,
    /// Which movement.
    pub kind: GaitKind,
    /// Horizontal step length, m.
    pub step_length_m: f32,
    /// Rise per step, m (negative going down; 0 on level ground).
    pub rise_m: f32,
    /// Stair tread, m (0 on level ground).
    pub tread_m: f32,
    /// Step time (the table's swing), s.
    pub step_time_s: f32,
    /// Progression in the closed loop over four steps, m/s.
    pub pace_m_s: f32,
    /// Lowest swing-foot clearance the table plans over the floor or
    /// the nosing, m.
    pub clearance_m: f32,
    /// The torque residual the stance hip may show in this gait's swings
    /// before it is taken for a drive fault (0x0404), N·m: what the
    /// gait's healthy closed loop showed there, with a margin, measured
    /// by the generator (0: the device's own limit). The board's
    /// supervisor holds it within its bounds.
    pub stance_hip_residual_nm: u8,
}

/// One verified gait of a bundle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BundleGait<'a> {
    /// Its description.
    pub info: GaitInfo,
    /// Its verified table.
    pub table: GaitTable<'a>,
}

/// A verified bundle (borrowing its image, typically in flash).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bundle<'a> {
    image: &'a [u8],
    count: usize,
    device_fingerprint: u32,
    generator_version: u32,
    patient_hash: u32,
    patient: Patient,
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    let s: [u8; 2] = b.get(at..at + 2)?.try_into().ok()?;
    Some(u16::from_le_bytes(s))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    let s: [u8; 4] = b.get(at..at + 4)?.try_into().ok()?;
    Some(u32::from_le_bytes(s))
}

fn f32_at(b: &[u8], at: usize) -> Option<f32> {
    u32_at(b, at).map(f32::from_bits)
}

fn kind_byte(kind: GaitKind) -> u8 {
    match kind {
        GaitKind::Walk => 0,
        GaitKind::StairUp => 1,
        GaitKind::StairDown => 2,
    }
}

fn kind_from_byte(b: u8) -> Option<GaitKind> {
    match b {
        0 => Some(GaitKind::Walk),
        1 => Some(GaitKind::StairUp),
        2 => Some(GaitKind::StairDown),
        _ => None,
    }
}

/// The length a bundle image in `sector` says it has (`None`: no magic,
/// or a length that does not fit): how much of a flash sector to verify.
pub fn stored_len(sector: &[u8]) -> Option<usize> {
    if sector.get(0..4) != Some(&MAGIC[..]) {
        return None;
    }
    let len = usize::try_from(u32_at(sector, 8)?).ok()?;
    (len <= sector.len() && len <= MAX_BUNDLE_LEN).then_some(len)
}

impl<'a> Bundle<'a> {
    /// Verifies the bundle at the start of a flash sector (the rest of the
    /// sector, erased or not, is ignored) for the device of fingerprint
    /// `device`.
    pub fn parse_sector(sector: &'a [u8], device: u32) -> Result<Self, BundleError> {
        if sector.get(0..4) != Some(&MAGIC[..]) {
            return Err(BundleError::BadMagic);
        }
        let len = stored_len(sector).ok_or(BundleError::BadLength)?;
        Self::parse(sector.get(..len).ok_or(BundleError::BadLength)?, device)
    }

    /// Verifies an image for the device of fingerprint `device`; nothing of
    /// an image that fails any check can be read.
    pub fn parse(image: &'a [u8], device: u32) -> Result<Self, BundleError> {
        if image.get(0..4) != Some(&MAGIC[..]) {
            return Err(BundleError::BadMagic);
        }
        let version = u16_at(image, 4).ok_or(BundleError::BadLength)?;
        if version != FORMAT_VERSION {
            return Err(BundleError::UnknownVersion(version));
        }
        let len = u32_at(image, 8).ok_or(BundleError::BadLength)? as usize;
        if len != image.len() || !(DIRECTORY_AT + 4..=MAX_BUNDLE_LEN).contains(&len) {
            return Err(BundleError::BadLength);
        }
        let body_end = len - 4;
        let body = image.get(..body_end).ok_or(BundleError::BadLength)?;
        if Some(CRC32.checksum(body)) != u32_at(image, body_end) {
            return Err(BundleError::BadCrc);
        }
        let fingerprint = u32_at(image, 12).ok_or(BundleError::BadLength)?;
        if fingerprint != device {
            return Err(BundleError::ForeignDevice {
                bundle: fingerprint,
                device,
            });
        }
        let count = usize::from(u16_at(image, 6).ok_or(BundleError::BadLength)?);
        if !(1..=MAX_GAITS).contains(&count) {
            return Err(BundleError::BadGaitCount);
        }
        if DIRECTORY_AT + count * ENTRY_LEN > body_end {
            return Err(BundleError::BadLength);
        }
        let block = image
            .get(HEADER_LEN..DIRECTORY_AT)
            .ok_or(BundleError::BadLength)?;
        let patient_hash = u32_at(image, 20).ok_or(BundleError::BadLength)?;
        if CRC32.checksum(block) != patient_hash {
            return Err(BundleError::BadPatientHash);
        }
        let patient = Patient::from_block(block)?;
        let bundle = Self {
            image,
            count,
            device_fingerprint: fingerprint,
            generator_version: u32_at(image, 16).ok_or(BundleError::BadLength)?,
            patient_hash,
            patient,
        };
        // Bounded: count ≤ MAX_GAITS.
        for i in 0..count {
            bundle.entry(i)?;
        }
        Ok(bundle)
    }

    /// Entry `i`, verified with its table.
    fn entry(&self, i: usize) -> Result<BundleGait<'a>, BundleError> {
        let tag = u8::try_from(i).unwrap_or(u8::MAX);
        let at = DIRECTORY_AT + i * ENTRY_LEN;
        let e = self
            .image
            .get(at..at + ENTRY_LEN)
            .ok_or(BundleError::BadLength)?;
        let bad = BundleError::BadEntry(tag);
        let name = GaitName::from_field(e.get(..NAME_LEN).ok_or(bad)?).ok_or(bad)?;
        let kind = kind_from_byte(e.get(NAME_LEN).copied().ok_or(bad)?).ok_or(bad)?;
        let stance_hip_residual_nm = e.get(NAME_LEN + 1).copied().ok_or(bad)?;
        let f = |k: usize| f32_at(e, 20 + 4 * k).ok_or(bad);
        let info = GaitInfo {
            name,
            kind,
            step_length_m: f(0)?,
            rise_m: f(1)?,
            tread_m: f(2)?,
            step_time_s: f(3)?,
            pace_m_s: f(4)?,
            clearance_m: f(5)?,
            stance_hip_residual_nm,
        };
        let figures = [
            info.step_length_m,
            info.rise_m,
            info.tread_m,
            info.step_time_s,
            info.pace_m_s,
            info.clearance_m,
        ];
        if figures.iter().any(|v| !v.is_finite())
            || info.step_length_m < 0.0
            || info.tread_m < 0.0
            || info.step_time_s <= 0.0
            || info.pace_m_s < 0.0
        {
            return Err(bad);
        }
        let offset = u32_at(e, 44).ok_or(bad)? as usize;
        let table_len = u32_at(e, 48).ok_or(bad)? as usize;
        let table_crc = u32_at(e, 52).ok_or(bad)?;
        let end = offset
            .checked_add(table_len)
            .ok_or(BundleError::BadLength)?;
        let dir_end = DIRECTORY_AT + self.count * ENTRY_LEN;
        if offset < dir_end || end > self.image.len().saturating_sub(4) {
            return Err(BundleError::BadLength);
        }
        let image = self.image.get(offset..end).ok_or(BundleError::BadLength)?;
        let table = GaitTable::parse(image).map_err(|t| BundleError::Table(tag, t))?;
        if u32_at(image, table_len.saturating_sub(4)) != Some(table_crc) {
            return Err(bad);
        }
        if table.kind() != kind {
            return Err(BundleError::KindMismatch(tag));
        }
        Ok(BundleGait {
            info,
            table: table.with_stance_hip_residual_nm(stance_hip_residual_nm),
        })
    }

    /// Number of gaits.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Always false for a verified bundle.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Gait `i` in the clinician's order (`None` past the end).
    pub fn gait(&self, i: usize) -> Option<BundleGait<'a>> {
        (i < self.count).then(|| self.entry(i).ok()).flatten()
    }

    /// The first gait named `name`.
    pub fn find(&self, name: &str) -> Option<(usize, BundleGait<'a>)> {
        (0..self.count).find_map(|i| {
            let g = self.gait(i)?;
            (g.info.name.as_str() == name).then_some((i, g))
        })
    }

    /// The patient.
    pub fn patient(&self) -> &Patient {
        &self.patient
    }

    /// The patient block's hash.
    pub fn patient_hash(&self) -> u32 {
        self.patient_hash
    }

    /// The fingerprint of the device the bundle was generated for.
    pub fn device_fingerprint(&self) -> u32 {
        self.device_fingerprint
    }

    /// The generator's version (`major << 16 | minor << 8 | patch`).
    pub fn generator_version(&self) -> u32 {
        self.generator_version
    }

    /// The image's CRC (its last four bytes).
    pub fn crc(&self) -> u32 {
        u32_at(self.image, self.image.len().saturating_sub(4)).unwrap_or(0)
    }

    /// The image's length, bytes.
    pub fn image_len(&self) -> usize {
        self.image.len()
    }
}
