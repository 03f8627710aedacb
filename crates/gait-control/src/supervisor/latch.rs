//! What latched and the post-mortem log, apart from the channels' tracks so
//! that a check can raise while it holds one of them.

use super::*;

/// What latched, and the post-mortem log: apart from the channels' tracks
/// so that a check can raise while it holds one of them and reads the
/// configuration in place.
#[derive(Debug, Clone)]
pub(super) struct Latch {
    pub(super) latched: FaultSet,
    /// Per fault (by index), channels already logged since it latched.
    pub(super) logged_channels: [u8; FaultCode::COUNT],
    /// Whether a no-channel record was logged since the fault latched.
    pub(super) logged_none: FaultSet,
    pub(super) log: RingLog<FaultRecord, LOG_LEN>,
    /// Joints whose drive a fault has disabled ([`FaultCode::brakes_joint`]),
    /// until a reset.
    pub(super) braked: [bool; JOINTS],
    /// Joints whose encoder a fault has lost ([`FaultCode::loses_angle`]),
    /// until a reset.
    pub(super) angle_lost: [bool; JOINTS],
    /// Joints 0x0404 has held in place instead of braking, until a reset.
    pub(super) held_in_place_once: [bool; JOINTS],
    /// Those of them this tick ([`Verdict::rehold_joints`]).
    pub(super) hold_in_place: [bool; JOINTS],
}

impl Latch {
    /// Records that `code`'s condition holds now on `channel`: latches it,
    /// and logs it once per channel while latched.
    pub(super) fn raise(&mut self, t: &mut Tick, code: FaultCode, channel: u8, value: f32) {
        self.raise_marking(t, code, channel, value, true);
    }

    /// Whether `code` raised on `joint` now holds it in place instead of
    /// braking it: [`FaultCode::held_in_place_first`], another joint
    /// already braked (or blind), this one not held in place before.
    pub(super) fn holds_in_place(&self, code: FaultCode, joint: usize) -> bool {
        super::findings::holds_in_place(
            code,
            joint,
            self.braked,
            self.angle_lost,
            self.held_in_place_once,
        )
    }

    /// [`Latch::raise`]; a joint's brake or lost angle marked only with
    /// `mark`.
    pub(super) fn raise_marking(
        &mut self,
        t: &mut Tick,
        code: FaultCode,
        channel: u8,
        value: f32,
        mark: bool,
    ) {
        t.present.insert(code);
        let marks = if !mark {
            None
        } else if code.loses_angle() {
            Some(&mut self.angle_lost)
        } else if code.brakes_joint() {
            Some(&mut self.braked)
        } else {
            None
        };
        if let Some(b) = marks.and_then(|m| m.get_mut(usize::from(channel))) {
            *b = true;
        }
        if !self.latched.contains(code) {
            self.latched.insert(code);
            t.new.insert(code);
        }
        let index = usize::from(code.index());
        let first_time = if channel == NO_CHANNEL {
            let first = !self.logged_none.contains(code);
            self.logged_none.insert(code);
            first
        } else {
            let bit = 1u8.checked_shl(u32::from(channel)).unwrap_or(0);
            match self.logged_channels.get_mut(index) {
                Some(mask) => {
                    let first = *mask & bit == 0;
                    *mask |= bit;
                    first
                }
                None => false,
            }
        };
        if first_time {
            self.log.push(FaultRecord {
                tick: t.tick,
                code,
                channel,
                value,
            });
        }
    }
}
