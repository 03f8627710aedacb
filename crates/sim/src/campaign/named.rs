//! The falls `docs/campaign.md` names with their physical reason (issue 13's
//! exceptions to "no fall"), told from a run's plan and where the gait was
//! when its fault struck: what no reaction of these four drives, with
//! these sensors, can hold. Every other fall is the device's to fix.

use gait_control::layout::Side;
use gait_control::operator::Gait;
use gait_control::sequencer::Phase;

use crate::inject::{Kind, Target};

use super::CampaignRun;

/// A fall with a physical reason (docs/campaign.md, "Cases named with their
/// physical reason").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NamedCase {
    /// The pilot stops balancing or leans: the ankles are passive, so the
    /// body's balance over the feet is the pilot's arms on the crutches.
    Pilot,
    /// In a stair descent, a knee that carries the body bent loses its
    /// drive (stuck, weak, its bridge's PWM or direction pin, or every
    /// drive with the e-stop; a weak or stuck one also when it struck
    /// before the swing that loads it): braked, a bent loaded knee sinks at
    /// load / brake damping, and only a working drive holds it still.
    DescentKneeWithoutDrive,
    /// In a swing, the stance hip loses its drive or its encoder (or every
    /// drive with the e-stop, outside a descent): the torso
    /// rests on that hip alone until the other foot is down, and the board
    /// has no other sensor of the torso's pitch (no IMU). A drive lost
    /// before that swing (weak, or stuck on a set value) counts too: its
    /// deficit is a share of the torque asked, which standing or swinging
    /// that leg can keep under the current check's band (0x0405) and the
    /// residual's noise, so it is lost in the swing that first loads it.
    StanceHipInASwing,
}

impl NamedCase {
    /// Short name for the campaign's JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Pilot => "pilot",
            Self::DescentKneeWithoutDrive => "descent-knee-without-drive",
            Self::StanceHipInASwing => "stance-hip-in-a-swing",
        }
    }
}

/// The drive gives less than it is told, or nothing.
fn loses_drive(kind: Kind) -> bool {
    matches!(
        kind,
        Kind::MotorStuck | Kind::MotorWeak(_) | Kind::GearSlip(_) | Kind::PwmFail | Kind::DirFail
    )
}

/// The joint's angle is no longer read.
fn loses_encoder(kind: Kind) -> bool {
    matches!(
        kind,
        Kind::EncoderBus | Kind::EncoderParity | Kind::EncoderErrorFlag | Kind::EncoderStuck
    )
}

/// The named case of `run`'s fault (its falls and, through
/// [`explains_stop`], its stops crossed are told by it), given the phase
/// the gait was in when its fault struck (`None`: not known, or not
/// struck), which legs (left, right) were the stance leg of a swing at
/// or after it and before what is told (the fall, or the first stop
/// crossed: [`RunResult`](super::RunResult)), and which leg's foot carried
/// the larger share of the body when it struck.
pub fn named_case(
    run: &CampaignRun,
    struck_in: Option<Phase>,
    stance_after_strike: [bool; 2],
    carrying_at_strike: [bool; 2],
) -> Option<NamedCase> {
    let kind = run.fault.kind;
    if matches!(kind, Kind::PilotLean(_) | Kind::PilotStopsBalancing) {
        return Some(NamedCase::Pilot);
    }
    let swing_stance = match struck_in {
        Some(Phase::Swing { stance, .. }) => Some(stance),
        _ => None,
    };
    let joint = match run.fault.target {
        Some(Target::Joint(j)) => Some(j),
        _ => None,
    };
    let leg = joint.and_then(|j| {
        [Side::Left, Side::Right]
            .into_iter()
            .find(|s| s.has_joint(j))
    });
    let is_knee = joint.zip(leg).is_some_and(|(j, s)| j == s.hip() + 1);
    let is_hip = joint.zip(leg).is_some_and(|(j, s)| j == s.hip());
    // A weak or stuck drive shows only under load: one lost before the
    // swing that loads its leg is lost in that swing (a lost encoder or
    // output stage is found at once, and no step starts after it).
    let latent = matches!(
        kind,
        Kind::MotorStuck | Kind::MotorWeak(_) | Kind::GearSlip(_)
    ) && leg.is_some_and(|l| stance_after_strike.get(l.index()) == Some(&true));
    // The knee carries the body unless its own foot is in the air: the
    // stance leg's in a swing, or the swing leg's while its foot still
    // carries most of the body (a descent's trailing foot, on its toe on
    // the upper step, lowers the body on its bent knee through the first
    // part of the swing: 580–830 N of about 940).
    let carrying = leg.is_some_and(|l| carrying_at_strike.get(l.index()) == Some(&true));
    let knee_loaded = is_knee
        && (latent
            || struck_in.is_some()
                && (carrying || leg.is_some_and(|l| swing_stance.is_none_or(|s| s == l))));
    if run.gait == Gait::StairDown
        && (matches!(kind, Kind::EStop | Kind::EStopRead) || (loses_drive(kind) && knee_loaded))
    {
        return Some(NamedCase::DescentKneeWithoutDrive);
    }
    let stance_hip_lost =
        swing_stance.is_some() && swing_stance == leg && (loses_drive(kind) || loses_encoder(kind));
    if is_hip && (stance_hip_lost || latent) {
        return Some(NamedCase::StanceHipInASwing);
    }
    // The e-stop takes every drive, the stance hip's among them.
    if swing_stance.is_some() && matches!(kind, Kind::EStop | Kind::EStopRead) {
        return Some(NamedCase::StanceHipInASwing);
    }
    None
}

/// Whether `case` (the named case of `run`) is the physical reason for
/// its joint `joint` crossing its flexion (`flexion`) or extension stop,
/// the joint's drive having given all it has (`gave_all`: its full torque
/// against that stop when it crossed it, `Outcome::resisted_at_limit`):
/// the pilot's push may take any joint there; a descent's
/// braked loaded knee sinks onto its flexion stop (any knee for the
/// e-stop, which brakes them all; the faulted one otherwise), and the body
/// sinking with it loads the other bent knee past what its working drive
/// gives; a stance hip without its drive or encoder (any hip's flexion
/// stop with the e-stop, which brakes both) lets the torso turn on it.
/// (Another joint the torso's turn loads past what its drive gives is
/// not this case's: where the hold put the foot is the device's choice.)
pub fn explains_stop(
    case: NamedCase,
    run: &CampaignRun,
    joint: usize,
    flexion: bool,
    gave_all: bool,
) -> bool {
    let target = match run.fault.target {
        Some(Target::Joint(j)) => Some(j),
        _ => None,
    };
    let is_knee = joint == Side::Left.hip() + 1 || joint == Side::Right.hip() + 1;
    match case {
        NamedCase::Pilot => true,
        NamedCase::DescentKneeWithoutDrive => {
            is_knee
                && flexion
                && (matches!(run.fault.kind, Kind::EStop | Kind::EStopRead)
                    || target == Some(joint)
                    || gave_all)
        }
        NamedCase::StanceHipInASwing => {
            let is_hip = joint == Side::Left.hip() || joint == Side::Right.hip();
            target == Some(joint)
                || (is_hip && flexion && matches!(run.fault.kind, Kind::EStop | Kind::EStopRead))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inject::Injection;

    fn run(gait: Gait, kind: Kind, target: Option<Target>) -> CampaignRun {
        CampaignRun {
            gait,
            slot: crate::campaign::built_in_slot(gait),
            fault: Injection {
                kind,
                target,
                at_s: 2.0,
            },
            noise_seed: 1,
        }
    }

    const NONE_AFTER: [bool; 2] = [false; 2];

    /// The named case when neither foot carried more at the strike than
    /// its stance says.
    fn named(run: &CampaignRun, at: Option<Phase>, after: [bool; 2]) -> Option<NamedCase> {
        named_case(run, at, after, [false; 2])
    }

    const SWING_RIGHT: Option<Phase> = Some(Phase::Swing {
        stance: Side::Right,
        t_s: 0.5,
    });

    const SWING_LEFT: Option<Phase> = Some(Phase::Swing {
        stance: Side::Left,
        t_s: 0.5,
    });

    #[test]
    fn the_pilot_s_own_faults_are_named_whatever_the_phase() {
        let r = run(Gait::Walk, Kind::PilotStopsBalancing, None);
        assert_eq!(named(&r, None, NONE_AFTER), Some(NamedCase::Pilot));
        let r = run(Gait::StairUp, Kind::PilotLean(0.1), None);
        assert_eq!(named(&r, SWING_LEFT, NONE_AFTER), Some(NamedCase::Pilot));
    }

    #[test]
    fn a_descent_knee_is_named_only_for_a_lost_drive_on_a_loaded_knee() {
        let left_knee = Some(Target::Joint(1));
        let right_knee = Some(Target::Joint(3));
        let stuck = |t| run(Gait::StairDown, Kind::MotorStuck, t);
        // The stance knee in a swing; either knee standing.
        assert_eq!(
            named(&stuck(left_knee), SWING_LEFT, NONE_AFTER),
            Some(NamedCase::DescentKneeWithoutDrive)
        );
        assert_eq!(
            named(&stuck(right_knee), Some(Phase::Standing), NONE_AFTER),
            Some(NamedCase::DescentKneeWithoutDrive)
        );
        // Not the swing knee, not a lost encoder, not in another gait.
        assert_eq!(named(&stuck(right_knee), SWING_LEFT, NONE_AFTER), None);
        // Unless its leg then stands in a swing, which finds the drive.
        assert_eq!(
            named(&stuck(right_knee), SWING_LEFT, [true, true]),
            Some(NamedCase::DescentKneeWithoutDrive)
        );
        let output_stage = run(Gait::StairDown, Kind::PwmFail, right_knee);
        assert_eq!(named(&output_stage, SWING_LEFT, [true, true]), None);
        let blind = run(Gait::StairDown, Kind::EncoderStuck, left_knee);
        assert_eq!(named(&blind, SWING_LEFT, NONE_AFTER), None);
        let walk = run(Gait::Walk, Kind::MotorStuck, left_knee);
        assert_eq!(named(&walk, SWING_LEFT, NONE_AFTER), None);
        // The e-stop brakes every drive.
        let estop = run(Gait::StairDown, Kind::EStop, None);
        assert_eq!(
            named(&estop, Some(Phase::Standing), NONE_AFTER),
            Some(NamedCase::DescentKneeWithoutDrive)
        );
        assert_eq!(
            named(&run(Gait::Walk, Kind::EStop, None), None, NONE_AFTER),
            None
        );
    }

    #[test]
    fn a_descent_swing_knee_is_loaded_while_its_foot_carries_the_body() {
        let right_knee = Some(Target::Joint(3));
        let right_carries = [false, true];
        for kind in [Kind::MotorStuck, Kind::PwmFail, Kind::MotorWeak(0.5)] {
            let r = run(Gait::StairDown, kind, right_knee);
            assert_eq!(
                named_case(&r, SWING_LEFT, NONE_AFTER, right_carries),
                Some(NamedCase::DescentKneeWithoutDrive)
            );
            // Once the stance foot has the body, the swing knee is not it.
            assert_eq!(named_case(&r, SWING_LEFT, NONE_AFTER, [true, false]), None);
        }
        // Its encoder lost: the drive works, not this case.
        let blind = run(Gait::StairDown, Kind::EncoderParity, right_knee);
        assert_eq!(
            named_case(&blind, SWING_LEFT, NONE_AFTER, right_carries),
            None
        );
        // Nor a walk's or an ascent's.
        let walk = run(Gait::Walk, Kind::MotorStuck, right_knee);
        assert_eq!(
            named_case(&walk, SWING_LEFT, NONE_AFTER, right_carries),
            None
        );
    }

    #[test]
    fn a_stance_hip_is_named_only_in_a_swing_for_a_lost_drive_or_encoder() {
        let left_hip = Some(Target::Joint(0));
        for kind in [Kind::MotorWeak(0.5), Kind::PwmFail, Kind::EncoderParity] {
            let r = run(Gait::StairUp, kind, left_hip);
            assert_eq!(
                named(&r, SWING_LEFT, NONE_AFTER),
                Some(NamedCase::StanceHipInASwing)
            );
            // Both feet down, the other leg holds the torso.
            assert_eq!(named(&r, Some(Phase::Standing), NONE_AFTER), None);
        }
        // The swing hip, or a jump (the encoder still reads).
        let swing_hip = run(Gait::StairUp, Kind::MotorWeak(0.5), Some(Target::Joint(2)));
        assert_eq!(named(&swing_hip, SWING_LEFT, NONE_AFTER), None);
        let jump = run(Gait::StairUp, Kind::EncoderJump(200), left_hip);
        assert_eq!(named(&jump, SWING_LEFT, NONE_AFTER), None);
    }

    #[test]
    fn a_hip_drive_lost_before_the_swing_that_loads_it_is_a_stance_hip_in_a_swing() {
        let left_hip = Some(Target::Joint(0));
        let left_stance_later = [true, false];
        // Weak or stuck while standing, or while it swung its own leg.
        for kind in [Kind::MotorWeak(0.5), Kind::MotorStuck] {
            let r = run(Gait::Walk, kind, left_hip);
            for at in [Some(Phase::Standing), SWING_RIGHT] {
                assert_eq!(
                    named(&r, at, left_stance_later),
                    Some(NamedCase::StanceHipInASwing)
                );
                // No swing on it came: not this case.
                assert_eq!(named(&r, at, [false, true]), None);
            }
        }
        // A lost encoder or output stage is found at once, the knee is not
        // the torso's joint.
        for (kind, target) in [
            (Kind::EncoderBus, left_hip),
            (Kind::PwmFail, left_hip),
            (Kind::MotorWeak(0.5), Some(Target::Joint(1))),
        ] {
            let r = run(Gait::Walk, kind, target);
            assert_eq!(named(&r, Some(Phase::Standing), left_stance_later), None);
        }
    }

    #[test]
    fn a_named_case_explains_only_the_stops_its_reason_reaches() {
        use NamedCase::*;
        let pilot = run(Gait::Walk, Kind::PilotLean(0.1), None);
        assert!(explains_stop(Pilot, &pilot, 0, false, false));
        // The e-stop: any knee's flexion stop, no hip, no extension.
        let estop = run(Gait::StairDown, Kind::EStop, None);
        assert!(explains_stop(
            DescentKneeWithoutDrive,
            &estop,
            3,
            true,
            false
        ));
        assert!(!explains_stop(
            DescentKneeWithoutDrive,
            &estop,
            3,
            false,
            false
        ));
        assert!(!explains_stop(
            DescentKneeWithoutDrive,
            &estop,
            2,
            true,
            true
        ));
        // A drive lost: that knee, and the other one only when its own
        // drive gave all it has, not when a fault braked it.
        let stuck = run(Gait::StairDown, Kind::MotorStuck, Some(Target::Joint(1)));
        assert!(explains_stop(
            DescentKneeWithoutDrive,
            &stuck,
            1,
            true,
            false
        ));
        assert!(!explains_stop(
            DescentKneeWithoutDrive,
            &stuck,
            3,
            true,
            false
        ));
        assert!(explains_stop(
            DescentKneeWithoutDrive,
            &stuck,
            3,
            true,
            true
        ));
        // A stance hip: that hip, either stop.
        let hip = run(Gait::StairUp, Kind::MotorWeak(0.5), Some(Target::Joint(0)));
        assert!(explains_stop(StanceHipInASwing, &hip, 0, true, false));
        assert!(explains_stop(StanceHipInASwing, &hip, 0, false, false));
        // No other joint, even one whose drive gave all it has: where the
        // hold put the foot that loads it is the device's choice.
        assert!(!explains_stop(StanceHipInASwing, &hip, 1, false, false));
        assert!(!explains_stop(StanceHipInASwing, &hip, 3, false, true));
        // The e-stop in a swing: either hip's flexion stop (both braked),
        // no knee, no extension.
        let estop = run(Gait::StairUp, Kind::EStopRead, None);
        assert!(explains_stop(StanceHipInASwing, &estop, 0, true, false));
        assert!(explains_stop(StanceHipInASwing, &estop, 2, true, false));
        assert!(!explains_stop(StanceHipInASwing, &estop, 2, false, false));
        assert!(!explains_stop(StanceHipInASwing, &estop, 1, true, false));
    }

    #[test]
    fn an_e_stop_in_a_swing_is_the_stance_hip_s_case_but_in_a_descent() {
        for gait in [Gait::Walk, Gait::StairUp] {
            for kind in [Kind::EStop, Kind::EStopRead] {
                let r = run(gait, kind, None);
                assert_eq!(
                    named(&r, SWING_LEFT, NONE_AFTER),
                    Some(NamedCase::StanceHipInASwing)
                );
                // Standing or in a transfer both feet carry the torso.
                assert_eq!(named(&r, Some(Phase::Standing), NONE_AFTER), None);
            }
        }
        let descent = run(Gait::StairDown, Kind::EStop, None);
        assert_eq!(
            named(&descent, SWING_LEFT, NONE_AFTER),
            Some(NamedCase::DescentKneeWithoutDrive)
        );
    }
}
