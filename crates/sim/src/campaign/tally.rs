//! Counts over a campaign's results, per fault kind or per gait, and in
//! all.

use super::{HealthyResult, RunResult};

/// Counts over a campaign, per kind and in all.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tally {
    /// Runs.
    pub runs: usize,
    /// Runs in which the pilot fell.
    pub falls: usize,
    /// Of them, falls outside the cases named with their physical reason
    /// ([`NamedCase`]): the device's to fix.
    pub unnamed_falls: usize,
    /// Runs in which a hip or knee went past its Table I stop.
    pub past_a_stop: usize,
    /// Of them, runs whose stop no named case explains: the device's.
    pub unnamed_past_a_stop: usize,
    /// Runs of a must-detect kind that nothing detected.
    pub missed: usize,
    /// Runs with a fault latched before the injection.
    pub false_trips: usize,
    /// Runs the simulation could not finish (not a fall).
    pub errors: usize,
}

impl Tally {
    /// Adds one run.
    pub fn add(&mut self, r: &RunResult) {
        self.runs += 1;
        self.falls += usize::from(r.outcome.fell.is_some());
        self.unnamed_falls += usize::from(r.unnamed_fall());
        self.past_a_stop += usize::from(r.past_a_stop());
        self.unnamed_past_a_stop += usize::from(r.unnamed_stop());
        self.missed += usize::from(r.missed());
        self.false_trips += usize::from(r.false_trip);
        self.errors += usize::from(r.error.is_some());
    }
}

/// The tally of `results` per kind name, in the order kinds first appear,
/// and over all.
pub fn tally(results: &[RunResult]) -> (Vec<(&'static str, Tally)>, Tally) {
    grouped(results, |r| r.run.fault.kind.name(), Tally::add)
}

/// The tally of `results` per gait, each of the campaign's `gaits` slots
/// in order (one no run drew: an empty tally): which of a patient's gaits
/// a fault drops the pilot from.
pub fn tally_by_gait(results: &[RunResult], gaits: usize) -> Vec<(usize, Tally)> {
    let mut by: Vec<(usize, Tally)> = (0..gaits).map(|g| (g, Tally::default())).collect();
    for r in results {
        if let Some((_, t)) = by.get_mut(r.run.slot) {
            t.add(r);
        }
    }
    by
}

/// `results` added up per `key`, in the order keys first appear, and over
/// all.
fn grouped<R, K: PartialEq, T: Default>(
    results: &[R],
    key: impl Fn(&R) -> K,
    add: impl Fn(&mut T, &R),
) -> (Vec<(K, T)>, T) {
    let mut by: Vec<(K, T)> = Vec::new();
    let mut all = T::default();
    for r in results {
        let k = key(r);
        match by.iter_mut().find(|(n, _)| *n == k) {
            Some((_, t)) => add(t, r),
            None => {
                let mut t = T::default();
                add(&mut t, r);
                by.push((k, t));
            }
        }
        add(&mut all, r);
    }
    (by, all)
}

/// Counts over healthy runs, per gait and in all.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HealthyTally {
    /// Runs.
    pub runs: usize,
    /// Runs in which the pilot fell.
    pub falls: usize,
    /// Runs in which a hip or knee went past its Table I stop.
    pub past_a_stop: usize,
    /// Runs in which anything latched.
    pub false_trips: usize,
    /// Runs with fewer landings than steps asked.
    pub short: usize,
    /// Runs the simulation could not finish (not a fall).
    pub errors: usize,
}

impl HealthyTally {
    /// Adds one run.
    pub fn add(&mut self, r: &HealthyResult) {
        self.runs += 1;
        self.falls += usize::from(r.outcome.fell.is_some());
        self.past_a_stop += usize::from(r.outcome.worst_limit_margin_rad < 0.0);
        self.false_trips += usize::from(r.false_trip());
        self.short += usize::from(r.short());
        self.errors += usize::from(r.error.is_some());
    }
}

/// The tally of healthy `results` per gait (by slot in the campaign's
/// gaits), in the order gaits first appear, and over all.
pub fn healthy_tally(results: &[HealthyResult]) -> (Vec<(usize, HealthyTally)>, HealthyTally) {
    grouped(results, |r| r.run.slot, HealthyTally::add)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::CampaignRun;
    use crate::campaign::play::no_outcome;
    use gait_control::operator::Gait;

    fn result(slot: usize, fell: bool) -> RunResult {
        let mut outcome = no_outcome();
        outcome.fell = fell.then(|| "fell".to_string());
        RunResult {
            run: CampaignRun {
                gait: Gait::Walk,
                slot,
                fault: "estop@2".parse().unwrap_or_else(|e| panic!("{e}")),
                noise_seed: 1,
            },
            outcome,
            false_trip: false,
            detected: true,
            error: None,
            struck_in: None,
            stance_after_strike: [false; 2],
            stance_before_stop: [false; 2],
            carrying_at_strike: [false; 2],
        }
    }

    #[test]
    fn fault_runs_are_tallied_for_every_gait_in_slot_order() {
        let results = [result(2, true), result(0, false), result(2, false)];
        let by = tally_by_gait(&results, 3);
        let counts: Vec<(usize, usize, usize)> =
            by.iter().map(|(s, t)| (*s, t.runs, t.falls)).collect();
        assert_eq!(counts, [(0, 1, 0), (1, 0, 0), (2, 2, 1)]);
    }
}
