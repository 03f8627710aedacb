//! In-memory peripherals for running the real controller where there is no
//! hardware (QEMU's `mps2-an386`): fakes of the AS5048A and MCP3208 that
//! speak their wire formats, and PWM and GPIO fakes that accept writes.
//!
//! The fakes are written from the datasheets, not from gait-control's
//! drivers, so the benchmark also checks that the acquisition's rounds
//! (the DMA's frame order) and the drivers speak the parts' protocols. No heap, no `unsafe`, fixed work per call.
//!
//! The fakes read what a [`PANEL`] of atomics holds, set between ticks:
//! [`standing`] builds a rig of a pilot standing still on both feet with
//! both crutches loaded, e-stop released and no button pressed (the
//! controller must run it without any fault); [`replay`] sets the panel to
//! a tick recorded in the simulator.

use core::convert::Infallible;
use core::sync::atomic::{AtomicBool, AtomicU16, Ordering};

use embedded_hal::digital::{self, InputPin, OutputPin};
use embedded_hal::pwm::{self, SetDutyCycle};
use embedded_hal::spi::{self, Operation, SpiDevice};
use gait_control::acquisition::{self, Frames};
use gait_control::controller::Controller;
use gait_control::drivers::as5048a::{Calibration, Direction};
use gait_control::drivers::buttons::ActiveLevel;

use exogait_device::{BoardIo, DeviceConfig};

/// What the rig's sensors and inputs read, set from outside between ticks
/// (the standing rig's fixed values, or a recording's tick after tick):
/// the fakes, once owned by the drivers, read it at every transfer.
#[derive(Debug)]
pub struct Panel {
    /// Each encoder's angle frame: its counts (joint order, then the
    /// ankles) with the parity bit the part sets. The part works the frame
    /// out in its own logic, not the MCU's: it is worked out here, when
    /// the panel is set between ticks, so the tick's instruction count
    /// holds only the MCU's work.
    encoders: [AtomicU16; 6],
    /// Each ADC input's counts, CH0..CH7.
    adc: [AtomicU16; 8],
    /// MODE, GO, e-stop input levels (high or not).
    levels: [AtomicBool; 3],
}

/// The panel the rig's fakes read.
pub static PANEL: Panel = Panel {
    encoders: [const { AtomicU16::new(0) }; 6],
    adc: [const { AtomicU16::new(0) }; 8],
    levels: [const { AtomicBool::new(false) }; 3],
};

/// The panel's input lines.
#[derive(Clone, Copy, Debug)]
pub enum Line {
    /// The MODE button.
    Mode = 0,
    /// The GO button.
    Go = 1,
    /// The emergency stop.
    EStop = 2,
}

impl Panel {
    /// Sets encoder `channel`'s counts (low 14 bits).
    pub fn set_encoder(&self, channel: usize, counts: u16) {
        if let Some(c) = self.encoders.get(channel) {
            c.store(with_even_parity(counts & 0x3FFF), Ordering::Relaxed);
        }
    }

    /// Sets ADC input `channel`'s counts (low 12 bits).
    pub fn set_adc(&self, channel: usize, counts: u16) {
        if let Some(c) = self.adc.get(channel) {
            c.store(counts & 0x0FFF, Ordering::Relaxed);
        }
    }

    /// Sets an input line's level.
    pub fn set_level(&self, line: Line, high: bool) {
        if let Some(l) = self.levels.get(line as usize) {
            l.store(high, Ordering::Relaxed);
        }
    }

    /// Encoder `channel`'s angle frame, parity included.
    fn encoder_frame(&self, channel: usize) -> u16 {
        self.encoders
            .get(channel)
            .map_or(0, |c| c.load(Ordering::Relaxed))
    }

    fn adc(&self, channel: usize) -> u16 {
        self.adc
            .get(channel)
            .map_or(0, |c| c.load(Ordering::Relaxed))
    }

    fn level(&self, line: Line) -> bool {
        self.levels
            .get(line as usize)
            .is_some_and(|l| l.load(Ordering::Relaxed))
    }
}

/// AS5048A register addresses (datasheet, "Register Description").
mod as5048a_reg {
    pub const NOP: u16 = 0x0000;
    pub const CLEAR_ERROR_FLAG: u16 = 0x0001;
    pub const DIAGNOSTICS_AGC: u16 = 0x3FFD;
    pub const MAGNITUDE: u16 = 0x3FFE;
    pub const ANGLE: u16 = 0x3FFF;
}

/// Sets bit 15 so the 16-bit frame has even parity (datasheet: "PAR").
const fn with_even_parity(frame: u16) -> u16 {
    let f = frame & 0x7FFF;
    if f.count_ones() % 2 == 1 {
        f | 0x8000
    } else {
        f
    }
}

/// An AS5048A at a fixed angle. It answers each 16-bit frame with the
/// answer to the *previous* command, as the part does (the command is
/// executed on CSn's rising edge): one `transaction` is one CSn window.
#[derive(Debug)]
pub struct FakeAs5048a {
    /// Its counts on the [`PANEL`].
    channel: usize,
    /// Reply of the next frame (the answer to the last command).
    pending: u16,
    /// Error register: bit 0 framing, bit 2 parity.
    errors: u16,
    /// Frames seen (for checking that the driver talks to the part).
    pub frames: u32,
}

impl FakeAs5048a {
    /// The part whose counts are the [`PANEL`]'s encoder `channel`.
    #[must_use]
    pub const fn on_panel(channel: usize) -> Self {
        Self {
            channel,
            pending: 0,
            errors: 0,
            frames: 0,
        }
    }

    /// One 16-bit frame: returns the reply, latches the next one.
    fn frame(&mut self, command: u16) -> u16 {
        self.frames = self.frames.wrapping_add(1);
        let reply = self.pending;
        let addr = command & 0x3FFF;
        let read = command & 0x4000 != 0;
        self.pending = if command.count_ones() % 2 == 1 {
            // Command parity error: flag it, answer with EF set.
            self.errors |= 0b100;
            with_even_parity(0x4000)
        } else if !read {
            // Writes are not modelled: answer the old register contents.
            with_even_parity(0)
        } else {
            match addr {
                as5048a_reg::NOP => with_even_parity(0),
                as5048a_reg::CLEAR_ERROR_FLAG => {
                    let e = self.errors;
                    self.errors = 0;
                    with_even_parity(e)
                }
                // OCF set, AGC mid-range, no CORDIC overflow, field in range.
                as5048a_reg::DIAGNOSTICS_AGC => with_even_parity(0x0100 | 0x0080),
                as5048a_reg::MAGNITUDE => with_even_parity(0x1000),
                as5048a_reg::ANGLE => PANEL.encoder_frame(self.channel),
                _ => {
                    self.errors |= 0b010;
                    with_even_parity(0x4000)
                }
            }
        };
        reply
    }

    /// Any transfer that is not one 16-bit frame is a framing error: the
    /// part shifts out garbage (all ones here) and flags it.
    fn bad_frame(&mut self, buf: &mut [u8]) {
        self.errors |= 0b001;
        buf.iter_mut().for_each(|b| *b = 0xFF);
        self.pending = with_even_parity(0x4000);
    }
}

impl spi::ErrorType for FakeAs5048a {
    type Error = Infallible;
}

impl SpiDevice<u8> for FakeAs5048a {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), Infallible> {
        for op in operations.iter_mut() {
            match op {
                Operation::TransferInPlace(buf) => match buf {
                    [hi, lo] => {
                        let reply = self.frame(u16::from_be_bytes([*hi, *lo]));
                        [*hi, *lo] = reply.to_be_bytes();
                    }
                    other => self.bad_frame(other),
                },
                Operation::Transfer(read, write) => match (&mut **read, &**write) {
                    ([rh, rl], [wh, wl]) => {
                        let reply = self.frame(u16::from_be_bytes([*wh, *wl]));
                        [*rh, *rl] = reply.to_be_bytes();
                    }
                    (other, _) => self.bad_frame(other),
                },
                Operation::Read(buf) => self.bad_frame(buf),
                Operation::Write(_) => self.errors |= 0b001,
                Operation::DelayNs(_) => {}
            }
        }
        Ok(())
    }
}

/// An MCP3208 whose eight inputs read the [`PANEL`]'s ADC counts.
#[derive(Debug, Default)]
pub struct FakeMcp3208 {
    /// Conversions answered.
    pub conversions: u32,
}

impl FakeMcp3208 {
    /// One 3-byte conversion window (datasheet section 6.1): byte 0 holds
    /// the start bit (bit 2), SGL/DIFF (bit 1) and D2 (bit 0), byte 1 holds
    /// D1 D0 in bits 7..6. The reply: a null bit (bit 4 of byte 1, zero),
    /// B11..B8 in bits 3..0 of byte 1, B7..B0 in byte 2.
    fn convert(&mut self, buf: &mut [u8]) {
        let [b0, b1, b2] = buf else {
            buf.iter_mut().for_each(|b| *b = 0);
            return;
        };
        let started = *b0 & 0b100 != 0;
        let single = *b0 & 0b010 != 0;
        let channel = usize::from(((*b0 & 1) << 2) | (*b1 >> 6));
        let counts = match (started, single) {
            (true, true) => PANEL.adc(channel),
            // Differential or no start bit: not modelled, reads 0.
            _ => 0,
        };
        self.conversions = self.conversions.wrapping_add(1);
        let [hi, lo] = counts.to_be_bytes();
        *b0 = 0xFF; // MISO is high-impedance while the request goes out.
        *b1 = hi & 0x0F;
        *b2 = lo;
    }
}

impl spi::ErrorType for FakeMcp3208 {
    type Error = Infallible;
}

impl SpiDevice<u8> for FakeMcp3208 {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), Infallible> {
        for op in operations.iter_mut() {
            match op {
                Operation::TransferInPlace(buf) => self.convert(buf),
                Operation::Transfer(read, write) => {
                    for (r, w) in read.iter_mut().zip(write.iter()) {
                        *r = *w;
                    }
                    self.convert(read);
                }
                Operation::Read(buf) => buf.iter_mut().for_each(|b| *b = 0),
                Operation::Write(_) | Operation::DelayNs(_) => {}
            }
        }
        Ok(())
    }
}

/// A PWM channel that remembers its duty. `max_duty` 8,400: TIM1 at
/// 20 kHz from a 168 MHz timer clock, as on the motor board.
#[derive(Debug)]
pub struct FakePwm {
    /// The last duty written.
    pub duty: u16,
}

/// The motor board's TIM1 period at 20 kHz (168 MHz / 20 kHz).
pub const PWM_MAX_DUTY: u16 = 8_400;

impl pwm::ErrorType for FakePwm {
    type Error = Infallible;
}

impl SetDutyCycle for FakePwm {
    fn max_duty_cycle(&self) -> u16 {
        PWM_MAX_DUTY
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        self.duty = duty.min(PWM_MAX_DUTY);
        Ok(())
    }
}

/// An output pin that remembers its level.
#[derive(Debug)]
pub struct FakeOutput {
    /// Level last written.
    pub high: bool,
}

impl digital::ErrorType for FakeOutput {
    type Error = Infallible;
}

impl OutputPin for FakeOutput {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.high = false;
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Infallible> {
        self.high = true;
        Ok(())
    }
}

/// An input pin reading one of the [`PANEL`]'s lines.
#[derive(Debug)]
pub struct FakeInput {
    /// The line it reads.
    pub line: Line,
}

impl digital::ErrorType for FakeInput {
    type Error = Infallible;
}

impl InputPin for FakeInput {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(PANEL.level(self.line))
    }

    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(!PANEL.level(self.line))
    }
}

/// The rig's peripherals, typed as [`crate::board_config::hardware`] takes them.
pub type RigIo =
    BoardIo<FakeAs5048a, FakeMcp3208, FakePwm, FakeOutput, FakeOutput, FakeInput, FakeOutput>;

/// The controller's drivers over the rig's peripherals, as
/// [`crate::board_config::hardware`] builds them from [`RigIo`].
pub type RigHardware = gait_control::controller::Hardware<
    FakeAs5048a,
    FakeMcp3208,
    FakePwm,
    FakeOutput,
    FakeOutput,
    FakeInput,
    FakeOutput,
>;

/// Standing posture of the rig, rad: hips and knees slightly flexed (joint
/// order), ankles neutral (left, right).
pub const STANDING_JOINTS_RAD: [f32; 4] = [0.05, 0.05, 0.05, 0.05];
/// Ankle angles of the standing rig, rad (left, right).
pub const STANDING_ANKLES_RAD: [f32; 2] = [0.0, 0.0];

/// Forces of the standing rig, N: 367 N on each foot and 82 N on each
/// crutch, ≈ 900 N in all (93 kg).
pub const STANDING_FORCES_N: [f32; 4] = [367.0, 367.0, 82.0, 82.0];

/// ADC counts of the standing rig: [`STANDING_FORCES_N`] through the
/// device's load cells; the drives' current monitors at mid-range (0 A).
#[must_use]
pub fn standing_adc_counts(device: &DeviceConfig) -> [u16; 8] {
    let [lf, rf, lc, rc] = STANDING_FORCES_N;
    let foot = |n: f32| (device.foot_sensor.counts(n) + 0.5) as u16;
    let crutch = |n: f32| (device.crutch_sensor.counts(n) + 0.5) as u16;
    [
        foot(lf),
        foot(rf),
        crutch(lc),
        crutch(rc),
        2_048,
        2_048,
        2_048,
        2_048,
    ]
}

/// The raw counts of `angle_rad` under `cal`.
#[must_use]
pub fn counts_at(cal: Calibration, angle_rad: f32) -> u16 {
    let counts_per_rad = 16_384.0 / (2.0 * core::f32::consts::PI);
    // |angle| < π, so the rounded count fits an i16 well.
    let counts = libm::roundf(angle_rad * counts_per_rad) as i16;
    let zero = cal.zero_offset_counts as i16;
    let raw = match cal.direction {
        Direction::Positive => zero.wrapping_add(counts),
        Direction::Negative => zero.wrapping_sub(counts),
    };
    raw as u16
}

/// Sets the [`PANEL`] to a pilot standing still on both feet, both
/// crutches loaded, e-stop released, no button pressed, with the device's
/// calibrations.
pub fn stand(device: &DeviceConfig) {
    let angles = [
        STANDING_JOINTS_RAD.as_slice(),
        STANDING_ANKLES_RAD.as_slice(),
    ];
    for (channel, (cal, &angle)) in device
        .encoders
        .iter()
        .zip(angles.into_iter().flatten())
        .enumerate()
    {
        PANEL.set_encoder(channel, counts_at(*cal, angle));
    }
    for (channel, counts) in standing_adc_counts(device).into_iter().enumerate() {
        PANEL.set_adc(channel, counts);
    }
    let button_active_high = matches!(device.buttons.active, ActiveLevel::High);
    PANEL.set_level(Line::Mode, !button_active_high);
    PANEL.set_level(Line::Go, !button_active_high);
    PANEL.set_level(Line::EStop, !device.e_stop_active_high);
}

/// Sets the [`PANEL`] to the device on its calibration jig: every joint at
/// its zero pose, nothing on the feet and crutches, the drives' monitors
/// at 0 A (what the calibration procedure records).
pub fn on_jig(device: &DeviceConfig) {
    for (channel, cal) in device.encoders.iter().enumerate() {
        PANEL.set_encoder(channel, counts_at(*cal, 0.0));
    }
    let foot = (device.foot_sensor.counts(0.0) + 0.5) as u16;
    let crutch = (device.crutch_sensor.counts(0.0) + 0.5) as u16;
    for (channel, counts) in [foot, foot, crutch, crutch, 2_048, 2_048, 2_048, 2_048]
        .into_iter()
        .enumerate()
    {
        PANEL.set_adc(channel, counts);
    }
}

/// Sets the [`PANEL`] to one recorded tick: the counts as recorded, each
/// input at the level that means what was recorded under the device's
/// polarities.
pub fn replay(device: &DeviceConfig, t: &exogait_device::tick_record::TickRecord) {
    for (channel, &counts) in t.encoder_counts.iter().enumerate() {
        PANEL.set_encoder(channel, counts);
    }
    for (channel, &counts) in t.adc_counts.iter().enumerate() {
        PANEL.set_adc(channel, counts);
    }
    let button_active_high = matches!(device.buttons.active, ActiveLevel::High);
    PANEL.set_level(Line::Mode, t.mode_pressed == button_active_high);
    PANEL.set_level(Line::Go, t.go_pressed == button_active_high);
    PANEL.set_level(Line::EStop, t.e_stop_pressed == device.e_stop_active_high);
}

/// The rig's peripherals, all reading the [`PANEL`] (set it with [`stand`]
/// or [`replay`]).
#[must_use]
pub fn peripherals() -> RigIo {
    BoardIo {
        encoders: [0, 1, 2, 3, 4, 5].map(FakeAs5048a::on_panel),
        adc: FakeMcp3208::default(),
        pwm: [0; 4].map(|duty| FakePwm { duty }),
        dir: [0; 4].map(|_| FakeOutput { high: false }),
        // Enables start high so the boot-time disable is visible.
        enable: [0; 4].map(|_| FakeOutput { high: true }),
        mode: FakeInput { line: Line::Mode },
        go: FakeInput { line: Line::Go },
        e_stop: FakeInput { line: Line::EStop },
        gait_led: FakeOutput { high: false },
        fault_led: FakeOutput { high: false },
        buzzer: FakeOutput { high: false },
    }
}

/// The acquisition before `controller`'s next tick, frame by frame in the
/// motor board's DMA order ([`acquisition::acquire_in_rounds`]) through
/// the rig's parts: what the board's DMA reads before its tick, so the
/// tick's count holds none of the buses' work.
pub fn acquire(hw: &mut RigHardware, controller: &Controller<'_>) -> Frames {
    acquisition::acquire_in_rounds(hw, controller.next_drive_joint())
}

/// A pilot standing still ([`stand`]) and the rig's peripherals.
#[must_use]
pub fn standing(device: &DeviceConfig) -> RigIo {
    stand(device);
    peripherals()
}
