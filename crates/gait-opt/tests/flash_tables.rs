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
