//! Writing a bundle: the one definition of the format's layout on the
//! writer's side; every image written is read back by [`Bundle::parse`].

use super::{
    Bundle, BundleError, CRC32, DIRECTORY_AT, ENTRY_LEN, FORMAT_VERSION, GaitInfo, HEADER_LEN,
    MAGIC, MAX_BUNDLE_LEN, MAX_GAITS, NAME_LEN, Patient, kind_byte, u32_at,
};

/// One gait to write: its description and its table image (already
/// verified by the writer's caller or refused here).
#[derive(Clone, Copy, Debug)]
pub struct GaitSource<'t> {
    /// Its description.
    pub info: GaitInfo,
    /// Its table image.
    pub table: &'t [u8],
}

/// The image length of a bundle of `gaits`.
pub fn bundle_len(gaits: &[GaitSource<'_>]) -> usize {
    let tables: usize = gaits
        .iter()
        .map(|g| g.table.len().next_multiple_of(4))
        .sum();
    DIRECTORY_AT + gaits.len() * ENTRY_LEN + tables + 4
}

/// Writes a bundle into `out`; returns its length. Refuses what the reader
/// would refuse (read back with `device` before returning).
pub fn encode(
    device: u32,
    generator_version: u32,
    patient: &Patient,
    gaits: &[GaitSource<'_>],
    out: &mut [u8],
) -> Result<usize, BundleError> {
    if !(1..=MAX_GAITS).contains(&gaits.len()) {
        return Err(BundleError::BadGaitCount);
    }
    let len = bundle_len(gaits);
    if len > MAX_BUNDLE_LEN {
        return Err(BundleError::BadLength);
    }
    let img = out.get_mut(..len).ok_or(BundleError::BufferTooSmall)?;
    img.fill(0);
    let put = |img: &mut [u8], at: usize, bytes: &[u8]| -> Result<(), BundleError> {
        img.get_mut(at..at + bytes.len())
            .ok_or(BundleError::BufferTooSmall)?
            .copy_from_slice(bytes);
        Ok(())
    };
    let count = u16::try_from(gaits.len()).map_err(|_| BundleError::BadGaitCount)?;
    let total = u32::try_from(len).map_err(|_| BundleError::BadLength)?;
    put(img, 0, &MAGIC)?;
    put(img, 4, &FORMAT_VERSION.to_le_bytes())?;
    put(img, 6, &count.to_le_bytes())?;
    put(img, 8, &total.to_le_bytes())?;
    put(img, 12, &device.to_le_bytes())?;
    put(img, 16, &generator_version.to_le_bytes())?;
    put(img, 20, &patient.hash().to_le_bytes())?;
    put(img, HEADER_LEN, &patient.block())?;
    let mut offset = DIRECTORY_AT + gaits.len() * ENTRY_LEN;
    for (i, g) in gaits.iter().enumerate() {
        let at = DIRECTORY_AT + i * ENTRY_LEN;
        let bad = BundleError::BadEntry(u8::try_from(i).unwrap_or(u8::MAX));
        put(
            img,
            at,
            g.info.name.bytes.get(..g.info.name.len).ok_or(bad)?,
        )?;
        put(
            img,
            at + NAME_LEN,
            &[kind_byte(g.info.kind), g.info.stance_hip_residual_nm],
        )?;
        let i = &g.info;
        let figures = [
            i.step_length_m,
            i.rise_m,
            i.tread_m,
            i.step_time_s,
            i.pace_m_s,
            i.clearance_m,
        ];
        for (k, v) in figures.iter().enumerate() {
            put(img, at + 20 + 4 * k, &v.to_le_bytes())?;
        }
        let crc = u32_at(g.table, g.table.len().saturating_sub(4)).ok_or(bad)?;
        let o = u32::try_from(offset).map_err(|_| BundleError::BadLength)?;
        let l = u32::try_from(g.table.len()).map_err(|_| BundleError::BadLength)?;
        put(img, at + 44, &o.to_le_bytes())?;
        put(img, at + 48, &l.to_le_bytes())?;
        put(img, at + 52, &crc.to_le_bytes())?;
        put(img, offset, g.table)?;
        offset += g.table.len().next_multiple_of(4);
    }
    let crc = CRC32.checksum(img.get(..len - 4).ok_or(BundleError::BufferTooSmall)?);
    put(img, len - 4, &crc.to_le_bytes())?;
    Bundle::parse(img, device)?;
    Ok(len)
}
