//! The generated flash-table module is exactly what the generator makes now
//! (so nobody edits it by hand, and a change of optimiser or model that
//! changes the tables cannot go unnoticed).
#![allow(clippy::unwrap_used, missing_docs)]

#[test]
fn flash_tables_match_the_generator() {
    let committed = include_str!("../../gait-core/src/flash_tables.rs");
    let fresh = gait_opt::tables::flash_module_source().unwrap();
    assert!(
        committed == fresh,
        "crates/gait-core/src/flash_tables.rs is stale: run `cargo xtask tables`"
    );
}

/// Each flash table carries, in its header, the IK options of the clinical
/// case it was optimised and sampled on (the sequencer plans its weight
/// transfers with them).
#[test]
fn flash_tables_carry_the_ik_options_of_their_case() {
    use gait_core::tables::GaitKind;
    use gait_opt::clinical::ClinicalCase;
    let device = exogait_device::DeviceConfig::exogait().unwrap();
    for kind in [GaitKind::Walk, GaitKind::StairUp, GaitKind::StairDown] {
        let table = gait_core::flash_tables::of(kind).unwrap();
        let case = ClinicalCase::for_gait(kind, &device);
        assert_eq!(table.ik_options(), case.ik.cast::<f32>(), "{kind:?}");
    }
}

/// A table image made by the generator's writer carries the options it is
/// given, whatever the gait.
#[test]
fn table_image_writes_the_ik_options_it_is_given() {
    use gait_core::ik::{IkOptions, KneeRange};
    use gait_core::tables::{GaitKind, GaitTable};
    let phi = vec![[0.0, 0.1, 0.0, 3.0, 3.2], [0.1, 0.0, 0.05, 2.9, 3.3]];
    for ik in [
        IkOptions::paper(),
        IkOptions::new(70f64.to_radians(), KneeRange::Human).unwrap(),
    ] {
        let image = gait_opt::tables::table_image(GaitKind::Walk, &ik, &phi).unwrap();
        let t = GaitTable::parse(&image).unwrap();
        assert_eq!(t.ik_options(), ik.cast::<f32>());
    }
}
