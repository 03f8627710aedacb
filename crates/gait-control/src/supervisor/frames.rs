//! Each encoder frame classified once a tick: the controller takes the
//! frames before it acts ([`Supervisor::take_encoder`]) and hands them to
//! the check ([`Supervisor::check_frames`]), which goes on from that
//! classification. Control and the check cannot disagree on a frame, and
//! no frame is classified twice. [`Supervisor::check`] takes the frames
//! itself.

use super::*;

/// Encoder frame of one tick as the supervisor classified it: whether
/// control may use it, and what the check goes on from. Twelve bytes: the
/// tick keeps six between its stages, and a form three times the size was
/// copied there with `memcpy`, some 900 instructions a tick in the QEMU
/// replay.
#[derive(Clone, Copy, Debug)]
pub struct EncoderFrame {
    /// Accepted: the angle (offset taken out); invalid: the reading.
    angle_rad: f32,
    /// Accepted: the last accepted frame's angle.
    previous_angle_rad: f32,
    /// Accepted with a predecessor: counts moved since it.
    delta_counts: i16,
    /// Accepted with a predecessor: ticks since it (at most the debounce
    /// window, 128).
    elapsed_ticks: u8,
    kind: Kind,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Rejected,
    /// Rejected as an invalid value (its reading is logged).
    Invalid,
    /// Accepted without a predecessor (a seed: no motion from it).
    Seed,
    /// Accepted after another frame.
    Moved,
    /// [`Kind::Moved`] or [`Kind::Seed`], but control does not use it (an
    /// ankle found stuck): `delta_counts` and `elapsed_ticks` are zero for
    /// a seed.
    SeedNotUsable,
    MovedNotUsable,
}

/// Counts moved since the last accepted frame, and ticks since it.
pub(super) type Motion = (i16, u32);

impl Default for EncoderFrame {
    fn default() -> Self {
        Self::NONE
    }
}

impl EncoderFrame {
    /// No frame: rejected, nothing to log.
    pub(crate) const NONE: Self = Self {
        angle_rad: f32::NAN,
        previous_angle_rad: f32::NAN,
        delta_counts: 0,
        elapsed_ticks: 0,
        kind: Kind::Rejected,
    };

    /// An accepted frame without a predecessor (no motion from it).
    pub(super) const fn seed(angle_rad: f32) -> Self {
        Self {
            angle_rad,
            previous_angle_rad: angle_rad,
            delta_counts: 0,
            elapsed_ticks: 0,
            kind: Kind::Seed,
        }
    }

    /// An accepted frame `delta_counts` from the last, `elapsed_ticks`
    /// after it.
    pub(super) fn moved(
        angle_rad: f32,
        previous_angle_rad: f32,
        delta_counts: i16,
        elapsed_ticks: u32,
    ) -> Self {
        Self {
            angle_rad,
            previous_angle_rad,
            delta_counts,
            elapsed_ticks: u8::try_from(elapsed_ticks).unwrap_or(u8::MAX),
            kind: Kind::Moved,
        }
    }

    /// A frame rejected as an invalid value, `value` read.
    pub(super) fn invalid_value(value: f32) -> Self {
        Self {
            angle_rad: value,
            kind: Kind::Invalid,
            ..Self::NONE
        }
    }

    /// The same frame, which control may not use.
    const fn not_usable(self) -> Self {
        let kind = match self.kind {
            Kind::Seed => Kind::SeedNotUsable,
            Kind::Moved => Kind::MovedNotUsable,
            k => k,
        };
        Self { kind, ..self }
    }

    /// Control may use the frame: accepted, and not an ankle's found stuck
    /// (0x0207) whose counts have not moved since.
    #[must_use]
    pub fn usable(&self) -> bool {
        matches!(self.kind, Kind::Seed | Kind::Moved)
    }

    /// An accepted frame's angle, its motion since the last accepted one
    /// (counts and ticks; none after a seed) and that one's angle.
    pub(super) fn accepted(&self) -> Option<(f32, Option<Motion>, f32)> {
        let delta = match self.kind {
            Kind::Rejected | Kind::Invalid => return None,
            Kind::Seed | Kind::SeedNotUsable => None,
            Kind::Moved | Kind::MovedNotUsable => {
                Some((self.delta_counts, u32::from(self.elapsed_ticks)))
            }
        };
        Some((self.angle_rad, delta, self.previous_angle_rad))
    }

    /// An invalid reading's value (for the log).
    pub(super) fn invalid(&self) -> Option<f32> {
        (self.kind == Kind::Invalid).then_some(self.angle_rad)
    }
}

impl<W> Supervisor<W> {
    /// Whether [`Supervisor::take_encoder`] would find `sense` usable as
    /// encoder `channel`'s frame of this tick (joints in joint order, then
    /// the ankles), asked before it: the same rules, nothing changed. A
    /// frame the supervisor drops (a jump) is not, nor are an ankle's found
    /// stuck (0x0207) until its counts move.
    pub fn accepts_encoder(&self, channel: usize, sense: &EncoderSense) -> bool {
        let cfg = &self.cfg;
        let (track, max_jump) = match channel.checked_sub(JOINTS) {
            None => (
                self.joints.get(channel).map(|j| &j.encoder),
                cfg.max_jump_counts_per_tick,
            ),
            Some(a) if self.ankle_stuck.get(a).copied().unwrap_or(true) => return false,
            Some(a) => (self.ankles.get(a), cfg.max_ankle_jump_counts_per_tick),
        };
        track.is_some_and(|t| {
            let sense = &t.seen(sense, self.encoder_offsets);
            matches!(
                t.classify(sense, cfg.encoder_debounce, max_jump),
                Class::Seed | Class::Good { .. }
            )
        })
    }

    /// The angle control takes from encoder `channel`'s accepted frame
    /// `angle_rad`: the reading without the offset of a persistent jump
    /// (0x0205), which the supervisor keeps until power-off (a reset does
    /// not move the encoder back). Needed only while
    /// [`Supervisor::encoder_offsets`].
    pub fn encoder_angle(&self, channel: usize, angle_rad: f32) -> f32 {
        let track = match channel.checked_sub(JOINTS) {
            None => self.joints.get(channel).map(|j| &j.encoder),
            Some(a) => self.ankles.get(a),
        };
        track.map_or(f32::NAN, |t| t.angle_without_offset(angle_rad))
    }

    /// Whether any encoder reads offset since a persistent jump (nearly
    /// never): only then are frames corrected, here and in control.
    pub const fn encoder_offsets(&self) -> bool {
        self.encoder_offsets
    }

    /// Classifies `sense` as encoder `channel`'s frame of this tick (joints
    /// in joint order, then the ankles), as [`Supervisor::accepts_encoder`]
    /// would, and moves its track on. Once a tick per channel, with the
    /// sense the check then gets; hand the frames to
    /// [`Supervisor::check_frames`].
    #[inline(always)]
    pub fn take_encoder(&mut self, channel: usize, sense: &EncoderSense) -> EncoderFrame {
        let cfg = &self.cfg;
        let offsets = self.encoder_offsets;
        let (track, max_jump, stuck) = match channel.checked_sub(JOINTS) {
            None => (
                self.joints.get_mut(channel).map(|j| &mut j.encoder),
                cfg.max_jump_counts_per_tick,
                false,
            ),
            Some(a) => (
                self.ankles.get_mut(a),
                cfg.max_ankle_jump_counts_per_tick,
                self.ankle_stuck.get(a).copied().unwrap_or(true),
            ),
        };
        let Some(track) = track else {
            return EncoderFrame::NONE;
        };
        let sense = &track.seen(sense, offsets);
        let frame = track.update(sense, cfg.encoder_debounce, max_jump);
        if stuck { frame.not_usable() } else { frame }
    }
}
