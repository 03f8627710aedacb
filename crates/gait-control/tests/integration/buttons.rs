//! Buttons (debounce, long press, input faults) and status indicators.

use std::io::ErrorKind;

use embedded_hal_mock::eh1::MockError;
use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as PinT};
use gait_control::drivers::buttons::{ActiveLevel, Button, ButtonConfig, Debouncer, Event};
use gait_control::drivers::status::{Indicator, Pattern};
use proptest::prelude::*;

const CFG: ButtonConfig = ButtonConfig {
    active: ActiveLevel::Low,
    debounce_ticks: 3,
    long_press_ticks: 5,
};

fn new_button(levels: &[PinT]) -> Button<PinMock> {
    Button::new(PinMock::new(levels), CFG)
}

fn destroy_button(b: Button<PinMock>) {
    b.destroy().done();
}

fn gets(states: &[State]) -> Vec<PinT> {
    states.iter().map(|s| PinT::get(*s)).collect()
}

use State::{High as H, Low as L};

#[test]
fn press_after_debounce_then_long_then_release() {
    // Active low: L = pressed.
    let seq = [L, L, L, L, L, L, L, L, L, H, H, H];
    let mut b = new_button(&gets(&seq));
    let events: Vec<_> = (0..seq.len()).map(|_| b.tick().event).collect();
    assert_eq!(
        events,
        vec![
            None,
            None,
            Some(Event::Pressed), // 3rd pressed sample
            None,
            None,
            None,
            None,
            Some(Event::LongPress), // 5 ticks after the press
            None,
            None,
            None,
            Some(Event::Released {
                held_ticks: 9,
                was_long: true
            }),
        ]
    );
    destroy_button(b);
}

#[test]
fn bounce_is_filtered() {
    let seq = [L, H, L, H, L, H, H, H];
    let mut b = new_button(&gets(&seq));
    for _ in 0..seq.len() {
        assert_eq!(b.tick().event, None);
    }
    destroy_button(b);
}

#[test]
fn short_press_release_is_not_long() {
    let seq = [L, L, L, L, H, H, H];
    let mut b = new_button(&gets(&seq));
    let events: Vec<_> = (0..seq.len()).filter_map(|_| b.tick().event).collect();
    assert_eq!(
        events,
        vec![
            Event::Pressed,
            Event::Released {
                held_ticks: 4,
                was_long: false
            }
        ]
    );
    destroy_button(b);
}

#[test]
fn input_error_counts_as_released_and_is_reported() {
    let e = MockError::Io(ErrorKind::NotConnected);
    let mut t = gets(&[L, L, L]);
    t.push(PinT::get(L).with_error(e.clone()));
    t.push(PinT::get(L).with_error(e.clone()));
    t.push(PinT::get(L).with_error(e));
    let mut b = new_button(&t);
    assert_eq!(b.tick().event, None);
    assert_eq!(b.tick().event, None);
    assert_eq!(b.tick().event, Some(Event::Pressed));
    let s = b.tick();
    assert!(s.input_fault && s.event.is_none());
    assert!(b.tick().input_fault);
    let s = b.tick();
    assert!(s.input_fault);
    assert!(matches!(s.event, Some(Event::Released { .. })));
    assert_eq!(b.input_errors(), 3);
    destroy_button(b);
}

#[test]
fn active_high_buttons() {
    let mut b = Button::new(
        PinMock::new(&gets(&[H])),
        ButtonConfig {
            active: ActiveLevel::High,
            debounce_ticks: 1,
            long_press_ticks: 100,
        },
    );
    assert_eq!(b.tick().event, Some(Event::Pressed));
    b.destroy().done();
}

#[test]
fn patterns() {
    assert!(!Pattern::Off.level(5));
    assert!(Pattern::On.level(5));
    let blink = Pattern::Blink {
        period_ticks: 10,
        on_ticks: 3,
    };
    assert!(blink.level(0) && blink.level(12) && !blink.level(13));
    assert!(
        !Pattern::Blink {
            period_ticks: 0,
            on_ticks: 3
        }
        .level(7)
    );
    // Code 2: on 0..200, off, on 400..600, off until 1800, repeat.
    let code = Pattern::Code { count: 2 };
    let lit: Vec<bool> = [0, 199, 200, 400, 599, 600, 1000, 1799, 1800]
        .iter()
        .map(|&t| code.level(t))
        .collect();
    assert_eq!(
        lit,
        [true, true, false, true, true, false, false, false, true]
    );
    let burst = Pattern::Burst {
        start: 100,
        count: 2,
    };
    assert!(!burst.level(99) && burst.level(100) && !burst.level(180) && burst.level(260));
    assert!(!burst.level(340) && !burst.level(10_000));
    let tone = Pattern::Tone {
        start: 10,
        on_ticks: 5,
    };
    assert!(!tone.level(9) && tone.level(14) && !tone.level(15));
}

#[test]
fn indicator_writes_only_on_change_and_retries_after_error() {
    let e = MockError::Io(ErrorKind::NotConnected);
    let pin = PinMock::new(&[
        PinT::set(L),
        PinT::set(H).with_error(e),
        PinT::set(H),
        PinT::set(L),
    ]);
    let mut led = Indicator::new(pin);
    let blink = Pattern::Blink {
        period_ticks: 4,
        on_ticks: 2,
    };
    led.update(Pattern::Off, 0).unwrap(); // first update always writes
    led.update(Pattern::Off, 1).unwrap(); // unchanged: no write
    assert!(led.update(blink, 0).is_err()); // failed write
    led.update(blink, 1).unwrap(); // retried
    led.update(blink, 2).unwrap(); // low
    led.update(blink, 3).unwrap(); // unchanged
    led.destroy().done();
}

proptest! {
    /// Any bounce pattern shorter than the debounce time, starting from a
    /// stable state, never produces an event.
    #[test]
    fn short_bounce_never_yields_event(
        debounce in 1u16..50,
        start_pressed in any::<bool>(),
        bounce in prop::collection::vec(any::<bool>(), 0..50),
    ) {
        let cfg = ButtonConfig { active: ActiveLevel::Low, debounce_ticks: debounce, long_press_ticks: 100_000 };
        let mut d = Debouncer::new(cfg);
        // Settle in the starting state.
        for _ in 0..u32::from(debounce) * 2 {
            d.update(start_pressed);
        }
        prop_assert_eq!(d.is_pressed(), start_pressed);
        let n = bounce.len().min(usize::from(debounce) - 1);
        for &raw in &bounce[..n] {
            prop_assert_eq!(d.update(raw).event, None);
        }
    }

    /// Events always alternate Pressed → (LongPress) → Released, whatever the
    /// input, and a held press is accepted within the debounce time.
    #[test]
    fn events_are_well_formed(samples in prop::collection::vec(any::<bool>(), 0..400)) {
        let mut d = Debouncer::new(CFG);
        let mut pressed = false;
        let mut long = false;
        for raw in samples {
            match d.update(raw).event {
                Some(Event::Pressed) => { prop_assert!(!pressed); pressed = true; long = false; }
                Some(Event::LongPress) => { prop_assert!(pressed && !long); long = true; }
                Some(Event::Released { was_long, .. }) => { prop_assert!(pressed); prop_assert_eq!(was_long, long); pressed = false; }
                None => {}
            }
            prop_assert_eq!(d.is_pressed(), pressed);
        }
        let mut got = false;
        for _ in 0..CFG.debounce_ticks {
            got |= d.update(true).event == Some(Event::Pressed);
        }
        prop_assert!(d.is_pressed());
        prop_assert!(got || pressed);
    }
}
