//! What the supervisor remembers of each channel between ticks: the
//! sliding windows of bad samples, the last accepted encoder frame, the
//! joints' filtered velocities and their tracking, frozen and saturation
//! counters.

use super::*;

/// Sliding window over the last ≤ 128 ticks: a ring of 128 bits (bit `i`
/// of the ring is bit `i % 32` of word `i / 32`), written at `head`, so a
/// push touches two bits instead of shifting all four words (10 windows a
/// tick: 35–50 instructions a tick fewer on the M4, `cargo xtask qemu`).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct SampleWindow {
    ring: [u32; 4],
    /// Where the next sample goes (0..128).
    head: u8,
    /// Bad samples among the last `window_ticks` pushed, kept as they come
    /// and go (a 128-bit popcount is some 60 instructions on the M4; this
    /// is a bit read and two adds).
    bad: u32,
}

/// The ring's length, samples.
const RING_BITS: u8 = 128;

impl SampleWindow {
    /// The sample at ring position `i` (0..128).
    fn bit(&self, i: u8) -> u32 {
        self.ring
            .get(usize::from(i / 32))
            .map_or(0, |w| (w >> (i % 32)) & 1)
    }

    /// Pushes this tick's sample; `window_ticks` (1..=128, the same on every
    /// push) is the window [`SampleWindow::count`] counts over.
    ///
    /// Each sample's bit is cleared as it leaves the window, so with no bad
    /// sample inside it the whole ring is clear and a good sample only moves
    /// the head: the healthy tick's ten windows cost a compare each
    /// (`cargo xtask profile`).
    pub(super) fn push(&mut self, bad: bool, window_ticks: u8) {
        if !bad && self.bad == 0 {
            self.head = (self.head + 1) % RING_BITS;
            return;
        }
        // The sample pushed `window_ticks` pushes ago leaves the window.
        let leaving = if window_ticks == 0 || window_ticks > RING_BITS {
            0
        } else {
            let at = self.head.wrapping_sub(window_ticks) % RING_BITS;
            let bit = self.bit(at);
            if let Some(w) = self.ring.get_mut(usize::from(at / 32)) {
                *w &= !(1u32 << (at % 32));
            }
            bit
        };
        if let Some(w) = self.ring.get_mut(usize::from(self.head / 32)) {
            let mask = 1u32 << (self.head % 32);
            *w = if bad { *w | mask } else { *w & !mask };
        }
        self.head = (self.head + 1) % RING_BITS;
        self.bad = (self.bad + u32::from(bad)).saturating_sub(leaving);
    }

    /// Bad samples within the window.
    pub(super) fn count(&self) -> u32 {
        self.bad
    }
}

/// An accepted encoder sample.
#[derive(Debug, Clone, Copy)]
pub(super) struct Accepted {
    pub(super) raw: u16,
    pub(super) angle_rad: f32,
}

/// History of one encoder (joint or ankle).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct EncoderTrack {
    pub(super) window: SampleWindow,
    /// Code of the latest bad frame (reported when the window trips).
    pub(super) last_bad: Option<FaultCode>,
    /// Latest accepted sample; `None` until the first and after a re-seed.
    pub(super) last: Option<Accepted>,
    /// Ticks since `last` was accepted.
    pub(super) since_last: u32,
    /// Consecutive frames rejected as jumps (the offset below is taken at
    /// the debounce count).
    pub(super) consecutive_jumps: u8,
    /// What the encoder reads beyond the joint since a jump persisted (its
    /// magnet or zero moved: the joint cannot have moved so far so fast),
    /// in raw counts (mod 2¹⁴) and rad; taken out of every frame after.
    pub(super) offset_counts: u16,
    pub(super) offset_rad: f32,
}

/// How a frame would be taken, before the track moves on
/// ([`EncoderTrack::classify`]).
#[derive(Debug, Clone, Copy)]
pub(super) enum Class {
    /// A bad frame (bus, parity, error flag, or an impossible value: then
    /// the value, for the immediate fault).
    Bad(FaultCode, Option<f32>),
    /// The first frame, or one after a gap longer than the window: it
    /// (re-)seeds the track.
    Seed,
    /// A change larger than the joint could have made since the last
    /// accepted frame.
    Jump,
    /// A good frame: its change from the last accepted one and the ticks
    /// between them.
    Good {
        delta: i16,
        elapsed: u32,
        previous: Accepted,
    },
}

impl EncoderTrack {
    /// How `sense` would be taken now, without changing anything: the one
    /// rule the controller's sense stage (which uses only the frames taken)
    /// and the check share.
    pub(super) fn classify(
        &self,
        sense: &EncoderSense,
        debounce: Debounce,
        max_jump: u16,
    ) -> Class {
        let since_last = self.since_last.saturating_add(1);
        match sense.status {
            EncoderStatus::BusError => return Class::Bad(FaultCode::EncoderBusError, None),
            EncoderStatus::Parity => return Class::Bad(FaultCode::EncoderParity, None),
            EncoderStatus::ErrorFlag => return Class::Bad(FaultCode::EncoderErrorFlag, None),
            EncoderStatus::Ok => {
                let angle_ok = sense.angle_rad.abs() <= MAX_ENCODER_ANGLE_RAD;
                if sense.raw_counts > DATA_MASK || !angle_ok {
                    return Class::Bad(FaultCode::EncoderInvalidValue, Some(sense.angle_rad));
                }
            }
        }
        let window = u32::from(debounce.window_ticks);
        let Some(previous) = self.last.filter(|_| since_last <= window) else {
            return Class::Seed;
        };
        let delta = wrapped_delta(previous.raw, sense.raw_counts);
        let allowed = u32::from(max_jump).saturating_mul(since_last);
        if u32::from(delta.unsigned_abs()) > allowed {
            Class::Jump
        } else {
            Class::Good {
                delta,
                elapsed: since_last,
                previous,
            }
        }
    }

    /// Takes `sense` as [`EncoderTrack::classify`] says; raises the
    /// immediate invalid-value fault through the returned value.
    pub(super) fn update(
        &mut self,
        sense: &EncoderSense,
        debounce: Debounce,
        max_jump: u16,
    ) -> EncoderFrame {
        let class = self.classify(sense, debounce, max_jump);
        self.since_last = self.since_last.saturating_add(1);
        let current = Accepted {
            raw: sense.raw_counts,
            angle_rad: sense.angle_rad,
        };
        match class {
            Class::Bad(code, invalid) => {
                self.window.push(true, debounce.window_ticks);
                self.last_bad = Some(code);
                invalid.map_or(EncoderFrame::NONE, EncoderFrame::invalid_value)
            }
            Class::Seed => {
                self.window.push(false, debounce.window_ticks);
                self.accept(current);
                EncoderFrame::seed(current.angle_rad)
            }
            Class::Jump => {
                self.window.push(true, debounce.window_ticks);
                self.last_bad = Some(FaultCode::EncoderJump);
                self.consecutive_jumps = self.consecutive_jumps.saturating_add(1);
                if self.consecutive_jumps >= debounce.count {
                    // The jump persists: the encoder now reads offset. The
                    // fault is raised by the window; from now on the offset
                    // is taken out, so the next frame continues from the
                    // last accepted one (the joint's motion over these few
                    // ticks, a fraction of a degree, goes into the offset)
                    // and control keeps the joint's true angle: a hold that
                    // sets a foot down on angles 6° off dropped the pilot.
                    // (`sense` is already without the offset so far.)
                    if let Some(previous) = self.last {
                        let more = sense.raw_counts.wrapping_sub(previous.raw);
                        self.offset_counts = self.offset_counts.wrapping_add(more) & DATA_MASK;
                        self.offset_rad = wrap_pi(
                            self.offset_rad + wrap_pi(sense.angle_rad - previous.angle_rad),
                        );
                    }
                    self.consecutive_jumps = 0;
                }
                EncoderFrame::NONE
            }
            Class::Good {
                delta,
                elapsed,
                previous,
            } => {
                self.window.push(false, debounce.window_ticks);
                self.accept(current);
                EncoderFrame::moved(current.angle_rad, previous.angle_rad, delta, elapsed)
            }
        }
    }

    /// `sense` as this track takes it: without the offset of a persistent
    /// jump when it has one (`any_offset`: some track has, else nothing to
    /// look at).
    pub(super) fn seen(&self, sense: &EncoderSense, any_offset: bool) -> EncoderSense {
        if any_offset && self.offset_counts != 0 {
            self.without_offset(sense)
        } else {
            *sense
        }
    }

    /// `sense` without the offset of a persistent jump; a bad or invalid
    /// frame unchanged, so [`EncoderTrack::classify`] still sees it.
    pub(super) fn without_offset(&self, sense: &EncoderSense) -> EncoderSense {
        let valid = matches!(sense.status, EncoderStatus::Ok)
            && sense.raw_counts <= DATA_MASK
            && sense.angle_rad.abs() <= MAX_ENCODER_ANGLE_RAD;
        if !valid {
            return *sense;
        }
        EncoderSense {
            status: sense.status,
            raw_counts: sense.raw_counts.wrapping_sub(self.offset_counts) & DATA_MASK,
            angle_rad: self.angle_without_offset(sense.angle_rad),
        }
    }

    /// `angle_rad` without the offset of a persistent jump, in (−π, π].
    pub(super) fn angle_without_offset(&self, angle_rad: f32) -> f32 {
        if self.offset_rad == 0.0 {
            angle_rad
        } else {
            wrap_pi(angle_rad - self.offset_rad)
        }
    }

    pub(super) fn accept(&mut self, sample: Accepted) {
        self.last = Some(sample);
        self.since_last = 0;
        self.consecutive_jumps = 0;
    }

    /// The debounced bad-frame fault, if the window holds enough.
    pub(super) fn tripped(&self, debounce: Debounce) -> Option<(FaultCode, u32)> {
        let n = self.window.count();
        if n >= u32::from(debounce.count) {
            self.last_bad.map(|c| (c, n))
        } else {
            None
        }
    }
}

/// `x` (within (−3π, 3π]) folded into (−π, π].
fn wrap_pi(x: f32) -> f32 {
    use core::f32::consts::{PI, TAU};
    if x > PI {
        x - TAU
    } else if x <= -PI {
        x + TAU
    } else {
        x
    }
}

/// Per-joint history of the tick's own checks.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct JointTrack {
    pub(super) encoder: EncoderTrack,
    pub(super) saturated_ticks: u32,
}

/// Per-joint history of the windowed checks.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct JointMotion {
    pub(super) velocity_rad_s: f32,
    pub(super) velocity_valid: bool,
    pub(super) tracking_ticks: u32,
    pub(super) frozen_ticks: u32,
    pub(super) still_ticks: u32,
    pub(super) residual: super::response::Residual,
}

/// Per-force-sensor history.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ForceTrack {
    pub(super) window: SampleWindow,
    pub(super) last_bad: Option<FaultCode>,
}

#[cfg(test)]
mod tests {
    use super::SampleWindow;

    #[test]
    fn a_window_counts_the_bad_samples_among_its_last_pushes() {
        // Against the plain count over a list, for windows 1..=128 and a
        // pseudo-random pattern long enough to wrap the ring many times.
        for window in [1u8, 2, 7, 31, 32, 33, 100, 127, 128] {
            let mut w = SampleWindow::default();
            let mut all = [false; 3000];
            let mut x = 0x2545_f491_u32;
            for n in 0..all.len() {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                // Dense bursts, sparse stretches and long clean ones (where
                // the window empties and a push only moves the head).
                let bad = match (n / 300) % 3 {
                    0 => x % 5 < 2,
                    1 => x.is_multiple_of(97),
                    _ => false,
                };
                all[n] = bad;
                w.push(bad, window);
                let from = (n + 1).saturating_sub(usize::from(window));
                let expected = all[from..=n].iter().filter(|b| **b).count() as u32;
                assert_eq!(w.count(), expected, "window {window} after {}", n + 1);
            }
        }
    }
}
