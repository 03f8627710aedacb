//! The panic-free ring log keeps the newest records, oldest first.

use gait_control::ring_log::RingLog;

#[test]
fn keeps_the_newest_n_oldest_first_through_several_wraps() {
    let mut log: RingLog<u32, 4> = RingLog::new();
    assert!(log.is_empty());
    assert_eq!(log.iter().count(), 0);
    for k in 0..3 {
        log.push(k);
    }
    assert_eq!(log.iter().copied().collect::<Vec<_>>(), [0, 1, 2]);
    for k in 3..11 {
        log.push(k);
        let got: Vec<u32> = log.iter().copied().collect();
        let want: Vec<u32> = (k.saturating_sub(3)..=k).collect();
        assert_eq!(got, want, "after pushing {k}");
    }
    assert_eq!(log.len(), 4);
    assert_eq!(log.iter().next_back(), Some(&10));
}

#[test]
fn a_one_slot_log_holds_the_latest() {
    let mut log: RingLog<u8, 1> = RingLog::new();
    log.push(1);
    log.push(2);
    assert_eq!(log.iter().copied().collect::<Vec<_>>(), [2]);
}
