//! The ground search in the closed loop: a step whose table ends with the
//! foot above the ground (a curb or a tread lower than planned) goes on
//! lowering the foot until its sensor feels the ground, and lands there;
//! without the search the foot hovers until the landing times out
//! (docs/safety.md, "Swing").

use exogait_device::DeviceConfig;
use gait_control::operator::Gait;
use sim::outcome::outcome;
use sim::scenario::{GO_AT_TICK, GO_TICKS, flash_tables, run_steps, strong_pilot, table_rig_on};
use sim::terrain::Terrain;

/// Walks `steps` steps onto ground `drop_m` lower than planned from 0.2 m
/// ahead of the stance foot (past its toe, before the first landing). One
/// step is what the search is for: the next starts with the trailing foot
/// above the stance foot's ground, which a table planned for level ground
/// does not expect (it drags that foot through the upper ground).
fn walk_down_a_curb(
    device: &DeviceConfig,
    drop_m: f64,
    steps: usize,
) -> (sim::outcome::Outcome, Vec<sim::Landing>) {
    let curb = Terrain::Stairs {
        start_x_m: 0.2,
        rise_m: -drop_m,
        tread_m: 100.0,
        steps: 1,
    };
    let mut rig = table_rig_on(device, Gait::Walk, strong_pilot(), flash_tables(), curb).unwrap();
    sim::closed_loop::Rig::press(&rig.go, GO_AT_TICK, GO_TICKS);
    let ended = run_steps(&mut rig, steps, 20.0).err();
    (outcome(&rig, ended.as_ref()), rig.plant.landings().to_vec())
}

#[test]
fn a_curb_lower_than_planned_is_found_and_walked_on() {
    let device = DeviceConfig::exogait().unwrap();
    for drop_m in [0.01, 0.02] {
        let (o, landings) = walk_down_a_curb(&device, drop_m, 1);
        assert!(
            o.landings == 1 && o.faults.is_empty() && o.fell.is_none(),
            "{drop_m} m: {o:?}"
        );
        // Set down gently, on the lower ground.
        let l = landings[0];
        assert!((l.ground_m + drop_m).abs() < 1e-9, "{l:?}");
        assert!(l.descent_speed_m_s < 0.15, "{l:?}");
        assert!(o.worst_limit_margin_rad > 0.0, "{drop_m} m: {o:?}");
    }
}

#[test]
fn without_the_search_the_foot_hovers_over_the_curb() {
    let mut device = DeviceConfig::exogait().unwrap();
    device.controller.sequencer.ground_search_depth_m = 0.0;
    // The landing times out with the foot in the air; standing on one leg,
    // the body tips back until that foot comes down behind the curb.
    let (o, landings) = walk_down_a_curb(&device, 0.02, 1);
    assert!(landings.iter().all(|l| l.ground_m == 0.0), "{o:?}");
}
