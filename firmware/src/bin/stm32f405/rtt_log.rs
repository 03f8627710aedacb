//! The defmt global logger over one RTT up-channel, written to never panic
//! and never wait: it replaces `defmt-rtt`, whose `_defmt_acquire` /
//! `_defmt_release` panic when the logger is taken re-entrantly and which
//! waits forever for the host in blocking mode.
//!
//! The `_SEGGER_RTT` control block is the one SEGGER's RTT protocol, probe-rs
//! and `defmt-print` read (the layout `defmt-rtt` declares): an ID, one up
//! channel named `defmt` over a 1 KiB ring buffer, no down channel; the
//! frames are defmt's own encoding (`defmt::Encoder`). probe-rs finds the
//! block by its symbol.
//!
//! - **Re-entrance drops the inner frame.** A log taken while another is
//!   being written (a fault handler or NMI interrupting a log; a `Format`
//!   impl that logs) writes nothing and releases nothing: the outer frame
//!   goes on whole.
//! - **A full buffer drops the frame.** Bytes are staged behind the channel's
//!   write offset and published only when the whole frame fits, so the host
//!   sees whole frames or none; the host's request for blocking mode (probe-rs
//!   sets it) is not honoured: a log never stalls the control loop. The
//!   board logs at 1 Hz and on events, well within what a probe reads.
//! - Interrupts are masked from acquire to release (a critical section, as
//!   `defmt-rtt` does); only NMI and faults can interrupt a frame.

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};

/// The ring buffer's size, bytes (a power of two: offsets wrap by masking).
const BUF_SIZE: usize = 1024;
const MASK: usize = BUF_SIZE - 1;
const _: () = assert!(BUF_SIZE.is_power_of_two());

/// RTT channel mode "skip": drop what does not fit (SEGGER_RTT_MODE_NO_BLOCK_SKIP).
const MODE_NO_BLOCK_SKIP: u32 = 0;

/// An RTT up-channel descriptor (SEGGER_RTT_BUFFER_UP).
#[repr(C)]
struct UpChannel {
    name: *const u8,
    buffer: *mut u8,
    size: u32,
    /// Written by the target: where the next byte goes.
    write: AtomicU32,
    /// Written by the host: the next byte it will read.
    read: AtomicU32,
    flags: AtomicU32,
}

/// The RTT control block (SEGGER_RTT_CB), one up channel, no down channel.
#[repr(C)]
struct ControlBlock {
    id: [u8; 16],
    max_up_channels: u32,
    max_down_channels: u32,
    up: UpChannel,
}

// SAFETY: the raw pointers point at statics; the host and the logger share
// the offsets through atomics, the buffer only as the RTT protocol says
// (the target writes bytes ahead of `write`, the host reads up to it).
unsafe impl Sync for ControlBlock {}

struct Buffer(UnsafeCell<[u8; BUF_SIZE]>);

// SAFETY: written only by the logger while it holds the frame (below).
unsafe impl Sync for Buffer {}

/// The ring buffer, in RAM the runtime leaves uninitialised.
#[unsafe(link_section = ".uninit.exogait-rtt.BUFFER")]
static BUFFER: Buffer = Buffer(UnsafeCell::new([0; BUF_SIZE]));

/// The channel's name, in RAM so the block can be read without flash.
#[unsafe(link_section = ".data.exogait-rtt.NAME")]
static NAME: [u8; 6] = *b"defmt\0";

#[unsafe(no_mangle)]
static _SEGGER_RTT: ControlBlock = ControlBlock {
    id: *b"SEGGER RTT\0\0\0\0\0\0",
    max_up_channels: 1,
    max_down_channels: 0,
    up: UpChannel {
        name: NAME.as_ptr(),
        buffer: BUFFER.0.get().cast(),
        size: BUF_SIZE as u32,
        write: AtomicU32::new(0),
        read: AtomicU32::new(0),
        flags: AtomicU32::new(MODE_NO_BLOCK_SKIP),
    },
};

/// How many acquires are open: 1 while a frame is written, more while a
/// re-entrant log is being dropped.
static DEPTH: AtomicU32 = AtomicU32::new(0);
/// Whether interrupts were enabled when the outer frame began.
static IRQ_WAS_ENABLED: AtomicBool = AtomicBool::new(false);
/// Where the frame being written has got to (an offset in the buffer).
static CURSOR: AtomicUsize = AtomicUsize::new(0);
/// Whether the frame being written no longer fits.
static OVERFLOWED: AtomicBool = AtomicBool::new(false);

struct Encoder(UnsafeCell<defmt::Encoder>);

// SAFETY: used only by the holder of the outer frame (DEPTH == 1).
unsafe impl Sync for Encoder {}

static ENCODER: Encoder = Encoder(UnsafeCell::new(defmt::Encoder::new()));

/// Free bytes from `cursor` up to the host's read offset (one slot stays
/// empty so that full and empty differ). Any offsets, even ones a confused
/// host wrote, give a number in 0..BUF_SIZE.
fn free(read: usize, cursor: usize) -> usize {
    read.wrapping_sub(cursor).wrapping_sub(1) & MASK
}

/// Stages `bytes` behind the published write offset, or marks the frame
/// overflowed.
fn stage(bytes: &[u8]) {
    if OVERFLOWED.load(Ordering::Relaxed) {
        return;
    }
    let read = _SEGGER_RTT.up.read.load(Ordering::Relaxed) as usize;
    let start = CURSOR.load(Ordering::Relaxed);
    if bytes.len() > free(read, start) {
        OVERFLOWED.store(true, Ordering::Relaxed);
        return;
    }
    let base = BUFFER.0.get().cast::<u8>();
    let mut at = start;
    for &b in bytes {
        // SAFETY: `at & MASK` < BUF_SIZE; these bytes lie ahead of the
        // published write offset and before the host's read offset (checked
        // above), which the host does not read.
        unsafe { base.add(at & MASK).write_volatile(b) };
        at = at.wrapping_add(1);
    }
    CURSOR.store(at & MASK, Ordering::Relaxed);
}

#[defmt::global_logger]
struct Logger;

// SAFETY: defmt's contract: acquire before write/flush/release, one frame at
// a time per context; re-entrant calls are counted and dropped here.
unsafe impl defmt::Logger for Logger {
    fn acquire() {
        let primask = cortex_m::register::primask::read();
        cortex_m::interrupt::disable();
        if DEPTH.fetch_add(1, Ordering::Acquire) != 0 {
            // Re-entered: this frame is dropped; the outer one restores the
            // interrupt mask.
            return;
        }
        IRQ_WAS_ENABLED.store(primask.is_active(), Ordering::Relaxed);
        OVERFLOWED.store(false, Ordering::Relaxed);
        CURSOR.store(
            _SEGGER_RTT.up.write.load(Ordering::Relaxed) as usize & MASK,
            Ordering::Relaxed,
        );
        // SAFETY: DEPTH went 0 → 1: this context holds the encoder.
        unsafe { (*ENCODER.0.get()).start_frame(stage) };
    }

    unsafe fn flush() {}

    unsafe fn release() {
        match DEPTH.load(Ordering::Relaxed) {
            0 => {}
            1 => {
                // SAFETY: the outer frame's holder.
                unsafe { (*ENCODER.0.get()).end_frame(stage) };
                if !OVERFLOWED.load(Ordering::Relaxed) {
                    _SEGGER_RTT
                        .up
                        .write
                        .store(CURSOR.load(Ordering::Relaxed) as u32, Ordering::Release);
                }
                DEPTH.store(0, Ordering::Release);
                if IRQ_WAS_ENABLED.load(Ordering::Relaxed) {
                    // SAFETY: restores the mask the outer acquire found.
                    unsafe { cortex_m::interrupt::enable() };
                }
            }
            _ => {
                DEPTH.fetch_sub(1, Ordering::Release);
            }
        }
    }

    unsafe fn write(bytes: &[u8]) {
        if DEPTH.load(Ordering::Relaxed) == 1 {
            // SAFETY: the outer frame's holder.
            unsafe { (*ENCODER.0.get()).write(bytes, stage) };
        }
    }
}
