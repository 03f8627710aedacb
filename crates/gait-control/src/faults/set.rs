//! A fixed-size set of fault codes, one bit per code, and the sets of
//! them each reaction covers (worked out from the table when compiling).

use super::{FaultCode, InSwing, Reaction};

/// A set of fault codes (one bit per code).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FaultSet(u64);

impl FaultSet {
    /// The empty set.
    pub const EMPTY: Self = Self(0);

    /// The empty set.
    #[must_use]
    pub const fn new() -> Self {
        Self::EMPTY
    }

    /// Adds `code`.
    pub const fn insert(&mut self, code: FaultCode) {
        self.0 |= code.bit();
    }

    /// Removes `code`.
    pub const fn remove(&mut self, code: FaultCode) {
        self.0 &= !code.bit();
    }

    /// Whether `code` is in the set.
    #[must_use]
    pub const fn contains(&self, code: FaultCode) -> bool {
        self.0 & code.bit() != 0
    }

    /// Whether the set is empty.
    #[must_use]
    pub const fn is_empty(&self) -> bool {
        self.0 == 0
    }

    /// Number of codes in the set.
    #[must_use]
    pub const fn len(&self) -> usize {
        self.0.count_ones() as usize
    }

    /// Codes in both sets.
    #[must_use]
    pub const fn intersection(self, other: Self) -> Self {
        Self(self.0 & other.0)
    }

    /// Codes in either set.
    #[must_use]
    pub const fn union(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    /// The raw bits (bit *i* is `FaultCode::ALL[i]`), for compact logs.
    #[must_use]
    pub const fn bits(&self) -> u64 {
        self.0
    }

    /// The codes in the set, in [`FaultCode::ALL`] order.
    pub fn iter(&self) -> impl Iterator<Item = FaultCode> + '_ {
        FaultCode::ALL.iter().copied().filter(|c| self.contains(*c))
    }

    /// The most severe reaction over the set ([`Reaction::None`] if empty).
    #[must_use]
    pub const fn reaction(&self) -> Reaction {
        // Masks worked out from the table when compiling: three ANDs a
        // tick instead of a walk over the table (60 instructions a tick on
        // the M4, more with faults latched: the safe hold's worst tick).
        if self.0 & REACTION_DISABLE_MOTORS != 0 {
            Reaction::DisableMotors
        } else if self.0 & REACTION_SAFE_HOLD != 0 {
            Reaction::SafeHold
        } else if self.0 & REACTION_FINISH_STEP != 0 {
            Reaction::FinishStepThenHold
        } else if self.0 & REACTION_PLAY_TABLE != 0 {
            Reaction::PlayTable
        } else {
            Reaction::None
        }
    }

    /// What the safe hold does in a swing ([`InSwing`]): land first only
    /// when every fault that asks for a safe hold lets the step land;
    /// otherwise set the foot down.
    #[must_use]
    pub const fn in_swing(&self) -> InSwing {
        if self.0 & HOLD_NOW_IN_SWING != 0 {
            InSwing::HoldNow
        } else {
            InSwing::LandFirst
        }
    }
}

/// The faults whose safe hold holds a swing at once and sets its foot
/// down, as [`FaultSet`] bits (worked out from the table when compiling:
/// one AND a tick).
const HOLD_NOW_IN_SWING: u64 = in_swing_mask(&FaultCode::ALL, InSwing::HoldNow);

/// The [`FaultSet`] bits of the faults of each reaction
/// ([`FaultSet::reaction`]).
const REACTION_DISABLE_MOTORS: u64 = reaction_mask(&FaultCode::ALL, Reaction::DisableMotors);
const REACTION_SAFE_HOLD: u64 = reaction_mask(&FaultCode::ALL, Reaction::SafeHold);
const REACTION_FINISH_STEP: u64 = reaction_mask(&FaultCode::ALL, Reaction::FinishStepThenHold);
const REACTION_PLAY_TABLE: u64 = reaction_mask(&FaultCode::ALL, Reaction::PlayTable);

/// The [`FaultSet`] bits of the codes in `codes` whose reaction is `which`.
const fn reaction_mask(codes: &[FaultCode], which: Reaction) -> u64 {
    match codes {
        [c, rest @ ..] => {
            let here = c.reaction() as u8 == which as u8;
            (if here { c.bit() } else { 0 }) | reaction_mask(rest, which)
        }
        [] => 0,
    }
}

/// The [`FaultSet`] bits of the safe-hold faults in `codes` whose swing
/// reaction is `which`.
const fn in_swing_mask(codes: &[FaultCode], which: InSwing) -> u64 {
    match codes {
        [c, rest @ ..] => {
            let here =
                matches!(c.reaction(), Reaction::SafeHold) && c.in_swing() as u8 == which as u8;
            (if here { c.bit() } else { 0 }) | in_swing_mask(rest, which)
        }
        [] => 0,
    }
}

impl FromIterator<FaultCode> for FaultSet {
    fn from_iter<I: IntoIterator<Item = FaultCode>>(iter: I) -> Self {
        let mut set = Self::new();
        for c in iter {
            set.insert(c);
        }
        set
    }
}
