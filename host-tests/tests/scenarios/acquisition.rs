//! The sensors read before the tick in the motor board's DMA order
//! (`gait_control::acquisition::acquire_in_rounds`: every encoder's ANGLE
//! command, then every NOP, an error flag cleared on its chip at once; the
//! ADC's five conversions) drive the device exactly as the tick's own reads
//! through the drivers do, in a healthy noisy walk and with the sensing
//! faults whose frames the order could change: the same commands bit for
//! bit, the same faults on the same ticks.

use gait_control::controller::TickReport;
use host_tests::{standing_rig, strong_pilot};
use sim::closed_loop::Rig;
use sim::inject::{Injection, Kind, Target};

/// Ticks of a walk from standing: GO, the weight transfer, two swings.
const TICKS: usize = 5_000;

fn walk(dma_frame_order: bool, fault: Option<Injection>) -> Vec<TickReport> {
    let mut rig = standing_rig(strong_pilot()).unwrap();
    rig.dma_frame_order = dma_frame_order;
    rig.set_sensor_noise(3, 10, 2026);
    if let Some(f) = fault {
        rig.schedule(f);
    }
    Rig::press(&rig.go, sim::scenario::GO_AT_TICK, sim::scenario::GO_TICKS);
    let mut reports = Vec::new();
    for _ in 0..TICKS {
        match rig.tick() {
            Ok(sample) => reports.push(sample.report),
            Err(_) => break,
        }
    }
    reports
}

#[test]
fn the_dma_frame_order_drives_the_device_as_the_drivers_reads_do() {
    let at = |kind, target| {
        Some(Injection {
            kind,
            target,
            at_s: 2.6,
        })
    };
    for fault in [
        None,
        at(Kind::EncoderErrorFlag, Some(Target::Joint(1))),
        at(Kind::EncoderParity, Some(Target::Ankle(0))),
        at(Kind::EncoderBus, Some(Target::Joint(2))),
        at(Kind::AdcBus, None),
    ] {
        let drivers = walk(false, fault);
        let dma = walk(true, fault);
        assert!(drivers.len() > 2_000, "{fault:?}: {} ticks", drivers.len());
        assert_eq!(drivers.len(), dma.len(), "{fault:?}");
        if fault.is_some() {
            assert!(
                drivers.iter().any(|r| !r.faults.is_empty()),
                "{fault:?}: nothing found"
            );
        }
        for (n, (a, b)) in drivers.iter().zip(&dma).enumerate() {
            let bits = |r: &TickReport| r.command_nm.map(f32::to_bits);
            assert_eq!(bits(a), bits(b), "{fault:?}: tick {n}");
            assert_eq!(a.faults, b.faults, "{fault:?}: tick {n}");
            assert_eq!(a.reaction, b.reaction, "{fault:?}: tick {n}");
        }
    }
}
