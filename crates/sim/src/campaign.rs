//! A seeded randomised fault campaign: each run walks, climbs or descends
//! with sensor noise and one fault of a random kind, target, value and time
//! (standing, in a swing or in a weight transfer), and is judged by
//! [`crate::outcome`]. Beside it, healthy runs of each gait with sensor
//! noise and no fault, in which anything latched is a false trip. The same
//! seed gives the same runs. `exogait faults` and the campaign tests run
//! them; docs/campaign.md has the figures.
//!
//! A campaign plays the device's own gaits or every gait of a patient's
//! bundle (`gaits`).
//!
//! In modules: the gaits played (`gaits`), the seeded plans (`plan`), a fault run's result and what
//! it must detect (`run`), playing and judging it (`play`), healthy runs
//! (`healthy`), the counts (`tally`), the falls named with their physical
//! reason (`named`), and spreading runs over the cores (`parallel`).

mod gaits;
mod healthy;
mod named;
mod parallel;
mod plan;
mod play;
mod run;
mod tally;

pub use gaits::{CampaignGait, CampaignGaits, built_in_slot};
pub use healthy::{
    HEALTHY_STEPS, HealthyResult, HealthyRun, play_all_healthy, play_all_healthy_on, play_healthy,
    play_healthy_on,
};
pub use named::{NamedCase, explains_stop, named_case};
pub use plan::{healthy_plan, healthy_plan_over, plan, plan_over};
pub use play::{play, play_all, play_all_on, play_all_with_pilot, play_on, play_with_pilot};
pub use run::{CampaignRun, RunResult, must_be_detected};
pub use tally::{HealthyTally, Tally, healthy_tally, tally, tally_by_gait};
