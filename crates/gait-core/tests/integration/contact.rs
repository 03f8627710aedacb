//! gait-core's one dynamics API: the contact is an argument, and forward
//! dynamics undo the inverse on either contact.

use gait_core::BodyModel;
use gait_core::dynamics::Contact::{FixedAnkle, ToeRocker};
use gait_core::dynamics::{energy, forward_dynamics, inverse_dynamics};
use gait_core::foot::StanceFoot;

/// A foot whose heel never lifts is the paper's pinned ankle, and the
/// forward dynamics undo the inverse on either.
#[test]
fn the_foot_is_an_input_and_forward_undoes_inverse() {
    let m = BodyModel::<f64>::paper_table_iii();
    let (q, w, a) = (
        [0.21, -0.18, 0.07, 2.71, 3.52],
        [0.4, -0.9, 0.2, -2.1, 3.3],
        [1.5, -2.0, 0.7, 6.0, -9.0],
    );
    let never = StanceFoot::device(10.0);
    let on_toe = StanceFoot::device(0.1);
    let pinned = inverse_dynamics(&m, &FixedAnkle, &q, &w, &a);
    assert_eq!(inverse_dynamics(&m, &ToeRocker(never), &q, &w, &a), pinned);
    let rolling = inverse_dynamics(&m, &ToeRocker(on_toe), &q, &w, &a);
    assert!(
        rolling
            .iter()
            .zip(&pinned)
            .any(|(r, p)| (r - p).abs() > 1e-3)
    );
    for contact in [FixedAnkle, ToeRocker(on_toe)] {
        let t = inverse_dynamics(&m, &contact, &q, &w, &a);
        let back = forward_dynamics(&m, &contact, &q, &w, &t).unwrap();
        for (b, x) in back.iter().zip(&a) {
            assert!((b - x).abs() < 1e-9, "{back:?}");
        }
    }
    assert_eq!(
        energy(&m, &ToeRocker(never), &q, &w),
        energy(&m, &FixedAnkle, &q, &w)
    );
}

/// Holding a posture at rest: the statics alone are the inverse dynamics
/// with zero rates, bit for bit but for the sign of a zero, on either
/// contact, with the heel down and up, in the board's f32.
#[test]
fn statics_are_the_inverse_dynamics_at_rest() {
    use gait_core::dynamics::{inverse_dynamics_at, static_torques_at};
    use gait_core::kinematics::Posture;
    let m: BodyModel<f32> = BodyModel::<f64>::paper_table_iii().cast();
    let zero = [0.0f32; 5];
    let mut seed = 7u32;
    let mut next = || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
    };
    for _ in 0..500 {
        let phi = [
            0.6 * next(),
            -0.3 + 0.8 * next(),
            0.4 * next(),
            2.9 + 0.6 * next(),
            3.3 + 0.6 * next(),
        ];
        let posture = Posture::new(&phi);
        for contact in [FixedAnkle, ToeRocker(StanceFoot::device(0.1))] {
            let full = inverse_dynamics_at(&m, &contact, &posture, &zero, &zero);
            let held = static_torques_at(&m, &contact, &posture);
            for (a, b) in full.iter().zip(&held) {
                assert!(a == b, "{phi:?}: {full:?} against {held:?}");
            }
        }
    }
}
