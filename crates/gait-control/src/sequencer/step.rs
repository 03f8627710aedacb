//! The step a swing plays: the flash table's, or the one the idle-time
//! re-planner made of it for where the pilot's ankle is
//! ([`crate::replan`]). Both are Φ samples at the table's period, read the
//! same way (one interpolation a tick).

use gait_core::LINKS;
use gait_core::ik::IkOptions;
use gait_core::tables::{GaitTable, interpolate};

use crate::replan::ReplanSlot;

/// The samples of the step being played.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepTable<'t> {
    /// The verified table, as planned.
    Planned(GaitTable<'t>),
    /// The re-planned step taken from the slot: `len` samples at the
    /// table's period, with its IK options.
    Replanned {
        /// Where the samples are.
        slot: &'t ReplanSlot,
        /// How many.
        len: usize,
        /// The table it was made from.
        table: GaitTable<'t>,
    },
}

impl StepTable<'_> {
    /// Sample `k` (Φ, rad), or `None` past the end.
    #[inline]
    pub fn sample(&self, k: usize) -> Option<[f32; LINKS]> {
        match self {
            Self::Planned(t) => t.sample(k),
            Self::Replanned { slot, len, .. } if k < *len => slot.sample(k),
            Self::Replanned { .. } => None,
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        match self {
            Self::Planned(t) => t.len(),
            Self::Replanned { len, .. } => *len,
        }
    }

    /// Whether it has no sample (never, for a step being played).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The table it plays or was made from.
    pub fn table(&self) -> &GaitTable<'_> {
        match self {
            Self::Planned(t) | Self::Replanned { table: t, .. } => t,
        }
    }

    /// Sample period, s.
    pub fn period_s(&self) -> f32 {
        self.table().period_s()
    }

    /// From the first to the last sample, s.
    pub fn duration_s(&self) -> f32 {
        self.period_s() * self.len().saturating_sub(1) as f32
    }

    /// The IK options its postures were made with.
    pub fn ik_options(&self) -> IkOptions<f32> {
        self.table().ik_options()
    }

    /// Φ at `t_s` (linear between samples, held at the ends).
    #[inline]
    pub fn at_time(&self, t_s: f32) -> [f32; LINKS] {
        match self {
            Self::Planned(t) => t.at_time(t_s),
            Self::Replanned { .. } => {
                interpolate(self.len(), self.period_s(), t_s, |k| self.sample(k))
            }
        }
    }
}
