//! The clinician button scheme, driven through real debouncers.

use gait_control::drivers::buttons::{ButtonConfig, Debouncer};
use gait_control::drivers::status::Pattern;
use gait_control::operator::{
    AllowedGaits, ConfigError, ControllerStatus, FAST_BLINK, Gait, GaitChoice, Input, MAX_GAITS,
    Operator, OperatorConfig, Output, Request,
};
use proptest::prelude::*;

struct Rig {
    op: Operator,
    mode: Debouncer,
    go: Debouncer,
    status: ControllerStatus,
    last: Option<Output>,
}

impl Rig {
    fn new(allowed: &[Gait]) -> Self {
        Self {
            op: Operator::new(OperatorConfig {
                allowed: AllowedGaits::new(allowed).unwrap(),
                reset_hold_ticks: 3000,
            }),
            mode: Debouncer::new(ButtonConfig::DEFAULT_1KHZ),
            go: Debouncer::new(ButtonConfig::DEFAULT_1KHZ),
            status: ControllerStatus {
                safe_posture: true,
                ..ControllerStatus::default()
            },
            last: None,
        }
    }

    fn standard() -> Self {
        Self::new(&[Gait::Walk, Gait::StairUp, Gait::StairDown])
    }

    /// Runs `ticks` ticks with the raw contacts given; returns the requests
    /// with the tick (from the start of this call) they came at.
    fn run(&mut self, ticks: u32, mode: bool, go: bool) -> Vec<(u32, Request)> {
        let mut out = Vec::new();
        for t in 0..ticks {
            let input = Input {
                mode: self.mode.update(mode),
                go: self.go.update(go),
                status: self.status,
            };
            let o = self.op.tick(&input);
            if let Some(r) = o.request {
                out.push((t, r));
            }
            self.last = Some(o);
        }
        out
    }

    fn idle(&mut self, ticks: u32) -> Vec<(u32, Request)> {
        self.run(ticks, false, false)
    }

    fn out(&self) -> Output {
        self.last.unwrap()
    }

    fn buzzer_count(&self) -> Option<u8> {
        match self.out().feedback.buzzer {
            Pattern::Burst { count, .. } => Some(count),
            _ => None,
        }
    }

    fn short_mode(&mut self) -> Vec<(u32, Request)> {
        let mut r = self.run(100, true, false);
        r.extend(self.idle(50));
        r
    }
}

#[test]
fn starts_on_first_gait_showing_its_code() {
    let mut rig = Rig::standard();
    assert!(rig.idle(10).is_empty());
    assert_eq!(rig.out().selected, Gait::Walk);
    assert_eq!(rig.out().feedback.gait_led, Pattern::Code { count: 1 });
    assert_eq!(rig.out().feedback.fault_led, Pattern::Off);
}

#[test]
fn mode_short_press_cycles_and_wraps() {
    let mut rig = Rig::standard();
    assert!(rig.short_mode().is_empty());
    assert_eq!(rig.out().selected, Gait::StairUp);
    assert_eq!(rig.out().feedback.gait_led, Pattern::Code { count: 2 });
    assert_eq!(rig.buzzer_count(), Some(1));
    rig.short_mode();
    assert_eq!(rig.out().selected, Gait::StairDown);
    rig.short_mode();
    assert_eq!(rig.out().selected, Gait::Walk);
}

#[test]
fn mode_acts_on_release_not_on_press() {
    let mut rig = Rig::standard();
    rig.run(500, true, false);
    assert_eq!(rig.out().selected, Gait::Walk);
    rig.idle(30);
    assert_eq!(rig.out().selected, Gait::StairUp);
}

#[test]
fn bounce_changes_nothing() {
    let mut rig = Rig::standard();
    for _ in 0..20 {
        rig.run(5, true, false);
        rig.run(5, false, false);
        rig.run(5, false, true);
        rig.run(5, false, false);
    }
    assert_eq!(rig.out().selected, Gait::Walk);
    assert_eq!(rig.out().feedback.buzzer, Pattern::Off);
}

#[test]
fn mode_long_press_does_nothing() {
    let mut rig = Rig::standard();
    rig.run(1500, true, false);
    rig.idle(50);
    assert_eq!(rig.out().selected, Gait::Walk);
}

#[test]
fn single_gait_list_stays_put() {
    let mut rig = Rig::new(&[Gait::StairUp]);
    rig.short_mode();
    assert_eq!(rig.out().selected, Gait::StairUp);
}

#[test]
fn go_short_press_does_not_start() {
    let mut rig = Rig::standard();
    assert!(rig.run(500, false, true).is_empty());
    assert!(rig.idle(50).is_empty());
}

#[test]
fn go_long_press_starts_selected_gait_once() {
    let mut rig = Rig::standard();
    rig.short_mode();
    let reqs = rig.run(2000, false, true);
    assert_eq!(reqs.len(), 1);
    let (t, r) = reqs[0];
    assert_eq!(
        r,
        Request::Start(GaitChoice {
            kind: Gait::StairUp,
            slot: 1,
            flashes: 2
        })
    );
    // 20 ms debounce + 1 s hold (counted from the debounced press).
    assert!((1015..=1025).contains(&t), "{t}");
    assert_eq!(rig.buzzer_count(), Some(2));
    assert!(rig.idle(50).is_empty());
}

#[test]
fn start_refused_while_faulted() {
    let mut rig = Rig::standard();
    rig.status.faulted = true;
    assert!(rig.run(1500, false, true).is_empty());
    assert_eq!(rig.buzzer_count(), Some(3));
    assert_eq!(rig.out().feedback.fault_led, Pattern::On);
    assert_eq!(rig.out().feedback.gait_led, Pattern::Off);
}

#[test]
fn go_while_walking_stops_after_step() {
    let mut rig = Rig::standard();
    rig.status.walking = true;
    rig.status.step_in_progress = true;
    assert_eq!(rig.out_or_idle(), Pattern::On);
    let reqs = rig.run(1500, false, true);
    assert_eq!(reqs.len(), 1, "{reqs:?}");
    assert_eq!(reqs[0].1, Request::StopAfterStep);
    assert!(reqs[0].0 < 25, "stop acts on the press, not on a long hold");
    assert_eq!(rig.out().feedback.gait_led, FAST_BLINK);
    rig.idle(50);
    rig.status.walking = false;
    rig.status.step_in_progress = false;
    rig.idle(1);
    assert_eq!(rig.out().feedback.gait_led, Pattern::Code { count: 1 });
}

impl Rig {
    fn out_or_idle(&mut self) -> Pattern {
        self.idle(1);
        self.out().feedback.gait_led
    }
}

#[test]
fn mode_ignored_during_step_and_while_walking() {
    let mut rig = Rig::standard();
    rig.status.walking = true;
    rig.status.step_in_progress = true;
    assert!(rig.short_mode().is_empty());
    assert_eq!(rig.out().selected, Gait::Walk);
    assert_eq!(rig.buzzer_count(), Some(3));
    // Between steps, still walking: still ignored.
    rig.status.step_in_progress = false;
    rig.short_mode();
    assert_eq!(rig.out().selected, Gait::Walk);
    // Standing: accepted.
    rig.status.walking = false;
    rig.short_mode();
    assert_eq!(rig.out().selected, Gait::StairUp);
}

#[test]
fn reset_combination_honoured_in_safe_posture() {
    let mut rig = Rig::standard();
    rig.status.faulted = true;
    rig.idle(5);
    let reqs = rig.run(1000, true, true);
    assert!(
        reqs.is_empty(),
        "no start although GO was held 1 s: {reqs:?}"
    );
    assert_eq!(rig.out().feedback.fault_led, FAST_BLINK);
    let reqs = rig.run(3000, true, true);
    assert_eq!(reqs.len(), 1, "{reqs:?}");
    assert_eq!(reqs[0].1, Request::ResetFaults);
    assert!(matches!(rig.out().feedback.buzzer, Pattern::Tone { .. }));
    // Release: MODE must not cycle the gait, GO must not start.
    assert!(rig.idle(100).is_empty());
    assert_eq!(rig.out().selected, Gait::Walk);
}

#[test]
fn reset_combination_refused_when_not_safe() {
    let mut rig = Rig::standard();
    rig.status.faulted = true;
    rig.status.safe_posture = false;
    assert!(rig.run(3500, true, true).is_empty());
    assert_eq!(rig.buzzer_count(), Some(3));
    // Holding on does not retry, even once the posture becomes safe: one
    // decision per hold.
    rig.status.safe_posture = true;
    assert!(rig.run(3500, true, true).is_empty());
    assert!(rig.idle(100).is_empty());
    // A fresh hold in a safe posture works.
    assert_eq!(rig.run(3100, true, true).len(), 1);
}

#[test]
fn combination_released_early_does_nothing() {
    let mut rig = Rig::standard();
    assert!(rig.run(2500, true, true).is_empty());
    assert!(rig.idle(100).is_empty());
    assert_eq!(rig.out().selected, Gait::Walk);
    // A later combination starts counting from zero.
    let reqs = rig.run(3100, true, true);
    assert_eq!(reqs.len(), 1);
    assert_eq!(reqs[0].1, Request::ResetFaults);
}

#[test]
fn mode_held_first_then_go_is_a_combination() {
    let mut rig = Rig::standard();
    rig.run(300, true, false);
    let reqs = rig.run(1500, true, true);
    assert!(reqs.is_empty(), "{reqs:?}");
    // Let go of GO first, MODE later: still no gait change.
    rig.run(100, true, false);
    assert!(rig.idle(100).is_empty());
    assert_eq!(rig.out().selected, Gait::Walk);
}

#[test]
fn both_buttons_while_walking_still_stop() {
    let mut rig = Rig::standard();
    rig.status.walking = true;
    rig.status.step_in_progress = true;
    rig.status.safe_posture = false;
    let reqs = rig.run(4000, true, true);
    assert_eq!(reqs.len(), 1, "{reqs:?}");
    assert_eq!(reqs[0].1, Request::StopAfterStep);
}

#[test]
fn allowed_list_is_checked() {
    assert_eq!(AllowedGaits::new(&[]), Err(ConfigError::Empty));
    assert_eq!(
        AllowedGaits::new(&[Gait::Walk, Gait::Walk]),
        Err(ConfigError::Duplicate)
    );
    assert_eq!(
        AllowedGaits::new(&[Gait::Walk, Gait::StairUp, Gait::StairDown, Gait::Walk]),
        Err(ConfigError::Duplicate)
    );
    assert_eq!(
        AllowedGaits::in_order(&[Gait::Walk; MAX_GAITS + 1]),
        Err(ConfigError::TooMany)
    );
    // A bundle's list: the same movement more than once, each its own
    // slot, shown by its place in the list.
    let b = AllowedGaits::in_order(&[Gait::Walk, Gait::Walk, Gait::StairDown]).unwrap();
    assert_eq!(b.len(), 3);
    assert_eq!(
        b.choice(1),
        GaitChoice {
            kind: Gait::Walk,
            slot: 1,
            flashes: 2
        }
    );
    assert_eq!(b.choice(2).kind, Gait::StairDown);
    assert_eq!(b.choice(2).flashes, 3);
    assert_eq!(b.choice(3), b.choice(0));
    let a = AllowedGaits::new(&[Gait::StairDown, Gait::Walk]).unwrap();
    assert_eq!(
        (a.len(), a.get(0), a.get(1), a.get(2)),
        (2, Gait::StairDown, Gait::Walk, Gait::StairDown)
    );
}

#[test]
fn short_combination_released_one_by_one_does_nothing() {
    let mut rig = Rig::standard();
    // Both together for half a second, then GO up first, MODE a bit later:
    // MODE's release is short, but it belongs to the combination.
    rig.run(500, true, true);
    rig.run(100, true, false);
    assert!(rig.idle(100).is_empty());
    assert_eq!(rig.out().selected, Gait::Walk);
    assert_eq!(rig.out().feedback.buzzer, Pattern::Off);
}

proptest! {
    /// Whatever the buttons and the controller status do, the scheme never
    /// asks to start while walking or faulted, never resets outside a safe
    /// standing posture, never stops when not walking, and starts at most
    /// once per GO press.
    #[test]
    fn safety_invariants(
        segments in prop::collection::vec(
            (1u32..1500, any::<bool>(), any::<bool>(), any::<bool>(), any::<bool>(), any::<bool>(), any::<bool>()),
            1..20,
        ),
    ) {
        let mut op = Operator::new(OperatorConfig {
            allowed: AllowedGaits::new(&[Gait::Walk, Gait::StairUp]).unwrap(),
            reset_hold_ticks: 3000,
        });
        let mut mode = Debouncer::new(ButtonConfig::DEFAULT_1KHZ);
        let mut go = Debouncer::new(ButtonConfig::DEFAULT_1KHZ);
        let mut starts_this_press = 0;
        for (ticks, m, g, walking, step, safe, faulted) in segments {
            let status = ControllerStatus {
                walking,
                step_in_progress: step,
                safe_posture: safe,
                faulted,
            };
            for _ in 0..ticks {
                let input = Input { mode: mode.update(m), go: go.update(g), status };
                if !input.go.pressed {
                    starts_this_press = 0;
                }
                let out = op.tick(&input);
                match out.request {
                    Some(Request::Start(gait)) => {
                        prop_assert!(!walking && !step && !faulted);
                        prop_assert!(gait.kind == Gait::Walk || gait.kind == Gait::StairUp);
                        starts_this_press += 1;
                        prop_assert_eq!(starts_this_press, 1);
                    }
                    Some(Request::ResetFaults) => {
                        prop_assert!(safe && !walking && !step);
                        prop_assert!(input.mode.pressed && input.go.pressed);
                    }
                    Some(Request::StopAfterStep) => prop_assert!(walking),
                    None => {}
                }
            }
        }
    }
}
