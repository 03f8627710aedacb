//! The seeded plans: which fault runs and which healthy runs a campaign
//! plays (the same seed gives the same runs).

use gait_control::operator::Gait;

use crate::inject::{Injection, Kind, Target};

use super::{CampaignGaits, CampaignRun, HealthyRun};

/// A seeded xorshift generator (as [`crate::noise`]: a fixed sequence per
/// seed across library versions).
struct Draw(u64);

impl Draw {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    fn below(&mut self, n: usize) -> usize {
        (self.unit() * n as f64) as usize % n.max(1)
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// The `runs` runs of campaign `seed` over the device's own gaits
/// ([`CampaignGaits::built_in`]).
pub fn plan(seed: u64, runs: usize) -> Vec<CampaignRun> {
    plan_over(seed, runs, &CampaignGaits::built_in())
}

/// The `runs` runs of campaign `seed` over `gaits`, each gait drawn as
/// likely as the others (over the built-in three, the runs of [`plan`]).
pub fn plan_over(seed: u64, runs: usize, gaits: &CampaignGaits<'_>) -> Vec<CampaignRun> {
    let mut d = Draw(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    for _ in 0..8 {
        d.next();
    }
    (0..runs)
        .map(|_| {
            let slot = d.below(gaits.len());
            let gait = gaits.get(slot).map_or(Gait::Walk, |g| g.gait);
            let joint = Target::Joint(d.below(4));
            let encoder = if d.below(3) == 0 {
                Target::Ankle(d.below(2))
            } else {
                joint
            };
            let force = Target::Force(d.below(4));
            let sign = if d.below(2) == 0 { -1 } else { 1 };
            let (kind, target) = match d.below(24) {
                0 => (Kind::EncoderBus, Some(encoder)),
                1 => (Kind::EncoderParity, Some(encoder)),
                2 => (Kind::EncoderErrorFlag, Some(encoder)),
                3 => (Kind::EncoderStuck, Some(encoder)),
                4 => (
                    Kind::EncoderJump(sign * (110 + d.below(400)) as i32),
                    Some(joint),
                ),
                5 => (
                    Kind::EncoderGlitch(sign * (200 + d.below(3000)) as i32),
                    Some(encoder),
                ),
                6 => (Kind::FsrOpen, Some(force)),
                7 => (Kind::FsrShort, Some(force)),
                8 => (Kind::FsrOverRange, Some(force)),
                9 => (Kind::FsrSpike(d.range(100.0, 500.0)), Some(force)),
                10 => (Kind::AdcBus, None),
                11 => (Kind::MotorWeak(d.range(0.2, 0.8)), Some(joint)),
                12 => (Kind::MotorStuck, Some(joint)),
                13 => (Kind::PwmFail, Some(joint)),
                14 => (Kind::DirFail, Some(joint)),
                15 => (Kind::EStop, None),
                16 => (Kind::EStopRead, None),
                17 => (Kind::ButtonRead, None),
                18 => (Kind::Overrun(3 + d.below(8) as u32), None),
                19 => (Kind::PilotLean(d.range(0.05, 0.2)), None),
                20 => (Kind::PilotStopsBalancing, None),
                21 => (Kind::CurrentOpen, Some(joint)),
                22 => (Kind::GearSlip(d.range(0.2, 0.8)), Some(joint)),
                _ => (Kind::CurrentShort, Some(joint)),
            };
            // Standing before GO, then anywhere in the first two steps.
            let at_s = (d.range(0.3, 5.0) * 1000.0).round() / 1000.0;
            CampaignRun {
                gait,
                slot,
                fault: Injection { kind, target, at_s },
                noise_seed: d.next() % 1_000_000,
            }
        })
        .collect()
}

/// `per_gait` healthy runs of each of the device's own gaits, the noise
/// seeds drawn from `seed` (the same seed gives the same runs; none is a
/// fault run's).
pub fn healthy_plan(seed: u64, per_gait: usize) -> Vec<HealthyRun> {
    healthy_plan_over(seed, per_gait, &CampaignGaits::built_in())
}

/// `per_gait` healthy runs of each of `gaits`, in their order (over the
/// built-in three, the runs of [`healthy_plan`]).
pub fn healthy_plan_over(seed: u64, per_gait: usize, gaits: &CampaignGaits<'_>) -> Vec<HealthyRun> {
    let mut d = Draw(seed.wrapping_mul(0xD1B5_4A32_D192_ED03) | 1);
    for _ in 0..8 {
        d.next();
    }
    gaits
        .iter()
        .enumerate()
        .flat_map(|(slot, g)| (0..per_gait).map(move |_| (slot, g.gait)))
        .map(|(slot, gait)| HealthyRun {
            gait,
            slot,
            noise_seed: d.next() % 1_000_000,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plan_is_seeded_valid_and_covers_every_kind() {
        let a = plan(7, 400);
        assert_eq!(a, plan(7, 400));
        assert_ne!(a, plan(8, 400));
        for r in &a {
            // Each planned fault reads back as itself.
            let text = r.fault.to_string();
            let back: Injection = text.parse().unwrap_or_else(|e| panic!("{text}: {e}"));
            assert_eq!(back.kind.name(), r.fault.kind.name());
            assert!((0.3..=5.0).contains(&r.fault.at_s));
        }
        for name in [
            "encoder-bus",
            "encoder-jump",
            "fsr-over-range",
            "motor-stuck",
            "overrun",
            "pilot-stops-balancing",
            "current-open",
            "current-short",
        ] {
            assert!(a.iter().any(|r| r.fault.kind.name() == name), "{name}");
        }
    }

    /// Runs seed 1's campaigns drew before a campaign could play a bundle
    /// (`exogait faults --seed 1 --runs 10000 --json`): the draws over the
    /// device's own gaits are the same, run for run.
    #[test]
    fn seed_1_draws_the_runs_it_always_drew() {
        let runs = plan(1, 10_000);
        let has = |gait: Gait, fault: &str, noise_seed: u64| {
            runs.iter().any(|r| {
                r.gait == gait && r.fault.to_string() == fault && r.noise_seed == noise_seed
            })
        };
        assert!(has(
            Gait::StairUp,
            "gear-slip=0.2654469242661147:right-hip@2.607",
            838_232
        ));
        assert!(has(
            Gait::Walk,
            "pilot-lean=0.12628771405880707@1.954",
            734_570
        ));
        assert!(has(
            Gait::Walk,
            "pilot-lean=0.19284182142236195@3.491",
            972_269
        ));
    }

    #[test]
    fn a_campaign_over_a_bundle_draws_every_gait_by_its_slot() {
        let built_in = CampaignGaits::built_in();
        // Over the device's own gaits, the runs and slots of `plan`.
        let own = plan_over(5, 300, &built_in);
        assert_eq!(own, plan(5, 300));
        for r in &own {
            assert_eq!(built_in.get(r.slot).map(|g| g.gait), Some(r.gait));
        }
        // A family of five gaits (two walks, a descent twice): each slot
        // drawn, and each run's movement the one of its slot.
        let table = |g: Gait| built_in.get(super::super::built_in_slot(g)).cloned();
        let family: Vec<_> = [
            Gait::Walk,
            Gait::Walk,
            Gait::StairUp,
            Gait::StairDown,
            Gait::StairDown,
        ]
        .into_iter()
        .filter_map(table)
        .collect();
        let five = CampaignGaits::of(family);
        let runs = plan_over(5, 300, &five);
        for slot in 0..5 {
            let n = runs.iter().filter(|r| r.slot == slot).count();
            assert!((30..=90).contains(&n), "slot {slot}: {n} of 300 runs");
        }
        for r in &runs {
            assert_eq!(five.get(r.slot).map(|g| g.gait), Some(r.gait));
        }
        let healthy = healthy_plan_over(5, 4, &five);
        assert_eq!(healthy.len(), 20);
        for (k, r) in healthy.iter().enumerate() {
            assert_eq!(r.slot, k / 4);
            assert_eq!(five.get(r.slot).map(|g| g.gait), Some(r.gait));
        }
        assert_eq!(healthy_plan_over(5, 4, &built_in), healthy_plan(5, 4));
    }

    #[test]
    fn the_healthy_plan_is_seeded_and_gives_each_gait_its_runs() {
        let a = healthy_plan(3, 50);
        assert_eq!(a, healthy_plan(3, 50));
        assert_ne!(a, healthy_plan(4, 50));
        for gait in [Gait::Walk, Gait::StairUp, Gait::StairDown] {
            let seeds: std::collections::BTreeSet<u64> = a
                .iter()
                .filter(|r| r.gait == gait)
                .map(|r| r.noise_seed)
                .collect();
            assert_eq!(seeds.len(), 50, "{gait:?}: distinct noise seeds");
        }
    }
}
