//! An acquisition one frame at a time, for a bus engine that sends each
//! frame on its own and is told the reply (the motor board's DMA, whose
//! transfer-complete interrupt asks for the next frame). The frames and
//! their order are fixed here, so the board's interrupt only moves bytes.
//!
//! The encoders' round sends every ANGLE command, then every NOP: two
//! frames in a row are on one chip only in an error flag's clear, so each
//! chip's CSn stays high for five frames between its two, well over the
//! part's 350 ns. Each chip
//! still sees ANGLE then NOP, so its NOP reply is the answer to its ANGLE
//! command, as in [`super::acquire`]; a reply with the error flag is
//! followed at once by that chip's [`CLEAR_ERROR_COMMANDS`], as the
//! drivers clear it.

use super::{CLEAR_ERROR_COMMANDS, ENCODER_COMMANDS, Frames, needs_clear};
use crate::drivers::mcp3208::{self, Channel};
use crate::layout::{ENCODERS, FORCES};

/// The encoders' frames of one acquisition: 12, two more for each reply
/// that raised the error flag (24 at most).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncoderRound {
    /// Frames of the 12 answered so far.
    sent: u8,
    /// A clear under way: its chip, and which of its two frames is next.
    clearing: Option<(u8, u8)>,
    /// Each chip's angle reply.
    replies: [Option<u16>; ENCODERS],
    /// Chips whose ANGLE command failed on the bus: their reply is a bus
    /// error, whatever their NOP brings.
    failed: [bool; ENCODERS],
}

impl Default for EncoderRound {
    fn default() -> Self {
        Self::new()
    }
}

impl EncoderRound {
    /// A round with nothing sent.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            sent: 0,
            clearing: None,
            replies: [None; ENCODERS],
            failed: [false; ENCODERS],
        }
    }

    /// The next frame, `(encoder, command)`; `None` when the round is done.
    #[must_use]
    pub fn next(&self) -> Option<(usize, u16)> {
        if let Some((chip, k)) = self.clearing {
            return Some((
                usize::from(chip),
                *CLEAR_ERROR_COMMANDS.get(usize::from(k))?,
            ));
        }
        let s = usize::from(self.sent);
        let (which, chip) = (s / ENCODERS, s % ENCODERS);
        Some((chip, *ENCODER_COMMANDS.get(which)?))
    }

    /// The reply to the frame [`Self::next`] named (`None`: the bus
    /// failed).
    pub fn answer(&mut self, reply: Option<u16>) {
        if let Some((chip, k)) = self.clearing {
            // A failed clear is a bus error, and ends the clear.
            let i = usize::from(chip);
            if reply.is_none()
                && let Some(r) = self.replies.get_mut(i)
            {
                *r = None;
            }
            self.clearing = (k == 0 && reply.is_some()).then_some((chip, 1));
            return;
        }
        let s = usize::from(self.sent);
        if s >= 2 * ENCODERS {
            return;
        }
        self.sent += 1;
        let chip = s % ENCODERS;
        if s < ENCODERS {
            if let Some(f) = self.failed.get_mut(chip) {
                *f = reply.is_none();
            }
            return;
        }
        let failed = self.failed.get(chip).copied().unwrap_or(true);
        let reply = reply.filter(|_| !failed);
        if let Some(r) = self.replies.get_mut(chip) {
            *r = reply;
        }
        if reply.is_some_and(needs_clear) {
            self.clearing = Some((chip as u8, 0));
        }
    }

    /// Each encoder's angle reply (encoder order).
    #[must_use]
    pub const fn replies(&self) -> [Option<u16>; ENCODERS] {
        self.replies
    }
}

/// The MCP3208's null bit in a reply's second byte (datasheet §6.1).
const NULL_BIT: u8 = 0x10;

/// The ADC's conversions of one acquisition: the four force sensors, then
/// one drive monitor ([`super::plan`]'s order).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AdcRound {
    channels: [Option<Channel>; FORCES + 1],
    sent: u8,
    counts: [Option<u16>; FORCES + 1],
    drive_joint: u8,
}

impl AdcRound {
    /// A round over the force sensors' `forces` channels and the
    /// `drive_joint`'s monitor on `drive` (none: not read, a bus error).
    #[must_use]
    pub const fn new(forces: [Channel; FORCES], drive: Option<Channel>, drive_joint: u8) -> Self {
        let [a, b, c, d] = forces;
        Self {
            channels: [Some(a), Some(b), Some(c), Some(d), drive],
            sent: 0,
            counts: [None; FORCES + 1],
            drive_joint,
        }
    }

    /// The next conversion's request; `None` when the round is done.
    #[must_use]
    pub fn next(&self) -> Option<[u8; 3]> {
        let mut k = usize::from(self.sent);
        // A monitor the board has not is skipped (the channels before it
        // are always there).
        while let Some(None) = self.channels.get(k) {
            k += 1;
        }
        Some(mcp3208::encode_request((*self.channels.get(k)?)?))
    }

    /// The reply to the request [`Self::next`] gave (`None`: the bus
    /// failed).
    pub fn answer(&mut self, reply: Option<[u8; 3]>) {
        let mut k = usize::from(self.sent);
        while let Some(None) = self.channels.get(k) {
            k += 1;
        }
        if let Some(c) = self.counts.get_mut(k) {
            // The null bit before B11 is driven low: set, the frame slipped
            // (a byte lost or left over), and its counts mean nothing.
            *c = reply
                .filter(|r| r[1] & NULL_BIT == 0)
                .map(mcp3208::decode_reply);
            self.sent = (k + 1) as u8;
        }
    }
}

impl Frames {
    /// The frames of two finished rounds.
    #[must_use]
    pub fn of(encoders: &EncoderRound, adc: &AdcRound) -> Self {
        let [f0, f1, f2, f3, drive] = adc.counts;
        Self {
            encoders: encoders.replies(),
            forces: [f0, f1, f2, f3],
            drive_current: drive,
            drive_joint: adc.drive_joint,
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::drivers::as5048a::{self, reg};

    /// An AS5048A as the datasheet has it: each frame's reply is the
    /// answer to the command before; ANGLE answers `angle` (with EF while
    /// the error flag is up); CLEAR_ERROR_FLAG answers the error register
    /// and lowers the flag.
    #[derive(Clone, Copy)]
    struct Part {
        angle: u16,
        flag: bool,
        pending: u16,
        commands: [u16; 4],
        seen: usize,
    }

    impl Part {
        fn new(angle: u16, flag: bool) -> Self {
            Self {
                angle,
                flag,
                pending: 0,
                commands: [0; 4],
                seen: 0,
            }
        }

        fn frame(&mut self, command: u16) -> u16 {
            if let Some(c) = self.commands.get_mut(self.seen) {
                *c = command;
            }
            self.seen += 1;
            let reply = self.pending;
            let ef = if self.flag { 0x4000 } else { 0 };
            self.pending = even(match command & 0x3FFF {
                reg::ANGLE => (self.angle & 0x3FFF) | ef,
                reg::CLEAR_ERROR_FLAG => {
                    self.flag = false;
                    0b100
                }
                _ => ef,
            });
            reply
        }
    }

    fn even(f: u16) -> u16 {
        if f.count_ones() % 2 == 1 {
            f | 0x8000
        } else {
            f
        }
    }

    /// Runs a round over `parts`; `fail` names a frame (by its index in
    /// the round) the bus loses.
    fn run(parts: &mut [Part; ENCODERS], fail: Option<usize>) -> (EncoderRound, Vec<usize>) {
        let mut round = EncoderRound::new();
        let mut chips = Vec::new();
        while let Some((chip, command)) = round.next() {
            let k = chips.len();
            chips.push(chip);
            let reply = parts[chip].frame(command);
            round.answer((fail != Some(k)).then_some(reply));
            assert!(chips.len() <= 24, "the round is bounded");
        }
        (round, chips)
    }

    #[test]
    fn healthy_round_reads_each_angle_and_never_repeats_a_chip() {
        let mut parts = core::array::from_fn(|i| Part::new(1_000 + 100 * i as u16, false));
        let (round, chips) = run(&mut parts, None);
        assert_eq!(chips.len(), 12);
        assert!(chips.windows(2).all(|w| w[0] != w[1]));
        for (i, r) in round.replies().iter().enumerate() {
            let frame = r.expect("read");
            assert_eq!(as5048a::decode_response(frame), Ok(1_000 + 100 * i as u16));
        }
        for p in &parts {
            assert_eq!(p.commands[..2], ENCODER_COMMANDS);
        }
    }

    #[test]
    fn an_error_flag_is_reported_and_cleared_on_its_chip_at_once() {
        let mut parts = core::array::from_fn(|_| Part::new(2_000, false));
        parts[2].flag = true;
        let (round, chips) = run(&mut parts, None);
        assert_eq!(chips.len(), 14);
        assert_eq!(&chips[8..11], &[2, 2, 2]);
        let reply = round.replies()[2].expect("read");
        assert_eq!(
            as5048a::decode_response(reply),
            Err(as5048a::FrameError::ErrorFlag)
        );
        assert!(!parts[2].flag, "the flag is cleared");
        assert_eq!(parts[2].commands[2..], CLEAR_ERROR_COMMANDS);
        assert!(round.replies()[3].is_some_and(|r| !needs_clear(r)));
    }

    #[test]
    fn a_lost_frame_is_a_bus_error_of_its_chip_only() {
        // Frame 1 is chip 1's ANGLE, frame 9 chip 3's NOP.
        for (fail, chip) in [(1, 1), (9, 3)] {
            let mut parts = core::array::from_fn(|_| Part::new(3_000, false));
            let (round, _) = run(&mut parts, Some(fail));
            for (i, r) in round.replies().iter().enumerate() {
                assert_eq!(r.is_none(), i == chip, "frame {fail}, encoder {i}");
            }
        }
    }

    #[test]
    fn adc_round_converts_the_plan_in_order_and_skips_a_missing_monitor() {
        let forces = [Channel::Ch0, Channel::Ch1, Channel::Ch2, Channel::Ch3];
        for (drive, n) in [(Some(Channel::Ch6), 5), (None, 4)] {
            let mut round = AdcRound::new(forces, drive, 2);
            let mut sent = Vec::new();
            while let Some(request) = round.next() {
                sent.push(request);
                let ch = ((request[0] & 1) << 2) | (request[1] >> 6);
                let counts = 100 * u16::from(ch) + 7;
                round.answer(Some([0xFF, (counts >> 8) as u8, counts as u8]));
                assert!(sent.len() <= 5);
            }
            assert_eq!(sent.len(), n);
            let frames = Frames::of(&EncoderRound::new(), &round);
            assert_eq!(frames.forces, [Some(7), Some(107), Some(207), Some(307)]);
            assert_eq!(frames.drive_current, drive.map(|_| 607));
            assert_eq!(frames.drive_joint, 2);
            assert_eq!(sent[0], mcp3208::encode_request(Channel::Ch0));
        }
    }

    #[test]
    fn a_slipped_conversion_is_a_bus_error() {
        let forces = [Channel::Ch0, Channel::Ch1, Channel::Ch2, Channel::Ch3];
        let mut round = AdcRound::new(forces, None, 0);
        round.answer(Some([0xFF, 0x10 | 0x01, 0x23]));
        round.answer(Some([0xFF, 0x01, 0x23]));
        let frames = Frames::of(&EncoderRound::new(), &round);
        assert_eq!(frames.forces[..2], [None, Some(0x123)]);
    }
}
