//! The sensors read by DMA before each tick (`gait_control::acquisition`):
//! the tick decodes frames, it neither polls a bus nor waits for one.
//!
//! TIM2's compare channel 1 fires [`LEAD_US`] before each period ends and
//! [`start`]s both buses at once. Each frame is one DMA transfer (an RX
//! and a TX stream, bytes) inside its own chip-select window; the RX
//! stream's transfer-complete interrupt raises the chip select, hands the
//! reply to the round, lowers the next chip select and re-arms both
//! streams (Betaflight's SPI scheme). The rounds decide the frames
//! (`EncoderRound`: every ANGLE command, then every NOP, an error flag
//! cleared at once; `AdcRound`: four force sensors and one drive monitor),
//! so the interrupts only move bytes: about 100–250 cycles a frame
//! (chip-select waits included), 17 frames a tick.
//!
//! - SPI1 (encoders): DMA2 stream 0 (RX) and stream 3 (TX), channel 3.
//! - SPI2 (ADC): DMA1 stream 3 (RX) and stream 4 (TX), channel 0
//!   (RM0090 §10.3.3, tables 42–43).
//!
//! DMA2 serves only SPI1 here (APB2): erratum ES0182 §2.1.10 (DMA2 moving
//! data for AHB and APB2 peripherals at once) does not arise.
//!
//! The finished frames wait for the tick stamped with the period they were
//! started in. A tick that finds none of its own (the acquisition did not
//! finish, or started late behind an overrunning tick) stops what is still
//! running and reads the sensors itself through the drivers' blocking
//! buses, about 235 µs (both buses in turn), as the host's tick always does: the controller is
//! never left without this tick's sensors. The status line counts those
//! ticks; the next period's start aborts what is still running.

use core::cell::RefCell;
use core::sync::atomic::{AtomicU8, AtomicU32, Ordering, fence};

use cortex_m::interrupt::{self, Mutex};
use cortex_m::peripheral::NVIC;
use gait_control::acquisition::{AdcRound, EncoderRound, Frames, Handoff};
use gait_control::controller::ENCODERS;
use gait_control::drivers::mcp3208::{Channel, ForceChannels};
use gait_control::posture::JOINTS;
use stm32f4xx_hal::gpio::PinExt;
use stm32f4xx_hal::pac::{self, RCC, dma2, gpioa, spi1};

use crate::{ADC_CS_CYCLES, ENCODER_CS_CYCLES};

/// How long before a tick its acquisition starts, µs. The ADC's bus is
/// the slow one: five 24-bit conversions at 656 kHz take 183 µs; the
/// encoders' twelve 16-bit frames at 5.25 MHz take 37 µs on the wire,
/// about 60 µs with their interrupts, beside them.
pub const LEAD_US: u32 = 250;

/// SPI1's DMA (DMA2) streams and channel; SPI2's (DMA1).
const ENC_RX: usize = 0;
const ENC_TX: usize = 3;
const ENC_CHANNEL: u8 = 3;
const ADC_RX: usize = 3;
const ADC_TX: usize = 4;
const ADC_CHANNEL: u8 = 0;
/// Polls for a stream's EN bit to clear or the SPI to go idle when a
/// transfer is stopped: at least 4 cycles each, 48 µs in all, four byte
/// times of the ADC's bus (12.2 µs a byte at 656 kHz).
const SPI_POLLS: u32 = 2_000;

/// The DMA's buffers. It reads and writes them behind the compiler's
/// back: as atomics, each access is a real load or store.
static ENC_TX_BUF: [AtomicU8; 2] = [const { AtomicU8::new(0) }; 2];
static ENC_RX_BUF: [AtomicU8; 2] = [const { AtomicU8::new(0) }; 2];
static ADC_TX_BUF: [AtomicU8; 3] = [const { AtomicU8::new(0) }; 3];
static ADC_RX_BUF: [AtomicU8; 3] = [const { AtomicU8::new(0) }; 3];

/// The drive monitor the next acquisition reads (the controller's word
/// after each tick).
static NEXT_DRIVE_JOINT: AtomicU8 = AtomicU8::new(1);
/// Ticks that found no frames of their own, since boot.
static MISSED: AtomicU32 = AtomicU32::new(0);

static ENGINE: Mutex<RefCell<Option<Engine>>> = Mutex::new(RefCell::new(None));
/// The last finished acquisition, for the tick of the period after its
/// start.
static READY: Handoff = Handoff::new();

/// A chip select: its GPIO port and pin, driven through BSRR.
#[derive(Clone, Copy)]
pub struct Line {
    port: u8,
    pin: u8,
}

impl Line {
    /// The line of a configured output pin.
    pub fn of(pin: &impl PinExt) -> Self {
        Self {
            port: pin.port_id(),
            pin: pin.pin_id(),
        }
    }

    fn block(self) -> &'static gpioa::RegisterBlock {
        // SAFETY: GPIOA..GPIOI are 0x400 apart with one register layout
        // (RM0090 §2.3); only BSRR is written, whose writes are atomic and
        // touch only the bits set, so whatever else owns the port is not
        // disturbed. `port` comes from a configured pin (0..=8).
        unsafe { &*pac::GPIOA::ptr().byte_add(usize::from(self.port) * 0x400) }
    }

    fn low(self) {
        // SAFETY: as in `block`; any BSRR value is valid.
        self.block()
            .bsrr()
            .write(|w| unsafe { w.bits(1 << (u32::from(self.pin) + 16)) });
    }

    fn high(self) {
        // SAFETY: as in `block`.
        self.block()
            .bsrr()
            .write(|w| unsafe { w.bits(1 << u32::from(self.pin)) });
    }
}

/// The peripherals the acquisition drives.
// SAFETY (each): once `install` has run, the acquisition and the blocking
// buses the drivers were built over never use a bus at once: those serve
// the calibration at boot, before it, and after it only a tick that found
// no frames of its own, which first stops the acquisition (`stop`); the
// tick and the acquisition's interrupts share one priority and critical
// sections. The DMA controllers serve nothing else.
fn spi1() -> &'static spi1::RegisterBlock {
    unsafe { &*pac::SPI1::ptr() }
}
fn spi2() -> &'static spi1::RegisterBlock {
    unsafe { &*pac::SPI2::ptr() }
}
fn dma1() -> &'static dma2::RegisterBlock {
    unsafe { &*pac::DMA1::ptr() }
}
fn dma2() -> &'static dma2::RegisterBlock {
    unsafe { &*pac::DMA2::ptr() }
}

/// One acquisition's state, between the interrupts.
struct Engine {
    encoder_cs: [Line; ENCODERS],
    adc_cs: Line,
    forces: [Channel; 4],
    drives: [Channel; JOINTS],
    encoders: EncoderRound,
    /// The encoder the frame in flight is on.
    chip: Option<usize>,
    adc: AdcRound,
    adc_busy: bool,
    /// The period the acquisition was started in; `None`: none running.
    running: Option<u32>,
}

/// Sets up the streams and hands the buses to the acquisition; call once
/// the drivers are built and the calibration is done, before the tick's
/// timer starts.
pub fn install(
    rcc: &RCC,
    encoder_cs: [Line; ENCODERS],
    adc_cs: Line,
    forces: ForceChannels,
    drives: [Channel; JOINTS],
) {
    rcc.ahb1enr()
        .modify(|_, w| w.dma1en().set_bit().dma2en().set_bit());
    let _ = rcc.ahb1enr().read();
    let streams: [(
        &dma2::RegisterBlock,
        usize,
        usize,
        u8,
        &spi1::RegisterBlock,
        u32,
        u32,
    ); 2] = [
        (
            dma2(),
            ENC_RX,
            ENC_TX,
            ENC_CHANNEL,
            spi1(),
            ENC_RX_BUF.as_ptr() as u32,
            ENC_TX_BUF.as_ptr() as u32,
        ),
        (
            dma1(),
            ADC_RX,
            ADC_TX,
            ADC_CHANNEL,
            spi2(),
            ADC_RX_BUF.as_ptr() as u32,
            ADC_TX_BUF.as_ptr() as u32,
        ),
    ];
    for (dma, rx, tx, channel, spi, rx_buf, tx_buf) in streams {
        let dr = spi.dr().as_ptr() as u32;
        // RM0090 §10.5.5: channel, priority, bytes, memory incremented,
        // direction; the RX stream interrupts on completion and on error.
        dma.st(rx).cr().write(|w| {
            w.chsel().set(channel);
            w.pl().very_high();
            w.minc().incremented();
            w.dir().peripheral_to_memory();
            w.tcie().enabled();
            w.teie().enabled()
        });
        dma.st(tx).cr().write(|w| {
            w.chsel().set(channel);
            w.pl().very_high();
            w.minc().incremented();
            w.dir().memory_to_peripheral()
        });
        // SAFETY: the addresses of the SPI's data register and of the
        // buffers, which live for the program.
        dma.st(rx).par().write(|w| unsafe { w.pa().bits(dr) });
        dma.st(rx).m0ar().write(|w| unsafe { w.m0a().bits(rx_buf) });
        dma.st(tx).par().write(|w| unsafe { w.pa().bits(dr) });
        dma.st(tx).m0ar().write(|w| unsafe { w.m0a().bits(tx_buf) });
        // RM0090 §28.3.9: the SPI asks the DMA for each byte.
        spi.cr2()
            .modify(|_, w| w.rxdmaen().set_bit().txdmaen().set_bit());
    }
    let engine = Engine {
        encoder_cs,
        adc_cs,
        forces: [
            forces.left_foot,
            forces.right_foot,
            forces.left_crutch,
            forces.right_crutch,
        ],
        drives,
        encoders: EncoderRound::new(),
        chip: None,
        adc: AdcRound::new([Channel::Ch0; 4], None, 0),
        adc_busy: false,
        running: None,
    };
    interrupt::free(|cs| {
        if let Ok(mut slot) = ENGINE.borrow(cs).try_borrow_mut() {
            *slot = Some(engine);
        }
    });
    // SAFETY: their handlers share state only through `ENGINE` and `READY`
    // (critical sections); they run at the tick's priority, so neither
    // preempts the other.
    unsafe {
        NVIC::unmask(pac::Interrupt::DMA2_STREAM0);
        NVIC::unmask(pac::Interrupt::DMA1_STREAM3);
    }
}

/// Starts the acquisition for the tick that ends `period` (TIM2's compare
/// interrupt); aborts one still running.
pub fn start(period: u32) {
    with_engine(|e| {
        if e.running.is_some() {
            e.abort();
        }
        let joint = NEXT_DRIVE_JOINT.load(Ordering::Relaxed);
        e.encoders = EncoderRound::new();
        e.adc = AdcRound::new(e.forces, e.drives.get(usize::from(joint)).copied(), joint);
        e.running = Some(period);
        e.next_encoder_frame(None);
        e.next_conversion();
        e.finish_if_done();
    });
}

/// The frames of the acquisition started in `period`, once (the tick's
/// own); `None` when there are none (counted: [`missed`]).
pub fn take(period: u32) -> Option<Frames> {
    let frames = READY.take(period);
    if frames.is_none() {
        MISSED.fetch_add(1, Ordering::Relaxed);
    }
    frames
}

/// Stops an acquisition still running and leaves both buses idle, every
/// chip select high: for a tick that found no frames of its own and reads
/// the sensors itself, through the drivers' blocking buses.
pub fn stop() {
    with_engine(Engine::abort);
}

/// `f` on the installed engine, in a critical section. Never borrowed
/// twice (each borrow is inside one); `try_` keeps the panic of a double
/// borrow out of the image.
fn with_engine(f: impl FnOnce(&mut Engine)) {
    interrupt::free(|cs| {
        if let Ok(mut engine) = ENGINE.borrow(cs).try_borrow_mut()
            && let Some(e) = engine.as_mut()
        {
            f(e);
        }
    });
}

/// The drive monitor the next acquisition reads.
pub fn set_next_drive_joint(joint: u8) {
    NEXT_DRIVE_JOINT.store(joint, Ordering::Relaxed);
}

/// Ticks that found no frames of their own, since boot.
pub fn missed() -> u32 {
    MISSED.load(Ordering::Relaxed)
}

/// DMA2 stream 0's interrupt: an encoder frame ended.
pub fn on_encoder_frame() {
    with_engine(|e| {
        let Some(failed) = Bus::Encoders.ended() else {
            return;
        };
        let chip = e.chip.take();
        if let Some(line) = chip.and_then(|c| e.encoder_cs.get(c)) {
            line.high();
        }
        let reply = (!failed).then(|| {
            u16::from_be_bytes([
                ENC_RX_BUF[0].load(Ordering::Relaxed),
                ENC_RX_BUF[1].load(Ordering::Relaxed),
            ])
        });
        e.encoders.answer(reply);
        e.next_encoder_frame(chip);
        e.finish_if_done();
    });
}

/// DMA1 stream 3's interrupt: a conversion ended.
pub fn on_conversion() {
    with_engine(|e| {
        let Some(failed) = Bus::Adc.ended() else {
            return;
        };
        e.adc_cs.high();
        e.adc_busy = false;
        let reply = (!failed).then(|| ADC_RX_BUF.each_ref().map(|b| b.load(Ordering::Relaxed)));
        e.adc.answer(reply);
        // MCP3208: CS high at least 500 ns between conversions (tCSH).
        cortex_m::asm::delay(ADC_CS_CYCLES);
        e.next_conversion();
        e.finish_if_done();
    });
}

impl Engine {
    /// Sends the round's next encoder frame, if any. `last`: the chip of
    /// the frame just ended (a frame on the same chip waits for its CSn
    /// high time, 350 ns).
    fn next_encoder_frame(&mut self, last: Option<usize>) {
        let Some((chip, command)) = self.encoders.next() else {
            return;
        };
        let Some(&line) = self.encoder_cs.get(chip) else {
            self.encoders.answer(None);
            return;
        };
        let [hi, lo] = command.to_be_bytes();
        ENC_TX_BUF[0].store(hi, Ordering::Relaxed);
        ENC_TX_BUF[1].store(lo, Ordering::Relaxed);
        if last == Some(chip) {
            cortex_m::asm::delay(ENCODER_CS_CYCLES);
        }
        Bus::Encoders.drain();
        self.chip = Some(chip);
        line.low();
        Bus::Encoders.arm(2, ENCODER_CS_CYCLES);
    }

    /// Sends the round's next conversion, if any.
    fn next_conversion(&mut self) {
        let Some(request) = self.adc.next() else {
            return;
        };
        for (b, r) in ADC_TX_BUF.iter().zip(request) {
            b.store(r, Ordering::Relaxed);
        }
        Bus::Adc.drain();
        self.adc_busy = true;
        self.adc_cs.low();
        // MCP3208: CS low to the first clock, 100 ns (tSUCS).
        Bus::Adc.arm(3, ADC_CS_CYCLES / 4);
    }

    /// Publishes the frames once both rounds are done.
    fn finish_if_done(&mut self) {
        let done = self.chip.is_none()
            && self.encoders.next().is_none()
            && !self.adc_busy
            && self.adc.next().is_none();
        if let (true, Some(period)) = (done, self.running) {
            READY.publish(period, Frames::of(&self.encoders, &self.adc));
            self.running = None;
        }
    }

    /// Stops both buses and raises every chip select: what was not read
    /// is lost, and the new round starts on idle buses.
    fn abort(&mut self) {
        Bus::Encoders.stop();
        Bus::Adc.stop();
        self.encoder_cs.iter().for_each(|l| l.high());
        self.adc_cs.high();
        self.chip = None;
        self.adc_busy = false;
        self.running = None;
    }
}

/// A bus and its two DMA streams.
#[derive(Clone, Copy)]
enum Bus {
    /// SPI1 on DMA2 streams 0 (RX) and 3 (TX).
    Encoders,
    /// SPI2 on DMA1 streams 3 (RX) and 4 (TX).
    Adc,
}

/// A stream's flags in its six-bit group of LISR/HISR: direct mode error,
/// transfer error, transfer complete.
const DMEIF: u32 = 1 << 2;
const TEIF: u32 = 1 << 3;
const TCIF: u32 = 1 << 5;

impl Bus {
    fn parts(
        self,
    ) -> (
        &'static dma2::RegisterBlock,
        &'static spi1::RegisterBlock,
        usize,
        usize,
    ) {
        match self {
            Self::Encoders => (dma2(), spi1(), ENC_RX, ENC_TX),
            Self::Adc => (dma1(), spi2(), ADC_RX, ADC_TX),
        }
    }

    /// After the RX stream's interrupt: whether the frame failed (a
    /// stream's transfer or direct-mode error, or an SPI overrun; the bus
    /// is then stopped), or `None` if the RX stream has not completed (an
    /// interrupt an abort's stopped stream left pending).
    fn ended(self) -> Option<bool> {
        let (dma, spi, rx, tx) = self.parts();
        let (rx_flags, tx_flags) = (flags(dma, rx), flags(dma, tx));
        let failed =
            (rx_flags | tx_flags) & (TEIF | DMEIF) != 0 || spi.sr().read().ovr().bit_is_set();
        if !failed && rx_flags & TCIF == 0 {
            return None;
        }
        if failed {
            self.stop();
        }
        clear_flags(dma, rx);
        clear_flags(dma, tx);
        fence(Ordering::SeqCst);
        Some(failed)
    }

    /// Stops a transfer that may be under way (RM0090 §28.3.8, disabling
    /// with DMA): the TX stream, then the last byte out (TXE, not BSY),
    /// then the RX stream; the bytes left are read out (DR, then SR, which
    /// also clears an overrun). Every wait is bounded.
    fn stop(self) {
        let (dma, spi, rx, tx) = self.parts();
        disable(dma, tx);
        for _ in 0..SPI_POLLS {
            let sr = spi.sr().read();
            if sr.txe().bit_is_set() && sr.bsy().bit_is_clear() {
                break;
            }
        }
        disable(dma, rx);
        let _ = spi.dr().read();
        let _ = spi.sr().read();
        clear_flags(dma, rx);
        clear_flags(dma, tx);
    }

    /// Before a frame's chip select goes low: a byte left in the receiver
    /// (or an overrun) is read out, so the frame's RX stream takes only
    /// its own bytes.
    fn drain(self) {
        let (_, spi, _, _) = self.parts();
        let sr = spi.sr().read();
        if sr.rxne().bit_is_set() || sr.ovr().bit_is_set() {
            let _ = spi.dr().read();
            let _ = spi.sr().read();
        }
    }

    /// Re-arms both streams for one frame of `len` bytes after its chip
    /// select went low, `setup` cycles before the first clock: the RX
    /// stream first, so no received byte finds it off (RM0090 §28.3.9).
    fn arm(self, len: u16, setup: u32) {
        let (dma, _, rx, tx) = self.parts();
        // RM0090 §10.3.17: a stream's flags are cleared before it is
        // enabled.
        clear_flags(dma, rx);
        clear_flags(dma, tx);
        dma.st(rx).ndtr().write(|w| w.ndt().set(len));
        dma.st(tx).ndtr().write(|w| w.ndt().set(len));
        fence(Ordering::SeqCst);
        cortex_m::asm::delay(setup);
        dma.st(rx).cr().modify(|_, w| w.en().enabled());
        dma.st(tx).cr().modify(|_, w| w.en().enabled());
    }
}

/// Disables a stream and waits (bounded) for its EN bit to clear, once the
/// transfer under way ends (RM0090 §10.3.17).
fn disable(dma: &dma2::RegisterBlock, stream: usize) {
    dma.st(stream).cr().modify(|_, w| w.en().disabled());
    for _ in 0..SPI_POLLS {
        if dma.st(stream).cr().read().en().is_disabled() {
            break;
        }
    }
}

/// `stream`'s six flag bits (LISR for streams 0–3, HISR for 4–7).
fn flags(dma: &dma2::RegisterBlock, stream: usize) -> u32 {
    let isr = if stream < 4 {
        dma.lisr().read().bits()
    } else {
        dma.hisr().read().bits()
    };
    (isr >> SHIFTS.get(stream % 4).copied().unwrap_or(0)) & 0x3D
}

/// Where each stream's flags start in LISR/LIFCR (streams 0–3) and
/// HISR/HIFCR (4–7), RM0090 §10.5.1–4.
const SHIFTS: [u32; 4] = [0, 6, 16, 22];

/// Clears every flag of `stream` (transfer complete, half, error, direct
/// mode error, FIFO error): six bits a stream, at 0, 6, 16 and 22 in
/// LIFCR (streams 0–3) and HIFCR (4–7), RM0090 §10.5.3–4. An interrupt
/// left with its flag up would come back at once.
fn clear_flags(dma: &dma2::RegisterBlock, stream: usize) {
    let bits = 0x3D << SHIFTS.get(stream % 4).copied().unwrap_or(0);
    // SAFETY: write-1-to-clear bits of this stream only; the other bits
    // written 0 do nothing.
    if stream < 4 {
        dma.lifcr().write(|w| unsafe { w.bits(bits) });
    } else {
        dma.hifcr().write(|w| unsafe { w.bits(bits) });
    }
}
