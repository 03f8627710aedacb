//! Runs of the 10,000-run campaign (`cargo xtask faults --runs 10000
//! --seed 1`) in which a sensing fault would drop the pilot if control
//! acted on the stale or false reading, replayed as the campaign plays them
//! (the same gait, fault, time and sensor noise). Each stands
//! (docs/safety.md, "Choices and why" and "Swing").

use gait_control::faults::FaultCode;
use gait_control::operator::Gait;

use crate::common::campaign_run;

/// The stance ankle's encoder lost in a stair descent's swing, with the
/// foot in the air: the step finishes (0x0207) and lands on it. Its held
/// reading is the swing's, 0.3 rad off the landing's lean; a static
/// feed-forward built on it would be wrong by some 60 N·m at the knee, the
/// torque residual (0x0404) would brake the knee and the body sink onto
/// it. So the lean comes through the closed chain or from the plan.
#[test]
fn a_lost_ankle_encoder_leaves_the_stair_descent_standing() {
    for (fault, seed) in [
        ("encoder-bus:left-ankle@4.095", 808_419),
        ("encoder-parity:left-ankle@4.248", 122_854),
        ("encoder-error-flag:left-ankle@4.003", 95_741),
    ] {
        let r = campaign_run(Gait::StairDown, fault, seed);
        let o = &r.outcome;
        assert_eq!(o.fell, None, "{fault}");
        assert!(r.detected && !r.false_trip && r.error.is_none(), "{fault}");
        assert_eq!(
            o.faults.first().map(|f| f.code),
            Some(FaultCode::AnkleEncoder),
            "{fault}"
        );
        assert!(
            o.faults.iter().all(|f| f.code != FaultCode::MotorResponse),
            "{fault}: {:?}",
            o.faults
        );
        assert!(o.worst_limit_margin_rad > 0.0, "{fault}");
    }
}

/// A 3 ms force spike on the swing foot late in a swing: taken as the
/// landing, it would swap the legs with the foot in the air and tip the
/// torso over the leg just left. A landing is contact held 8 ms, so the
/// step lands when the foot does, and nothing faults.
#[test]
fn a_force_spike_late_in_a_swing_is_not_taken_for_the_landing() {
    for (gait, fault, seed) in [
        (Gait::StairUp, "fsr-spike=397.3:right-foot@2.974", 168_797),
        (Gait::StairUp, "fsr-spike=204.9:right-foot@3.184", 890_305),
        (Gait::Walk, "fsr-spike=261.6:right-foot@3.429", 527_790),
    ] {
        let r = campaign_run(gait, fault, seed);
        let o = &r.outcome;
        assert_eq!(o.fell, None, "{fault}");
        assert!(o.faults.is_empty(), "{fault}: {:?}", o.faults);
        assert!(o.landings >= 2, "{fault}: {} landings", o.landings);
    }
}

/// An ankle encoder stuck at toe-off in a stair descent: it reads the
/// dorsiflexion stop through the whole swing, and taken for the landing's
/// lean when its foot lands (a heel up on the stop), the stuck reading
/// would make the feed-forward hold a posture 0.3 rad off and the body
/// sink. Only the ground holds an ankle on its stop: read there,
/// unchanged, with the foot surely in the air, the encoder is stuck
/// (0x0207, the step finishes), control stops taking it, and the landing's
/// lean comes through the closed chain or from the plan.
#[test]
fn an_ankle_encoder_stuck_at_toe_off_is_found_in_the_air() {
    for (fault, seed) in [
        ("encoder-stuck:left-ankle@3.841", 954_929),
        ("encoder-stuck:left-ankle@3.59", 64_989),
    ] {
        let r = campaign_run(Gait::StairDown, fault, seed);
        let o = &r.outcome;
        assert_eq!(o.fell, None, "{fault}");
        assert!(!r.false_trip && r.error.is_none(), "{fault}");
        let first = o.faults.first().expect("detected");
        assert_eq!(first.code, FaultCode::AnkleEncoder, "{fault}");
        // Found in the swing after the stuck one (the foot lifts late in
        // a descent), before the landing it would have spoilt.
        assert!(first.detected_s < 6.0, "{fault}: {first:?}");
        assert!(
            o.faults.iter().all(|f| f.code != FaultCode::MotorResponse),
            "{fault}: {:?}",
            o.faults
        );
        assert!(o.worst_limit_margin_rad > 0.0, "{fault}");
    }
}
