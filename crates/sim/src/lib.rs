//! sim: the closed-loop plant and simulated peripherals.
//!
//! The plant ([`plant::Plant`]) is the paper's sagittal 5-link chain (gait-core's
//! model and dynamics) plus the world around it: which leg stands, where the
//! feet are, the terrain, the semi-passive ankle and the pilot balancing on
//! crutches. The peripherals speak the real wire formats (AS5048A, MCP3208,
//! a sign-magnitude motor bridge, buttons), each written from its datasheet
//! and not from gait-control's drivers, so that a bug in one is not mirrored
//! in the other. They exchange values with the plant through [`shared`]
//! cells that [`wiring::Wiring`] updates once per tick.
//!
//! Modules: [`plant`] (chain, world, landing), [`impact`] (the landing's
//! velocity map), [`pilot`] (balancing and crutch load), [`terrain`];
//! peripherals [`as5048a`], [`mcp3208`], [`motor`], [`pins`], their common
//! SPI plumbing [`spi`] and measurement [`noise`]; [`shared`] cells and
//! clock; [`wiring`].
//!
//! std only, single-threaded (`Rc` handles): a harness steps everything in
//! lock-step at 1 kHz.

pub mod as5048a;
pub mod campaign;
pub mod closed_loop;
pub mod compare;
pub mod impact;
pub mod inject;
pub mod mcp3208;
pub mod motor;
pub mod noise;
pub mod outcome;
pub mod pilot;
pub mod pins;
pub mod plant;
pub mod plot;
pub mod replanning;
pub mod replay;
pub mod residual;
pub mod scenario;
pub mod shared;
pub mod spi;
pub mod summary;
pub mod terrain;
pub mod wiring;

pub use pilot::{PilotConfig, PilotTarget};
pub use plant::{JointStops, Landing, Plant, PlantConfig, Side, SimError, TrueState};
pub use shared::{SharedF64, SimClock};
pub use terrain::Terrain;
pub use wiring::Wiring;
