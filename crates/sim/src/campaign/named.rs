//! The falls `docs/safety.md` names with their physical reason (issue 13's
//! exceptions to "no fall"), told from a run's plan and where the gait was
//! when its fault struck: what no reaction of these four drives, with
//! these sensors, can hold. Every other fall is the device's to fix.

use gait_control::layout::Side;
use gait_control::operator::Gait;
use gait_control::sequencer::Phase;

use crate::inject::{Kind, Target};

use super::CampaignRun;

/// A fall with a physical reason (docs/safety.md, "Cases named with their
/// physical reason").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NamedCase {
    /// The pilot stops balancing or leans: the ankles are passive, so the
    /// body's balance over the feet is the pilot's arms on the crutches.
    Pilot,
    /// In a stair descent, a knee that carries the body bent loses its
    /// drive (stuck, weak, its bridge's PWM or direction pin, or every
    /// drive with the e-stop): braked, a bent loaded knee sinks at load /
    /// brake damping, and only a working drive holds it still.
    DescentKneeWithoutDrive,
    /// In a swing, the stance hip loses its drive or its encoder: the torso
    /// rests on that hip alone until the other foot is down, and the board
    /// has no other sensor of the torso's pitch (no IMU).
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
        Kind::MotorStuck | Kind::MotorWeak(_) | Kind::PwmFail | Kind::DirFail
    )
}

/// The joint's angle is no longer read.
fn loses_encoder(kind: Kind) -> bool {
    matches!(
        kind,
        Kind::EncoderBus | Kind::EncoderParity | Kind::EncoderErrorFlag | Kind::EncoderStuck
    )
}

/// The named case a fall of `run` belongs to, given the phase the gait was
/// in when its fault struck (`None`: not known, or not struck).
pub fn named_case(run: &CampaignRun, struck_in: Option<Phase>) -> Option<NamedCase> {
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
    // The knee carries the body unless its own foot is in the air.
    let knee_loaded =
        is_knee && struck_in.is_some() && leg.is_some_and(|l| swing_stance.is_none_or(|s| s == l));
    if run.gait == Gait::StairDown
        && (matches!(kind, Kind::EStop | Kind::EStopRead) || (loses_drive(kind) && knee_loaded))
    {
        return Some(NamedCase::DescentKneeWithoutDrive);
    }
    if is_hip
        && swing_stance.is_some()
        && swing_stance == leg
        && (loses_drive(kind) || loses_encoder(kind))
    {
        return Some(NamedCase::StanceHipInASwing);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inject::Injection;

    fn run(gait: Gait, kind: Kind, target: Option<Target>) -> CampaignRun {
        CampaignRun {
            gait,
            fault: Injection {
                kind,
                target,
                at_s: 2.0,
            },
            noise_seed: 1,
        }
    }

    const SWING_LEFT: Option<Phase> = Some(Phase::Swing {
        stance: Side::Left,
        t_s: 0.5,
    });

    #[test]
    fn the_pilot_s_own_faults_are_named_whatever_the_phase() {
        let r = run(Gait::Walk, Kind::PilotStopsBalancing, None);
        assert_eq!(named_case(&r, None), Some(NamedCase::Pilot));
        let r = run(Gait::StairUp, Kind::PilotLean(0.1), None);
        assert_eq!(named_case(&r, SWING_LEFT), Some(NamedCase::Pilot));
    }

    #[test]
    fn a_descent_knee_is_named_only_for_a_lost_drive_on_a_loaded_knee() {
        let left_knee = Some(Target::Joint(1));
        let right_knee = Some(Target::Joint(3));
        let stuck = |t| run(Gait::StairDown, Kind::MotorStuck, t);
        // The stance knee in a swing; either knee standing.
        assert_eq!(
            named_case(&stuck(left_knee), SWING_LEFT),
            Some(NamedCase::DescentKneeWithoutDrive)
        );
        assert_eq!(
            named_case(&stuck(right_knee), Some(Phase::Standing)),
            Some(NamedCase::DescentKneeWithoutDrive)
        );
        // Not the swing knee, not a lost encoder, not in another gait.
        assert_eq!(named_case(&stuck(right_knee), SWING_LEFT), None);
        let blind = run(Gait::StairDown, Kind::EncoderStuck, left_knee);
        assert_eq!(named_case(&blind, SWING_LEFT), None);
        let walk = run(Gait::Walk, Kind::MotorStuck, left_knee);
        assert_eq!(named_case(&walk, SWING_LEFT), None);
        // The e-stop brakes every drive.
        let estop = run(Gait::StairDown, Kind::EStop, None);
        assert_eq!(
            named_case(&estop, Some(Phase::Standing)),
            Some(NamedCase::DescentKneeWithoutDrive)
        );
        assert_eq!(named_case(&run(Gait::Walk, Kind::EStop, None), None), None);
    }

    #[test]
    fn a_stance_hip_is_named_only_in_a_swing_for_a_lost_drive_or_encoder() {
        let left_hip = Some(Target::Joint(0));
        for kind in [Kind::MotorWeak(0.5), Kind::PwmFail, Kind::EncoderParity] {
            let r = run(Gait::StairUp, kind, left_hip);
            assert_eq!(
                named_case(&r, SWING_LEFT),
                Some(NamedCase::StanceHipInASwing)
            );
            // Both feet down, the other leg holds the torso.
            assert_eq!(named_case(&r, Some(Phase::Standing)), None);
        }
        // The swing hip, or a jump (the encoder still reads).
        let swing_hip = run(Gait::StairUp, Kind::MotorWeak(0.5), Some(Target::Joint(2)));
        assert_eq!(named_case(&swing_hip, SWING_LEFT), None);
        let jump = run(Gait::StairUp, Kind::EncoderJump(200), left_hip);
        assert_eq!(named_case(&jump, SWING_LEFT), None);
    }
}
