//! The tables a sequencer plays, by slot, and how the operator's
//! selection finds its table.

use gait_core::tables::{GaitKind, GaitTable};

use crate::operator::{Gait, GaitChoice, MAX_GAITS};

/// The verified tables the device plays, one per slot: the device's own
/// three by movement ([`GaitTables::by_kind`]), or a patient's bundle in
/// the clinician's order ([`GaitTables::in_order`], borrowed from where the
/// board keeps them: the controller stays under 4 KiB, so that every field
/// is in reach of one Cortex-M load). A gait without a table cannot start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaitTables<'t> {
    slots: Slots<'t>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Slots<'t> {
    /// Walking, stair ascent, stair descent.
    ByKind([Option<GaitTable<'t>>; 3]),
    /// A patient's list (at most [`MAX_GAITS`] are used).
    Listed(&'t [Option<GaitTable<'t>>]),
}

impl Default for GaitTables<'_> {
    fn default() -> Self {
        Self {
            slots: Slots::ByKind([None; 3]),
        }
    }
}

/// The movement a table describes, as the operator names it.
#[must_use]
pub const fn gait_of_kind(kind: GaitKind) -> Gait {
    match kind {
        GaitKind::Walk => Gait::Walk,
        GaitKind::StairUp => Gait::StairUp,
        GaitKind::StairDown => Gait::StairDown,
    }
}

impl<'t> GaitTables<'t> {
    /// One table per movement: walking in slot 0, stair ascent in 1,
    /// descent in 2 (the slots [`crate::operator::AllowedGaits::new`]
    /// chooses).
    #[must_use]
    pub const fn by_kind(
        walk: Option<GaitTable<'t>>,
        stair_up: Option<GaitTable<'t>>,
        stair_down: Option<GaitTable<'t>>,
    ) -> Self {
        Self {
            slots: Slots::ByKind([walk, stair_up, stair_down]),
        }
    }

    /// A patient's tables in order, slot *i* holding `list[i]` (the first
    /// [`MAX_GAITS`]).
    #[must_use]
    pub const fn in_order(list: &'t [Option<GaitTable<'t>>]) -> Self {
        Self {
            slots: Slots::Listed(list),
        }
    }

    /// The table in `slot`, if present.
    #[must_use]
    pub fn slot(&self, slot: usize) -> Option<&GaitTable<'t>> {
        match &self.slots {
            Slots::ByKind(t) => t.get(slot)?.as_ref(),
            Slots::Listed(t) if slot < MAX_GAITS => t.get(slot)?.as_ref(),
            Slots::Listed(_) => None,
        }
    }

    /// The first slot holding a table of `gait`'s movement.
    #[must_use]
    pub fn slot_of(&self, gait: Gait) -> Option<usize> {
        (0..MAX_GAITS).find(|&i| self.slot(i).is_some_and(|t| gait_of_kind(t.kind()) == gait))
    }

    /// The first table of `gait`'s movement, if present and verified.
    #[must_use]
    pub fn get(&self, gait: Gait) -> Option<&GaitTable<'t>> {
        self.slot(self.slot_of(gait)?)
    }
}

/// What the operator selected, as the sequencer finds its table: a
/// movement (its first table) or a clinician's choice (its slot).
pub trait Selection: Copy {
    /// The slot of the selected table in `tables` (`None`: no table).
    fn slot_in(self, tables: &GaitTables<'_>) -> Option<usize>;
}

impl Selection for Gait {
    fn slot_in(self, tables: &GaitTables<'_>) -> Option<usize> {
        tables.slot_of(self)
    }
}

impl Selection for GaitChoice {
    fn slot_in(self, tables: &GaitTables<'_>) -> Option<usize> {
        let slot = usize::from(self.slot);
        tables.slot(slot).map(|_| slot)
    }
}
