//! Anthropometry's tests: the model for the paper's pilot against Table III,
//! and properties over the accepted range of pilots.

extern crate std;

use super::*;
use proptest::prelude::*;

fn rel(a: f64, b: f64) -> f64 {
    (a - b) / b
}

/// A pilot of `height_m` and `mass_kg`.
fn pilot(height_m: f64, mass_kg: f64) -> Pilot<f64> {
    Pilot { height_m, mass_kg }
}

/// Table III lengths and masses within 10 % for the paper's pilot; the
/// numbers printed here are the ones quoted in docs/anthropometry.md
/// (`cargo test -p gait-core anthropometry -- --nocapture`).
#[test]
fn reproduces_table_iii_lengths_and_masses() -> Result<(), AnthropometryError> {
    let model = body_model_for(&Pilot::<f64>::paper(), &ExoSegments::paper_default())?;
    let ours = model.links();
    let paper = BodyModel::<f64>::paper_table_iii();
    let theirs = paper.links();
    // Length, centre of mass, mass, inertia: ours against Table III's.
    let figures = |l: &Link<f64>| [l.length_m, l.com_m, l.mass_kg, l.inertia_kgm2];
    for i in 0..LINKS {
        let columns: std::vec::Vec<std::string::String> = ["l", "d", "m", "I"]
            .iter()
            .zip(figures(&ours[i]).iter().zip(figures(&theirs[i])))
            .map(|(name, (&a, b))| {
                std::format!("{name} {a:.4} vs {b:.3} ({:+.1} %)", 100.0 * rel(a, b))
            })
            .collect();
        std::println!("link {}: {}", i + 1, columns.join(", "));
    }
    // Leg lengths within 10 %.
    for i in [0, 1, 3, 4] {
        assert!(
            rel(ours[i].length_m, theirs[i].length_m).abs() < 0.10,
            "l{}",
            i + 1
        );
    }
    // The torso's length is a convention (TorsoSpan); hip to vertex is
    // within 16 % of Table III, hip to shoulder 30 % short.
    assert!(rel(ours[2].length_m, theirs[2].length_m).abs() < 0.16);
    // Masses within 10 % of each link (Table III's legs differ by 1 kg
    // between stance and swing; ours are mirrored).
    for i in 0..LINKS {
        assert!(
            rel(ours[i].mass_kg, theirs[i].mass_kg).abs() < 0.10,
            "m{}",
            i + 1
        );
    }
    // Totals: 76.5 + 17 = 93.5 kg (the paper's text), Table III sums to 92.8.
    assert!((model.total_mass_kg() - 93.5).abs() < 1e-9);
    // Hip height standing, ankle to hip: 0.491 H = 0.859 m vs 0.836 m.
    let hip = ours[0].length_m + ours[1].length_m;
    assert!(rel(hip, 0.836).abs() < 0.03);
    Ok(())
}

#[test]
fn hip_to_shoulder_option() -> Result<(), AnthropometryError> {
    let opts = Options {
        torso: TorsoSpan::HipToShoulder,
        ..Options::default()
    };
    let m = body_model_with(&Pilot::<f64>::paper(), &ExoSegments::paper_default(), &opts)?;
    assert!((m.links()[2].length_m - 0.288 * 1.75).abs() < 1e-12);
    // Same dynamics-relevant torso properties as the default span, apart
    // from the default exo inertia (a rod over the link).
    let d = body_model_for(&Pilot::<f64>::paper(), &ExoSegments::paper_default())?;
    assert!((m.links()[2].com_m - d.links()[2].com_m).abs() < 1e-12);
    assert!((m.links()[2].mass_kg - d.links()[2].mass_kg).abs() < 1e-12);
    Ok(())
}

#[test]
fn pilot_alone_matches_winter_by_hand() -> Result<(), AnthropometryError> {
    let p = pilot(1.80, 80.0);
    let m = body_model_for(&p, &ExoSegments::none())?;
    let l = m.links();
    // Thigh: 0.245 H, 0.100 M, COM 0.433 l from the hip, k = 0.323 l.
    let lt: f64 = 0.245 * 1.80;
    assert!((l[3].length_m - lt).abs() < 1e-12);
    assert!((l[3].mass_kg - 8.0).abs() < 1e-12);
    assert!((l[3].com_m - 0.433 * lt).abs() < 1e-12);
    assert!((l[3].inertia_kgm2 - 8.0 * (0.323 * lt).powi(2)).abs() < 1e-12);
    assert!((l[1].com_m - 0.567 * lt).abs() < 1e-12);
    // Shank: leg 0.0465 M plus foot 0.0145 M at the ankle.
    let ls: f64 = 0.246 * 1.80;
    let (ml, mf): (f64, f64) = (0.0465 * 80.0, 0.0145 * 80.0);
    let d = (ml * 0.433 * ls + mf * ls) / (ml + mf);
    let i = ml * (0.302 * ls).powi(2)
        + ml * (0.433 * ls - d).powi(2)
        + mf * (0.475 * 0.152 * 1.80_f64).powi(2)
        + mf * (ls - d).powi(2);
    assert!((l[4].mass_kg - 0.061 * 80.0).abs() < 1e-12);
    assert!((l[4].com_m - d).abs() < 1e-12);
    assert!((l[0].com_m - (ls - d)).abs() < 1e-12);
    assert!((l[4].inertia_kgm2 - i).abs() < 1e-12);
    // HAT: 0.678 M, COM 0.626 × 0.288 H from the hip, k = 0.496 × 0.288 H.
    let lh: f64 = 0.288 * 1.80;
    assert!((l[2].mass_kg - 0.678 * 80.0).abs() < 1e-9);
    assert!((l[2].com_m - 0.626 * lh).abs() < 1e-12);
    assert!((l[2].inertia_kgm2 - 0.678 * 80.0 * (0.496 * lh).powi(2)).abs() < 1e-9);
    // The table's fractions sum to the whole body.
    assert!((m.total_mass_kg() - 80.0).abs() < 1e-9);
    Ok(())
}

#[test]
fn exo_parallel_axis_by_hand() -> Result<(), AnthropometryError> {
    let p = pilot(1.75, 70.0);
    let exo = ExoSegments {
        torso: ExoSegment::of_mass(0.0),
        thigh: ExoSegment {
            mass_kg: 3.0,
            com_m: Some(0.30),
            inertia_kgm2: Some(0.05),
        },
        shank: ExoSegment::of_mass(0.0),
    };
    let m = body_model_for(&p, &exo)?;
    let lt: f64 = 0.245 * 1.75;
    let (mh, dh, ih): (f64, f64, f64) = (7.0, 0.433 * lt, 7.0 * (0.323 * lt).powi(2));
    let d = (mh * dh + 3.0 * 0.30) / 10.0;
    let i = ih + mh * (dh - d).powi(2) + 0.05 + 3.0 * (0.30 - d).powi(2);
    let t = m.links()[3];
    assert!((t.mass_kg - 10.0).abs() < 1e-12);
    assert!((t.com_m - d).abs() < 1e-12);
    assert!((t.inertia_kgm2 - i).abs() < 1e-12);
    // Stance thigh: same body measured from the knee.
    assert!((m.links()[1].com_m - (lt - d)).abs() < 1e-12);
    Ok(())
}

#[test]
fn rejects_bad_input() {
    let exo = ExoSegments::<f64>::paper_default();
    let bad = |h: f64, m: f64| body_model_for(&pilot(h, m), &exo);
    use AnthropometryError as E;
    assert_eq!(bad(f64::NAN, 70.0), Err(E::NonFiniteHeight));
    assert_eq!(bad(1.7, f64::INFINITY), Err(E::NonFiniteMass));
    assert_eq!(bad(0.0, 70.0), Err(E::NonPositiveHeight));
    assert_eq!(bad(1.7, -1.0), Err(E::NonPositiveMass));
    assert_eq!(bad(1.1, 70.0), Err(E::ImplausibleHeight));
    assert_eq!(bad(2.3, 70.0), Err(E::ImplausibleHeight));
    assert_eq!(bad(1.7, 29.0), Err(E::ImplausibleMass));
    assert_eq!(bad(1.7, 201.0), Err(E::ImplausibleMass));
    let p = Pilot::<f64>::paper();
    let mut e = exo;
    e.thigh.mass_kg = -1.0;
    assert_eq!(
        body_model_for(&p, &e),
        Err(E::ExoNegative {
            part: ExoPart::Thigh
        })
    );
    let mut e = exo;
    e.shank.com_m = Some(0.9);
    assert_eq!(
        body_model_for(&p, &e),
        Err(E::ExoComOutsideLink {
            part: ExoPart::Shank
        })
    );
    let mut e = exo;
    e.torso.inertia_kgm2 = Some(f64::NAN);
    assert_eq!(
        body_model_for(&p, &e),
        Err(E::ExoNonFinite {
            part: ExoPart::Torso
        })
    );
}

#[test]
fn f32_matches_f64() -> Result<(), AnthropometryError> {
    let a = body_model_for(&Pilot::<f32>::paper(), &ExoSegments::paper_default())?;
    let b = body_model_for(&Pilot::<f64>::paper(), &ExoSegments::paper_default())?;
    for (x, y) in a.links().iter().zip(b.links()) {
        assert!((f64::from(x.mass_kg) - y.mass_kg).abs() < 1e-4);
        assert!((f64::from(x.inertia_kgm2) - y.inertia_kgm2).abs() < 1e-5);
    }
    Ok(())
}

fn exo_strategy() -> impl Strategy<Value = ExoSegments<f64>> {
    (0.0..15.0_f64, 0.0..6.0_f64, 0.0..4.0_f64).prop_map(|(t, th, s)| ExoSegments {
        torso: ExoSegment::of_mass(t),
        thigh: ExoSegment::of_mass(th),
        shank: ExoSegment::of_mass(s),
    })
}

proptest! {
    #[test]
    fn any_valid_pilot_builds_a_valid_model(
        h in MIN_HEIGHT_M..=MAX_HEIGHT_M,
        m in MIN_MASS_KG..=MAX_MASS_KG,
        exo in exo_strategy(),
        shoulder in any::<bool>(),
    ) {
        let torso = if shoulder { TorsoSpan::HipToShoulder } else { TorsoSpan::HipToVertex };
        let opts = Options { torso, ..Options::default() };
        let model = body_model_with(&pilot(h, m), &exo, &opts);
        prop_assert!(model.is_ok(), "{:?}", model);
        let model = model.map_err(|e| TestCaseError::fail(std::format!("{e}")))?;
        // Passes BodyModel::new again (the builder went through it).
        prop_assert!(BodyModel::new(*model.links(), *model.limits()).is_ok());
        let expected = m + exo.total_mass_kg();
        prop_assert!((model.total_mass_kg() - expected).abs() < 1e-9 * expected);
    }

    #[test]
    fn default_exo_total_is_pilot_plus_17_kg(
        h in MIN_HEIGHT_M..=MAX_HEIGHT_M,
        m in MIN_MASS_KG..=MAX_MASS_KG,
    ) {
        let model = body_model_for(&pilot(h, m), &ExoSegments::paper_default()).map_err(|e| TestCaseError::fail(std::format!("{e}")))?;
        prop_assert!((model.total_mass_kg() - (m + 17.0)).abs() < 1e-9);
    }
}
