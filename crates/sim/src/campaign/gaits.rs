//! The gaits a campaign plays: the device's own three, or every gait of a
//! patient's bundle, each with the tables it is played from. A run names
//! its gait by its slot here, so that a clinic's family (its paces and
//! stairs) is campaigned as the built-in gaits are.

use gait_control::operator::Gait;
use gait_control::sequencer::GaitTables;
use gait_core::bundle::Bundle;

use crate::compare::{gait_of, tables_of};
use crate::scenario::flash_tables;

/// One gait a campaign plays.
#[derive(Clone, Debug)]
pub struct CampaignGait<'t> {
    /// Its name as `--gait` takes it (a bundle's: the clinician's name).
    pub name: String,
    /// Its movement.
    pub gait: Gait,
    /// The tables it is played from (a bundle's gait: its table alone).
    pub tables: GaitTables<'t>,
}

/// The gaits of a campaign, by slot.
#[derive(Clone, Debug)]
pub struct CampaignGaits<'t> {
    gaits: Vec<CampaignGait<'t>>,
}

impl CampaignGaits<'static> {
    /// The device's own gaits from its flash tables: slot 0 walking, 1
    /// stair ascent, 2 stair descent.
    pub fn built_in() -> Self {
        let tables = flash_tables();
        let gait = |name: &str, gait| CampaignGait {
            name: name.to_string(),
            gait,
            tables,
        };
        Self {
            gaits: vec![
                gait("walk", Gait::Walk),
                gait("stair-up", Gait::StairUp),
                gait("stair-down", Gait::StairDown),
            ],
        }
    }
}

impl<'t> CampaignGaits<'t> {
    /// Every gait of `bundle`, in the clinician's order (slot *i* its gait
    /// *i*), each played alone from its own table.
    pub fn of_bundle(bundle: &Bundle<'t>) -> Self {
        Self {
            gaits: (0..bundle.len())
                .filter_map(|i| bundle.gait(i))
                .map(|g| CampaignGait {
                    name: g.info.name.as_str().to_string(),
                    gait: gait_of(g.table.kind()),
                    tables: tables_of(g.table),
                })
                .collect(),
        }
    }

    /// The gaits `gaits`, in slot order.
    pub fn of(gaits: Vec<CampaignGait<'t>>) -> Self {
        Self { gaits }
    }

    /// How many there are.
    pub fn len(&self) -> usize {
        self.gaits.len()
    }

    /// None at all.
    pub fn is_empty(&self) -> bool {
        self.gaits.is_empty()
    }

    /// The gait in `slot`.
    pub fn get(&self, slot: usize) -> Option<&CampaignGait<'t>> {
        self.gaits.get(slot)
    }

    /// The name of the gait in `slot` ("?" for none).
    pub fn name(&self, slot: usize) -> &str {
        self.gaits.get(slot).map_or("?", |g| g.name.as_str())
    }

    /// All of them, by slot.
    pub fn iter(&self) -> impl Iterator<Item = &CampaignGait<'t>> {
        self.gaits.iter()
    }
}

/// The slot of `gait` among the device's own gaits
/// ([`CampaignGaits::built_in`]).
pub const fn built_in_slot(gait: Gait) -> usize {
    match gait {
        Gait::Walk => 0,
        Gait::StairUp => 1,
        Gait::StairDown => 2,
    }
}
