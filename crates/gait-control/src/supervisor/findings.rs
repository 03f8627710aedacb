//! What the windowed checks (`windowed.rs`) found in one tick's facts, for
//! the latch at the next tick's guard: the faults present, in the order
//! raised, and the ankles whose readings control must stop or start taking
//! again. Each raise reads and moves on the latch's marks (braked, blind,
//! held in place once) as the latch's own raise would.

use super::*;

/// Room for the faults of two ticks' windowed checks (at most 32 a tick:
/// every rule of every channel at once, 4 joints × 4, 2 ankles × 3, 4 force
/// sensors × 2, 2 for the drive monitor; a little more is kept): a late
/// task adds a tick's findings to those the tick has not taken yet
/// (`check_slot`).
pub const MAX_RAISES: usize = 68;

/// What the latch had marked when the job was handed over: which joints
/// are braked, blind, or were held in place once (0x0404's rule for a
/// joint dragged by a braked one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Marks {
    pub(super) braked: [bool; JOINTS],
    pub(super) angle_lost: [bool; JOINTS],
    pub(super) held_once: [bool; JOINTS],
}

/// Whether `code` raised on `joint` holds it in place instead of braking
/// it: [`FaultCode::held_in_place_first`], another joint already `braked`
/// (or blind, `angle_lost`), this one not `held_once` before. The latch's
/// rule, and the windowed checks' on their marks.
pub(super) fn holds_in_place(
    code: FaultCode,
    joint: usize,
    braked: [bool; JOINTS],
    angle_lost: [bool; JOINTS],
    held_once: [bool; JOINTS],
) -> bool {
    let other_braked = braked
        .iter()
        .zip(&angle_lost)
        .enumerate()
        .any(|(k, (&b, &l))| k != joint && (b || l));
    let first = held_once.get(joint) == Some(&false);
    code.held_in_place_first() && other_braked && first
}

/// One fault the windowed checks found present.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Raise {
    pub(super) code: FaultCode,
    pub(super) channel: u8,
    pub(super) value: f32,
    /// 0x0404 on a joint dragged by a braked one: held where it is, not
    /// braked ([`Verdict::rehold_joints`]).
    pub(super) hold: bool,
}

impl Raise {
    /// The fault.
    pub const fn code(&self) -> FaultCode {
        self.code
    }
}

const NO_RAISE: Raise = Raise {
    code: FaultCode::DeadlineMissed,
    channel: NO_CHANNEL,
    value: 0.0,
    hold: false,
};

/// What the windowed checks found in one tick's facts: the faults present
/// (the latch takes them as its own checks' at the next guard) and the
/// ankles whose readings control must stop or start taking again
/// (0x0207's stuck ankle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Findings {
    pub(super) tick: u32,
    pub(super) raises: [Raise; MAX_RAISES],
    pub(super) len: u8,
    /// `Some(stuck)` where an ankle's stuck state changed.
    pub(super) ankle_stuck: [Option<bool>; ANKLES],
    /// A raise found no room (the task fell behind by more than a tick):
    /// latched as 0x0608.
    pub(super) overflowed: bool,
    /// The latch's marks as the raises so far left them (read by later
    /// raises, as the latch's own would be).
    pub(super) marks: Marks,
}

impl Findings {
    /// Nothing found in the facts of `tick`, the latch marked `marks`.
    pub(super) const fn new(tick: u32, marks: Marks) -> Self {
        Self {
            tick,
            raises: [NO_RAISE; MAX_RAISES],
            len: 0,
            ankle_stuck: [None; ANKLES],
            overflowed: false,
            marks,
        }
    }

    /// Nothing found (before the first job).
    pub const NONE: Self = Self::new(
        0,
        Marks {
            braked: [false; JOINTS],
            angle_lost: [false; JOINTS],
            held_once: [false; JOINTS],
        },
    );

    /// The tick whose facts these are.
    pub const fn tick(&self) -> u32 {
        self.tick
    }

    /// The faults found, in the order raised.
    pub fn raises(&self) -> &[Raise] {
        self.raises.get(..usize::from(self.len)).unwrap_or(&[])
    }

    /// Whether `code` was found (on any channel).
    pub fn contains(&self, code: FaultCode) -> bool {
        self.raises().iter().any(|r| r.code == code)
    }

    /// Whether a raise found no room.
    pub const fn overflowed(&self) -> bool {
        self.overflowed
    }

    /// Adds `later`'s findings (of a later tick's facts) to these, which
    /// the tick has not taken yet: both are applied at once, in order.
    pub fn merge(&mut self, later: &Self) {
        for &r in later.raises() {
            self.store(r);
        }
        for (stuck, change) in self.ankle_stuck.iter_mut().zip(later.ankle_stuck) {
            if change.is_some() {
                *stuck = change;
            }
        }
        self.overflowed |= later.overflowed;
        self.tick = later.tick;
    }

    /// Keeps `r`, or marks the findings overflowed.
    fn store(&mut self, r: Raise) {
        match self.raises.get_mut(usize::from(self.len)) {
            Some(slot) => {
                *slot = r;
                self.len += 1;
            }
            None => self.overflowed = true,
        }
    }

    fn push(&mut self, r: Raise) {
        self.store(r);
        let mark = !r.hold;
        let marks = if !mark {
            None
        } else if r.code.loses_angle() {
            Some(&mut self.marks.angle_lost)
        } else if r.code.brakes_joint() {
            Some(&mut self.marks.braked)
        } else {
            None
        };
        if let Some(b) = marks.and_then(|m| m.get_mut(usize::from(r.channel))) {
            *b = true;
        }
    }

    /// `code`'s condition holds on `channel` (as [`Latch::raise`]).
    pub(super) fn raise(&mut self, code: FaultCode, channel: u8, value: f32) {
        self.push(Raise {
            code,
            channel,
            value,
            hold: false,
        });
    }

    /// `code` on `joint`, held in place instead of braked where the latch
    /// would (`Latch::holds_in_place`'s rule, on the marks); returns
    /// whether it is.
    pub(super) fn raise_on_joint(&mut self, code: FaultCode, joint: usize, value: f32) -> bool {
        let m = &self.marks;
        let hold = holds_in_place(code, joint, m.braked, m.angle_lost, m.held_once);
        if hold {
            if let Some(once) = self.marks.held_once.get_mut(joint) {
                *once = true;
            }
        }
        self.push(Raise {
            code,
            channel: u8::try_from(joint).unwrap_or(NO_CHANNEL),
            value,
            hold,
        });
        hold
    }
}
