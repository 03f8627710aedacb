//! A fault run's plan and what it gave: which of its falls and stops a
//! named case explains, and which kinds it must detect.

use gait_control::faults::FaultCode;
use gait_control::operator::Gait;
use gait_control::sequencer::Phase;

use crate::inject::{Injection, Kind};
use crate::outcome::Outcome;

use super::{NamedCase, explains_stop, named_case};

/// One planned run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CampaignRun {
    /// The gait's movement.
    pub gait: Gait,
    /// The gait itself: its slot in the campaign's gaits
    /// ([`super::CampaignGaits`]; the built-in ones: 0 walking, 1 stair
    /// ascent, 2 stair descent).
    pub slot: usize,
    /// The fault.
    pub fault: Injection,
    /// Seed of the sensor noise (±3 encoder, ±10 ADC counts).
    pub noise_seed: u64,
}

/// What one run gave.
#[derive(Clone, Debug, PartialEq)]
pub struct RunResult {
    /// The plan.
    pub run: CampaignRun,
    /// Its outcome.
    pub outcome: Outcome,
    /// A fault latched before the injection: a false trip.
    pub false_trip: bool,
    /// Some fault latched at or after the injection.
    pub detected: bool,
    /// Why the simulation stopped early, if it did (other than a fall).
    pub error: Option<String>,
    /// Where the gait was when the fault struck.
    pub struck_in: Option<Phase>,
    /// Per leg (left, right): it was the stance leg of a swing at or after
    /// the strike and before the fall, if any (a drive lost before that
    /// swing is lost in it too): what tells the run's fall.
    pub stance_after_strike: [bool; 2],
    /// The same, but only swings before the run's first stop crossed:
    /// what tells its stops crossed (a later swing cannot have taken a
    /// joint there).
    pub stance_before_stop: [bool; 2],
    /// Per leg (left, right): its foot carried the larger share of the body
    /// when the fault struck (the simulator's truth).
    pub carrying_at_strike: [bool; 2],
}

impl RunResult {
    /// A kind the supervisor must detect was not detected.
    pub fn missed(&self) -> bool {
        must_be_detected(self.run.fault.kind) && !self.detected
    }

    /// The named case this run's fall belongs to, if it fell in one.
    pub fn named_fall(&self) -> Option<NamedCase> {
        self.outcome.fell.as_ref().and_then(|_| {
            named_case(
                &self.run,
                self.struck_in,
                self.stance_after_strike,
                self.carrying_at_strike,
            )
            .filter(|_| self.drives_off_by(self.outcome.fell_s))
        })
    }

    /// Whether an e-stop run's drives were off (its safe state reached)
    /// by `at_s`, when what is told happened: the e-stop's cases rest on
    /// every drive disabled and braked, and in a swing the drives first set
    /// the foot down (`docs/safety.md`, "The e-stop in a swing"), which is
    /// the device's doing. True for every other kind.
    fn drives_off_by(&self, at_s: Option<f64>) -> bool {
        if !matches!(self.run.fault.kind, Kind::EStop | Kind::EStopRead) {
            return true;
        }
        let off_s = self
            .outcome
            .faults
            .iter()
            .filter(|f| matches!(f.code, FaultCode::EStopPressed | FaultCode::EStopInputFault))
            .filter_map(|f| f.safe_state_s)
            .reduce(f64::min);
        match (off_s, at_s) {
            (Some(off), Some(at)) => at >= off - 1e-9,
            _ => false,
        }
    }

    /// The pilot fell, and not in a named case: the device's to fix.
    pub fn unnamed_fall(&self) -> bool {
        self.outcome.fell.is_some() && self.named_fall().is_none()
    }

    /// A hip or knee crossed its stop.
    pub fn past_a_stop(&self) -> bool {
        self.outcome.worst_limit_margin_rad < 0.0
    }

    /// The named case whose physical reason took every joint that crossed
    /// a stop past it ([`explains_stop`]), if the run crossed one.
    pub fn named_stop(&self) -> Option<NamedCase> {
        let crossed = || {
            (0..4)
                .zip(self.outcome.limit_margins)
                .filter(|(_, (m, _))| *m < 0.0)
        };
        let named = named_case(
            &self.run,
            self.struck_in,
            self.stance_before_stop,
            self.carrying_at_strike,
        );
        named
            .filter(|_| self.past_a_stop())
            .filter(|_| self.drives_off_by(self.outcome.first_stop_crossed_s))
            .filter(|&c| {
                crossed().all(|(j, (_, flexion))| {
                    let o = &self.outcome;
                    let gave_all = o.resisted_at_limit.get(j) == Some(&true);
                    explains_stop(c, &self.run, j, flexion, gave_all)
                })
            })
    }

    /// A joint crossed its stop, and not for a named case's reason: the
    /// device's to fix.
    pub fn unnamed_stop(&self) -> bool {
        self.past_a_stop() && self.named_stop().is_none()
    }
}

/// Kinds every run must detect: those whose fault the table promises to
/// see whatever the gait is doing. (A glitch or a spike is tolerated by
/// design; a weak motor or a stuck bridge is found once its current departs
/// from its command, a frozen encoder while its joint is driven, the
/// pilot's lean through its consequences.)
pub fn must_be_detected(kind: Kind) -> bool {
    matches!(
        kind,
        Kind::EncoderBus
            | Kind::EncoderParity
            | Kind::EncoderErrorFlag
            | Kind::EncoderJump(_)
            | Kind::FsrOpen
            | Kind::FsrShort
            | Kind::AdcBus
            | Kind::PwmFail
            | Kind::CurrentOpen
            | Kind::CurrentShort
            | Kind::EStop
            | Kind::EStopRead
            | Kind::ButtonRead
            | Kind::Overrun(_)
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::play::no_outcome;
    use gait_control::layout::Side;

    /// A descent's e-stop run that fell (or crossed a knee's flexion stop)
    /// at `at_s`, its drives off at `off_s`.
    fn estop_run(at_s: f64, off_s: Option<f64>) -> RunResult {
        let mut outcome = no_outcome();
        outcome.fell = Some("fell: hip 0.400 m high".into());
        outcome.fell_s = Some(at_s);
        outcome.worst_limit_margin_rad = -0.01;
        outcome.worst_limit_joint = 1;
        outcome.limit_margins[1] = (-0.01, true);
        outcome.first_stop_crossed_s = Some(at_s);
        outcome.faults.push(crate::outcome::FaultOutcome {
            code: FaultCode::EStopPressed,
            injected_s: Some(2.0),
            detected_s: 2.0,
            latency_ticks: Some(0),
            reaction: gait_control::faults::Reaction::DisableMotors,
            channel: None,
            safe_state_s: off_s,
        });
        RunResult {
            run: CampaignRun {
                gait: Gait::StairDown,
                slot: 2,
                fault: "estop@2".parse().unwrap_or_else(|e| panic!("{e}")),
                noise_seed: 1,
            },
            outcome,
            false_trip: false,
            detected: true,
            error: None,
            struck_in: Some(Phase::Swing {
                stance: Side::Left,
                t_s: 0.5,
            }),
            stance_after_strike: [true, false],
            stance_before_stop: [true, false],
            carrying_at_strike: [true, false],
        }
    }

    #[test]
    fn an_e_stop_s_case_names_only_what_happened_once_the_drives_were_off() {
        // Off at 2.5 s (the swing foot set down first): a fall or a stop
        // crossed from then on is the case's, before it the device's.
        let after = estop_run(3.0, Some(2.5));
        assert_eq!(after.named_fall(), Some(NamedCase::DescentKneeWithoutDrive));
        assert_eq!(after.named_stop(), Some(NamedCase::DescentKneeWithoutDrive));
        let during = estop_run(2.3, Some(2.5));
        assert_eq!(during.named_fall(), None);
        assert!(during.unnamed_fall() && during.unnamed_stop());
        // Drives never off: the device's.
        assert!(estop_run(3.0, None).unnamed_fall());
    }
}
