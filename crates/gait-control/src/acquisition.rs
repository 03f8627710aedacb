//! One tick's sensor frames, read before the tick decodes them.
//!
//! An *acquisition* reads every encoder's angle frame and the ADC's
//! conversions into [`Frames`]; the tick's *sense* stage decodes,
//! calibrates and checks them. Where the core drives the buses (the host,
//! the simulator), the acquisition is [`acquire`], through the drivers, at
//! the start of [`Controller::tick`], and on the motor board for a tick
//! that finds no acquisition of its own. Otherwise the board's SPI buses'
//! DMA reads the frames shortly before the tick
//! ([`Controller::tick_acquired`]), so the tick neither polls a bus nor
//! waits for one. Both read the same frames (each chip sees ANGLE then
//! NOP; the ADC converts in [`plan`]'s order), and one decode serves both.
//!
//! [`Controller::tick`]: crate::controller::Controller::tick
//! [`Controller::tick_acquired`]: crate::controller::Controller::tick_acquired

mod round;

use core::cell::Cell;

use critical_section::Mutex;
use embedded_hal::spi::SpiDevice;

use crate::controller::Hardware;
use crate::drivers::as5048a::{self, FrameError};
use crate::drivers::mcp3208::{self, Channel};
use crate::layout::{ENCODERS, FORCES};
use crate::posture::JOINTS;

pub use round::{AdcRound, EncoderRound};

/// The frames of one acquisition, as read: each `None` is a read the bus
/// failed (the tick counts it as a bus error).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frames {
    /// Each encoder's reply to its angle read (the NOP frame after the
    /// ANGLE command), encoder order: undecoded, parity and EF included.
    pub encoders: [Option<u16>; ENCODERS],
    /// The force sensors' counts (left foot, right foot, left crutch, right
    /// crutch).
    pub forces: [Option<u16>; FORCES],
    /// The counts of one drive's current monitor ([`Self::drive_joint`]).
    pub drive_current: Option<u16>,
    /// The joint whose drive monitor was read: one a tick, in turn.
    pub drive_joint: u8,
}

impl Frames {
    /// An acquisition that read nothing: every read a bus error.
    pub const MISSING: Self = Self {
        encoders: [None; ENCODERS],
        forces: [None; FORCES],
        drive_current: None,
        drive_joint: 0,
    };
}

/// What an acquisition converts, in order: the four force sensors' ADC
/// channels, then the drive monitor's of `drive_joint` (none for a joint
/// the board has not). The encoders are read in encoder order, each with
/// [`ENCODER_COMMANDS`].
#[must_use]
pub fn plan<ENC, ADC, PWM, DIR, EN, IN, OUT>(
    hw: &Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
    drive_joint: u8,
) -> ([Channel; FORCES], Option<Channel>) {
    let ch = hw.force_channels;
    (
        [ch.left_foot, ch.right_foot, ch.left_crutch, ch.right_crutch],
        hw.drive_current_channels
            .get(usize::from(drive_joint))
            .copied(),
    )
}

/// An encoder's angle read: the ANGLE command, then the NOP whose reply is
/// the answer, each frame in its own chip-select window.
pub const ENCODER_COMMANDS: [u16; 2] = [
    as5048a::encode_command(as5048a::reg::ANGLE, true),
    as5048a::encode_command(as5048a::reg::NOP, true),
];

/// After an angle reply that raised the error flag (good parity, EF set),
/// the acquisition reads the error register, which clears it: these two
/// frames, on that encoder, before the next encoder.
pub const CLEAR_ERROR_COMMANDS: [u16; 2] = [
    as5048a::encode_command(as5048a::reg::CLEAR_ERROR_FLAG, true),
    as5048a::encode_command(as5048a::reg::NOP, true),
];

/// Whether an angle reply asks for [`CLEAR_ERROR_COMMANDS`].
#[must_use]
pub const fn needs_clear(reply: u16) -> bool {
    matches!(as5048a::decode_response(reply), Err(FrameError::ErrorFlag))
}

/// The drive monitor read after `tick`'s: the next in turn.
#[must_use]
pub const fn drive_joint_of(tick: u32) -> u8 {
    (tick % JOINTS as u32) as u8
}

/// One acquisition through the drivers (the host's tick, and the board's
/// tick that finds no acquisition of its own):
/// every encoder (clearing an error flag at once), then the ADC's
/// conversions in [`plan`]'s order. Fixed work: 12 encoder frames (two
/// more per flag cleared) and 5 conversions.
pub fn acquire<ENC, ADC, PWM, DIR, EN, IN, OUT>(
    hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
    drive_joint: u8,
) -> Frames
where
    ENC: SpiDevice<u8>,
    ADC: SpiDevice<u8>,
{
    let mut frames = Frames::MISSING;
    for (frame, enc) in frames.encoders.iter_mut().zip(hw.encoders.iter_mut()) {
        *frame = enc.read_angle_frame().ok();
    }
    frames.drive_joint = drive_joint;
    let (forces, drive) = plan(hw, drive_joint);
    frames.forces = forces.map(|ch| read(&mut hw.adc, ch));
    frames.drive_current = drive.and_then(|ch| read(&mut hw.adc, ch));
    frames
}

fn read<ADC: SpiDevice<u8>>(adc: &mut mcp3208::Mcp3208<ADC>, channel: Channel) -> Option<u16> {
    adc.read_raw(channel).ok()
}

/// The same acquisition as [`acquire`], frame by frame in the order the
/// motor board's DMA sends them ([`EncoderRound`], [`AdcRound`]): what
/// the QEMU rig does before each tick in the board's place.
pub fn acquire_in_rounds<ENC, ADC, PWM, DIR, EN, IN, OUT>(
    hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
    drive_joint: u8,
) -> Frames
where
    ENC: SpiDevice<u8>,
    ADC: SpiDevice<u8>,
{
    let mut encoders = EncoderRound::new();
    while let Some((chip, command)) = encoders.next() {
        let reply = hw
            .encoders
            .get_mut(chip)
            .and_then(|e| e.frame(command).ok());
        encoders.answer(reply);
    }
    let (forces, drive) = plan(hw, drive_joint);
    let mut adc = AdcRound::new(forces, drive, drive_joint);
    while let Some(request) = adc.next() {
        adc.answer(hw.adc.exchange(request).ok());
    }
    Frames::of(&encoders, &adc)
}

/// Where a finished acquisition waits for its tick, stamped with the
/// period it was started in (the board counts periods by its timer's
/// updates): the tick of the next period takes it, once. A tick takes
/// nothing of another period's, so an acquisition that finished late is
/// never decoded as a later tick's sensors.
pub struct Handoff {
    ready: Mutex<Cell<Option<(u32, Frames)>>>,
}

impl Default for Handoff {
    fn default() -> Self {
        Self::new()
    }
}

impl Handoff {
    /// Nothing waiting.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            ready: Mutex::new(Cell::new(None)),
        }
    }

    /// Leaves `frames`, from the acquisition started in `period`, replacing
    /// any not taken.
    pub fn publish(&self, period: u32, frames: Frames) {
        critical_section::with(|cs| self.ready.borrow(cs).set(Some((period, frames))));
    }

    /// The frames of the acquisition started in `period`, once; `None` if
    /// none waits or what waits is another period's (dropped).
    pub fn take(&self, period: u32) -> Option<Frames> {
        critical_section::with(|cs| self.ready.borrow(cs).take())
            .filter(|(p, _)| *p == period)
            .map(|(_, frames)| frames)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(drive_joint: u8) -> Frames {
        Frames {
            drive_joint,
            ..Frames::MISSING
        }
    }

    #[test]
    fn a_tick_takes_its_own_acquisition_once() {
        let h = Handoff::new();
        h.publish(7, frames(3));
        assert_eq!(h.take(7).map(|f| f.drive_joint), Some(3));
        assert_eq!(h.take(7), None);
    }

    #[test]
    fn another_periods_acquisition_is_dropped_not_taken() {
        let h = Handoff::new();
        // Finished after its tick had run: the next tick must not take it.
        h.publish(7, frames(1));
        assert_eq!(h.take(8), None);
        assert_eq!(h.take(7), None, "dropped, not kept");
        // The newest replaces one not taken.
        h.publish(8, frames(1));
        h.publish(9, frames(2));
        assert_eq!(h.take(9).map(|f| f.drive_joint), Some(2));
    }
}
