//! The flash sectors the board loads data from, apart from its image: the
//! patient's gait bundle (`gait_core::bundle`) and the calibration record
//! (`exogait_device::calibration`). The linker keeps the image out of them
//! (`memory.x`, `qemu/memory.x`: the `FLASH` region ends where they begin),
//! so flashing a new image leaves a patient's bundle and calibration as
//! they are, and `cargo xtask flash-bundle` writes the bundle's sector
//! alone.
//!
//! This is the crate's one `unsafe`: the sectors are memory no Rust value
//! describes, read as byte slices. Everything read from them is verified
//! (magic, version, CRC, plausibility) before any of it is used.
#![allow(unsafe_code)]

/// Where the sectors are on each board: (bundle, bundle length,
/// calibration, calibration length), bytes.
#[cfg(feature = "board-stm32f405")]
const LAYOUT: (usize, usize, usize, usize) = (0x080E_0000, 128 * 1024, 0x080C_0000, 16 * 1024);
#[cfg(not(feature = "board-stm32f405"))]
const LAYOUT: (usize, usize, usize, usize) = (0x0030_0000, 128 * 1024, 0x0032_0000, 16 * 1024);

/// Where the QEMU image finds a recording of the host's run of a bundle's
/// first gait (`cargo xtask qemu --bundle`), and its largest length.
#[cfg(not(feature = "board-stm32f405"))]
pub const STEP_RECORDING: (usize, usize) = (0x0034_0000, 0x000C_0000);

/// Address of the bundle sector (`cargo xtask flash-bundle` writes there).
pub const BUNDLE_ADDRESS: usize = LAYOUT.0;
/// Address of the calibration sector.
pub const CALIBRATION_ADDRESS: usize = LAYOUT.2;

/// `len` bytes of memory-mapped flash at `address`.
fn sector(address: usize, len: usize) -> &'static [u8] {
    // SAFETY: `address .. address + len` is flash (or QEMU's code memory)
    // the linker script reserves for this data: mapped, readable, never
    // written while the firmware runs, and outside every Rust allocation,
    // so a shared `'static` slice over it aliases nothing.
    unsafe { core::slice::from_raw_parts(address as *const u8, len) }
}

/// The bundle sector.
#[must_use]
pub fn bundle() -> &'static [u8] {
    sector(LAYOUT.0, LAYOUT.1)
}

/// The calibration sector.
#[must_use]
pub fn calibration() -> &'static [u8] {
    sector(LAYOUT.2, LAYOUT.3)
}

/// The recording of a bundle's first step loaded beside the QEMU image.
#[cfg(not(feature = "board-stm32f405"))]
#[must_use]
pub fn step_recording() -> &'static [u8] {
    sector(STEP_RECORDING.0, STEP_RECORDING.1)
}
