//! The clinic's workflow through the built `exogait` binary: fit a patient,
//! design a gait family into a bundle, list it, play its gaits in the
//! closed loop; and every bad input refused with exit status 2.

use std::path::PathBuf;

use serde_json::Value;

use crate::common::{exogait, s};

fn dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn fit_writes_the_model_and_refuses_what_the_device_cannot_fit() {
    let d = dir("fit");
    let out = d.join("p.json");
    let r = exogait(&[
        "fit",
        "--height",
        "1.75",
        "--mass",
        "75",
        "--thigh",
        "0.43",
        "--out",
        s(&out),
    ]);
    assert_eq!(r.status, 0, "{}", r.stderr);
    let file: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let printed: Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(file, printed);
    assert_eq!(file["thigh_m"], 0.43);
    assert_eq!(file["measured"], serde_json::json!(["thigh"]));
    // Winter's proportion where not measured.
    assert!((file["shank_m"].as_f64().unwrap() - 0.246 * 1.75).abs() < 1e-9);
    // The exoskeleton's 17 kg on top of the pilot.
    assert!((file["total_mass_kg"].as_f64().unwrap() - 92.0).abs() < 1e-6);
    assert_eq!(file["links"].as_array().unwrap().len(), 5);
    for (bad, why) in [
        (vec!["--height", "1.40", "--mass", "60"], "height"),
        (vec!["--height", "2.05", "--mass", "60"], "height"),
        (vec!["--height", "1.70", "--mass", "39"], "mass"),
        (vec!["--height", "1.70", "--mass", "121"], "mass"),
        (
            vec!["--height", "1.70", "--mass", "70", "--shank", "0.60"],
            "shank",
        ),
        (
            vec!["--height", "1.70", "--mass", "70", "--foot", "-0.2"],
            "foot",
        ),
    ] {
        let bad_out = d.join("bad.json");
        let mut args = vec!["fit"];
        args.extend(bad);
        args.extend(["--out", s(&bad_out)]);
        let r = exogait(&args);
        assert_eq!(r.status, 2, "{args:?}");
        assert!(r.stderr.contains(why), "{args:?}: {}", r.stderr);
        assert!(!bad_out.exists(), "{args:?} wrote a file");
    }
}

#[test]
fn a_patient_file_edited_by_hand_is_refused() {
    let d = dir("edited");
    let p = d.join("p.json");
    assert_eq!(
        exogait(&["fit", "--height", "1.6", "--mass", "55", "--out", s(&p)]).status,
        0
    );
    let text = std::fs::read_to_string(&p).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    v["links"][2]["mass_kg"] = serde_json::json!(10.0);
    std::fs::write(&p, v.to_string()).unwrap();
    let r = exogait(&[
        "tables",
        "--patient",
        s(&p),
        "--out",
        s(&d.join("b.bundle")),
    ]);
    assert_eq!(r.status, 2);
    assert!(r.stderr.contains("exogait fit"), "{}", r.stderr);
}

#[test]
fn a_family_is_designed_listed_played_and_guarded() {
    let d = dir("family");
    let p = d.join("p.json");
    let b = d.join("p.bundle");
    assert_eq!(
        exogait(&["fit", "--height", "1.6", "--mass", "55", "--out", s(&p)]).status,
        0
    );
    // One brisk walk and one stair the drives cannot climb for anyone.
    let r = exogait(&[
        "tables",
        "--patient",
        s(&p),
        "--out",
        s(&b),
        "--paces",
        "0.35",
        "--stairs",
        "0.22:0.25",
        "--json",
    ]);
    assert_eq!(r.status, 0, "{}", r.stderr);
    let report: Value = serde_json::from_str(&r.stdout).unwrap();
    let gaits = report["gaits"].as_array().unwrap();
    assert_eq!(gaits.len(), 3);
    assert_eq!(gaits[0]["name"], "walk-0.35");
    assert_eq!(gaits[0]["cleared"], true, "{}", r.stdout);
    assert!(
        gaits[0]["pace_m_s"].as_f64().unwrap() >= 0.30,
        "{}",
        r.stdout
    );
    let up = &gaits[1];
    assert_eq!(up["name"], "up-0.220");
    assert_eq!(up["cleared"], false);
    assert!(up["reason"].as_str().unwrap().contains("N·m"), "{up}");

    let listed = exogait(&["bundle", s(&b), "--json"]);
    assert_eq!(listed.status, 0, "{}", listed.stderr);
    let l: Value = serde_json::from_str(&listed.stdout).unwrap();
    assert_eq!(l["height_m"], 1.6);
    assert_eq!(l["patient_hash"], report["patient_hash"]);
    assert_eq!(l["device_fingerprint"], report["device_fingerprint"]);
    let names: Vec<&str> = l["gaits"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g["name"].as_str().unwrap())
        .collect();
    let cleared: Vec<&str> = gaits
        .iter()
        .filter(|g| g["cleared"] == true)
        .map(|g| g["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, cleared);
    assert_eq!(l["gaits"][0]["kind"], "walk");

    // The closed loop on the patient's body plays the cleared walk.
    let sim = exogait(&["simulate", "--bundle", s(&b), "--gait", "walk-0.35"]);
    assert_eq!(sim.status, 0, "{}{}", sim.stdout, sim.stderr);
    let cmp = exogait(&[
        "compare",
        "--bundle",
        s(&b),
        "--gait",
        "walk-0.35",
        "--json",
    ]);
    let c: Value = serde_json::from_str(&cmp.stdout).unwrap_or_else(|_| panic!("{}", cmp.stderr));
    assert_eq!(c["gait"], "walk-0.35");
    assert_eq!(c["patient_hash"], report["patient_hash"]);
    assert!(
        (c["geometry"]["step_length_m"].as_f64().unwrap()
            - gaits[0]["step_length_m"].as_f64().unwrap())
        .abs()
            < 0.01
    );
    assert!(c["shipped"]["progression_m_s"].as_f64().unwrap() >= 0.30);
    assert_eq!(c["shipped"]["faults"].as_array().unwrap().len(), 0);
    assert_eq!(
        c["shipped"]["landing_error_m"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|x| !x.is_null())
            .count(),
        4
    );

    // The fault campaign and the healthy runs play the patient's own gaits
    // on the fitted device, each named as the bundle names it.
    let f = exogait(&[
        "faults",
        "--bundle",
        s(&b),
        "--runs",
        "6",
        "--healthy",
        "1",
        "--json",
    ]);
    assert!(matches!(f.status, 0 | 1), "{}", f.stderr);
    let v: Value = serde_json::from_str(&f.stdout).unwrap_or_else(|_| panic!("{}", f.stderr));
    assert_eq!(v["bundle"], s(&b));
    assert_eq!(v["all"]["runs"], 6);
    let healthy: Vec<&str> = v["healthy"]["by_gait"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g[0].as_str().unwrap())
        .collect();
    assert_eq!(healthy, names);
    assert_eq!(v["healthy"]["all"]["runs"], names.len());

    // A name the bundle does not hold, and every damaged bundle: exit 2.
    let r = exogait(&["simulate", "--bundle", s(&b), "--gait", "walk"]);
    assert_eq!(r.status, 2);
    assert!(r.stderr.contains("walk-0.35"), "{}", r.stderr);
    let image = std::fs::read(&b).unwrap();
    let mut flipped = image.clone();
    flipped[image.len() / 2] ^= 0x10;
    let mut foreign = image.clone();
    foreign[12] ^= 0xFF;
    for (name, bytes) in [
        ("truncated", image[..image.len() - 9].to_vec()),
        ("flipped", flipped),
        ("foreign", foreign),
        ("table", gait_core::flash_tables::WALK.to_vec()),
    ] {
        let f = d.join(format!("{name}.bundle"));
        std::fs::write(&f, bytes).unwrap();
        for args in [
            vec!["bundle", s(&f)],
            vec!["simulate", "--bundle", s(&f), "--gait", "walk-0.35"],
            vec!["faults", "--bundle", s(&f), "--runs", "1", "--healthy", "0"],
            vec!["compare", "--bundle", s(&f), "--gait", "walk-0.35"],
        ] {
            let r = exogait(&args);
            assert_eq!(r.status, 2, "{name}: {args:?}");
            assert!(r.stderr.contains("bundle refused"), "{name}: {}", r.stderr);
        }
    }
}

#[test]
fn bad_family_options_are_refused() {
    let d = dir("options");
    let p = d.join("p.json");
    assert_eq!(
        exogait(&["fit", "--height", "1.6", "--mass", "55", "--out", s(&p)]).status,
        0
    );
    let out = d.join("x.bundle");
    for bad in [
        vec!["--paces", "0.9"],
        vec!["--stairs", "0.15"],
        vec!["--stairs", "0.30:0.28"],
        vec!["--evals", "10"],
        vec!["--campaign", "20000"],
        vec!["--paces", "0.25,0.25"],
    ] {
        let mut args = vec!["tables", "--patient", s(&p), "--out", s(&out)];
        args.extend(bad.iter().copied());
        let r = exogait(&args);
        assert_eq!(r.status, 2, "{args:?}");
        assert!(!out.exists());
    }
    let r = exogait(&[
        "tables",
        "--patient",
        s(&d.join("missing.json")),
        "--out",
        s(&out),
    ]);
    assert_eq!(r.status, 2);
}
