//! The re-planner's landing aim (`ReplanSetup::aim_m`): the step starts
//! where the pilot stands, lands where it is aimed, and presses only the
//! approach's last centimetre under the floor.

use gait_core::flash_tables;
use gait_core::foot::StanceFoot;
use gait_core::playback::swing_ankle;
use gait_core::replan::{MAX_AIM_M, MAX_EVALS, Outcome, Progress, ReplanError, Replanner};
use gait_core::tables::GaitKind;

use super::replan_setup::{limits, measured, model, setup};

/// The device's walk and ascent aim.
const AIM: [f32; 2] = [-0.008, -0.003];

/// A walk or ascent re-planned 3° forward with `aim`: the outcome and
/// the samples.
fn aimed(kind: GaitKind, aim: [f32; 2]) -> (Outcome<f32>, Vec<[f32; 5]>) {
    let body = model();
    let table = flash_tables::of(kind).unwrap();
    let mut out = vec![[0.0f32; 5]; table.len()];
    let mut s = setup(&body, kind);
    s.aim_m = aim;
    let mut m = measured(&table, 3.0);
    m.persist = 0.6;
    let mut r = Replanner::new(s, limits(), table, m, &mut out, MAX_EVALS).unwrap();
    let Progress::Done(outcome) = r.step(MAX_EVALS) else {
        panic!("{kind:?}: not done within its budget");
    };
    (outcome, out)
}

#[test]
fn an_aimed_step_starts_where_the_pilot_stands_and_lands_where_it_is_aimed() {
    let body = model();
    let foot = StanceFoot::for_model(&body);
    for kind in [GaitKind::Walk, GaitKind::StairUp] {
        let table = flash_tables::of(kind).unwrap();
        let planned = swing_ankle(&body, &foot, &table.last());
        let (plain, plain_out) = aimed(kind, [0.0, 0.0]);
        let (outcome, out) = aimed(kind, AIM);
        assert!(
            matches!(plain, Outcome::Replanned { .. }),
            "{kind:?}: {plain:?}"
        );
        assert!(
            matches!(outcome, Outcome::Replanned { .. }),
            "{kind:?}: {outcome:?}"
        );
        // Where the pilot stands: the aim adds nothing at the start.
        for (a, b) in out[0].iter().zip(&plain_out[0]) {
            assert!(
                (a - b).abs() < 1e-4,
                "{kind:?}: {:?} vs {:?}",
                out[0],
                plain_out[0]
            );
        }
        let landed = swing_ankle(&body, &foot, out.last().unwrap());
        let off = [
            landed[0] - planned[0] - AIM[0],
            landed[1] - planned[1] - AIM[1],
        ];
        assert!(
            off[0].hypot(off[1]) <= 0.001,
            "{kind:?}: {off:?} m from the aim"
        );
        // Without the aim it lands on the table's foothold, 8 mm away.
        let plain_landed = swing_ankle(&body, &foot, plain_out.last().unwrap());
        assert!((plain_landed[0] - planned[0]).abs() <= 0.001, "{kind:?}");
        // The press is in the approach alone: the aimed swing ankle is
        // more than a millimetre under the table's only in the last
        // quarter of the step (an ascent's foot starts on the lower tread,
        // under the landing, and is not pressed there).
        let pressed: Vec<usize> = (0..out.len())
            .filter(|&k| {
                let t = swing_ankle(&body, &foot, &table.sample(k).unwrap());
                swing_ankle(&body, &foot, &out[k])[1] < t[1] - 0.001
            })
            .collect();
        assert!(!pressed.is_empty(), "{kind:?}: nothing pressed");
        assert!(
            pressed.iter().all(|&k| 4 * k >= 3 * out.len()),
            "{kind:?}: pressed at {pressed:?}"
        );
    }
}

#[test]
fn an_aim_beyond_its_bound_is_refused() {
    let body = model();
    let table = flash_tables::walk().unwrap();
    let mut out = vec![[0.0f32; 5]; table.len()];
    for aim in [
        [MAX_AIM_M as f32 + 0.001, 0.0],
        [0.0, -(MAX_AIM_M as f32) - 0.001],
        [f32::NAN, 0.0],
    ] {
        let mut s = setup(&body, GaitKind::Walk);
        s.aim_m = aim;
        let r = Replanner::new(s, limits(), table, measured(&table, 3.0), &mut out, 8);
        assert_eq!(r.err(), Some(ReplanError::BadSetup), "{aim:?}");
    }
}
