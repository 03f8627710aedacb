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
