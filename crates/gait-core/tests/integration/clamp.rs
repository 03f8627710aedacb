//! The panic-free clamp agrees with `f32::clamp` wherever that one is
//! defined, and does not panic where it would.

use gait_core::scalar::clamp_f32;

#[test]
fn agrees_with_the_standard_clamp_on_ordered_bounds() {
    let xs = [
        -1e9,
        -3.0,
        -1.0,
        -0.5,
        0.0,
        0.25,
        1.0,
        2.5,
        1e9,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ];
    for &x in &xs {
        for (lo, hi) in [(-1.0, 1.0), (0.0, 0.0), (-2.5, 0.3), (0.3, 7.0)] {
            assert_eq!(clamp_f32(x, lo, hi), x.clamp(lo, hi), "x {x}, [{lo}, {hi}]");
        }
    }
    assert!(clamp_f32(f32::NAN, -1.0, 1.0).is_nan());
}

#[test]
fn crossed_or_nan_bounds_give_a_value_not_a_panic() {
    assert_eq!(clamp_f32(5.0, 1.0, -1.0), -1.0);
    assert_eq!(clamp_f32(-5.0, 1.0, -1.0), 1.0);
    assert_eq!(clamp_f32(0.5, f32::NAN, 1.0), 0.5);
    assert_eq!(clamp_f32(2.0, f32::NAN, 1.0), 1.0);
}
