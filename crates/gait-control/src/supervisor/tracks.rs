//! What the supervisor remembers of each channel between ticks: the
//! sliding windows of bad samples, the last accepted encoder frame, the
//! joints' filtered velocities and their tracking, frozen and saturation
//! counters.

use super::*;

/// Sliding window over the last ≤ 128 ticks: bit 0 is this tick.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct SampleWindow {
    pub(super) history: u128,
}

impl SampleWindow {
    pub(super) fn push(&mut self, bad: bool) {
        self.history = (self.history << 1) | u128::from(bad);
    }

    pub(super) fn count(&self, window_ticks: u8) -> u32 {
        let mask = match 1u128.checked_shl(u32::from(window_ticks)) {
            Some(b) => b.wrapping_sub(1),
            None => u128::MAX,
        };
        (self.history & mask).count_ones()
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
    /// Consecutive frames rejected as jumps (re-seed at the debounce count).
    pub(super) consecutive_jumps: u8,
}

/// What this tick's encoder frame turned out to be.
#[derive(Debug, Clone, Copy)]
pub(super) enum Frame {
    /// Accepted; `delta_counts` and the elapsed ticks since the previous
    /// accepted sample, if there was one.
    Accepted {
        angle_rad: f32,
        delta: Option<(i16, u32)>,
        previous_angle_rad: f32,
    },
    /// Not used this tick.
    Rejected,
}

impl EncoderTrack {
    /// Classifies `sense`; raises the immediate invalid-value fault through
    /// `invalid`. Returns the frame and whether it was bad.
    pub(super) fn update(
        &mut self,
        sense: &EncoderSense,
        debounce: Debounce,
        max_jump: u16,
    ) -> (Frame, Option<f32>) {
        self.since_last = self.since_last.saturating_add(1);
        let mut invalid = None;
        let bad_code = match sense.status {
            EncoderStatus::BusError => Some(FaultCode::EncoderBusError),
            EncoderStatus::Parity => Some(FaultCode::EncoderParity),
            EncoderStatus::ErrorFlag => Some(FaultCode::EncoderErrorFlag),
            EncoderStatus::Ok => {
                let angle_ok = sense.angle_rad.abs() <= MAX_ENCODER_ANGLE_RAD;
                if sense.raw_counts > DATA_MASK || !angle_ok {
                    invalid = Some(sense.angle_rad);
                    Some(FaultCode::EncoderInvalidValue)
                } else {
                    None
                }
            }
        };
        if let Some(code) = bad_code {
            self.window.push(true);
            self.last_bad = Some(code);
            return (Frame::Rejected, invalid);
        }
        let current = Accepted {
            raw: sense.raw_counts,
            angle_rad: sense.angle_rad,
        };
        let window = u32::from(debounce.window_ticks);
        let previous = self.last.filter(|_| self.since_last <= window);
        let Some(previous) = previous else {
            // First sample, or a gap longer than the window: (re-)seed.
            self.window.push(false);
            self.accept(current);
            return (
                Frame::Accepted {
                    angle_rad: current.angle_rad,
                    delta: None,
                    previous_angle_rad: current.angle_rad,
                },
                None,
            );
        };
        let delta = wrapped_delta(previous.raw, current.raw);
        let allowed = u32::from(max_jump).saturating_mul(self.since_last);
        if u32::from(delta.unsigned_abs()) > allowed {
            self.window.push(true);
            self.last_bad = Some(FaultCode::EncoderJump);
            self.consecutive_jumps = self.consecutive_jumps.saturating_add(1);
            if self.consecutive_jumps >= debounce.count {
                // The jump persists: it is where the encoder now reads.
                // The fault is raised by the window; take the new value
                // as the reference so the condition can clear.
                self.last = None;
                self.consecutive_jumps = 0;
            }
            return (Frame::Rejected, None);
        }
        let elapsed = self.since_last;
        self.window.push(false);
        self.accept(current);
        (
            Frame::Accepted {
                angle_rad: current.angle_rad,
                delta: Some((delta, elapsed)),
                previous_angle_rad: previous.angle_rad,
            },
            None,
        )
    }

    pub(super) fn accept(&mut self, sample: Accepted) {
        self.last = Some(sample);
        self.since_last = 0;
        self.consecutive_jumps = 0;
    }

    /// The debounced bad-frame fault, if the window holds enough.
    pub(super) fn tripped(&self, debounce: Debounce) -> Option<(FaultCode, u32)> {
        let n = self.window.count(debounce.window_ticks);
        if n >= u32::from(debounce.count) {
            self.last_bad.map(|c| (c, n))
        } else {
            None
        }
    }
}

/// Per-joint history.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct JointTrack {
    pub(super) encoder: EncoderTrack,
    pub(super) velocity_rad_s: f32,
    pub(super) velocity_valid: bool,
    pub(super) tracking_ticks: u32,
    pub(super) frozen_ticks: u32,
    pub(super) saturated_ticks: u32,
}

/// Per-force-sensor history.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ForceTrack {
    pub(super) window: SampleWindow,
    pub(super) last_bad: Option<FaultCode>,
}
