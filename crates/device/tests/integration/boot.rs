//! What the board plays from its bundle sector: the built-in tables when
//! it is erased, a verified patient's gaits in the clinician's order, and
//! nothing (fault 0x0604 latched, no reset) when a bundle is refused.

use exogait_device::DeviceConfig;
use exogait_device::boot::{self, Gaits, TableSlots};
use exogait_device::calibration::{self, Record, Refusal};
use exogait_device::fitting::{Measures, fit};
use gait_control::faults::FaultCode;
use gait_control::operator::Gait;
use gait_control::sequencer::GaitTables;
use gait_core::bundle::{BundleError, MAX_GAITS};
use gait_core::tables::GaitKind;

fn device() -> DeviceConfig {
    DeviceConfig::exogait().unwrap()
}

/// A 1.60 m patient's bundle: stair descent first, then walking.
fn bundle_image(device: &DeviceConfig) -> Vec<u8> {
    let patient = fit(
        device,
        &Measures {
            height_m: 1.6,
            mass_kg: 55.0,
            thigh_m: None,
            shank_m: None,
            foot_m: None,
        },
    )
    .unwrap();
    sim::scenario::descent_then_walk_bundle(device, &patient).unwrap()
}

fn sector(image: &[u8]) -> Vec<u8> {
    let mut s = vec![0xFF; 128 * 1024];
    s[..image.len()].copy_from_slice(image);
    s
}

/// The board's controller for `gaits` on the device with its own
/// calibration, no built-in tables.
fn calibrated<'a>(
    d: &DeviceConfig,
    gaits: &Gaits<'a>,
    slots: &'a mut TableSlots<'a>,
) -> (DeviceConfig, gait_control::controller::Controller<'a>) {
    boot::build(
        d,
        gaits,
        &Ok(Record::of_device(d)),
        GaitTables::default(),
        slots,
    )
    .unwrap()
}

#[test]
fn an_erased_sector_plays_the_built_in_gaits() {
    let d = device();
    for fill in [0xFF, 0x00] {
        let s = vec![fill; 4096];
        let gaits = boot::gaits_in(&d, &s);
        assert_eq!(gaits, Gaits::BuiltIn);
        let built_in = GaitTables::by_kind(gait_core::flash_tables::walk().ok(), None, None);
        let mut slots: TableSlots<'_> = [None; MAX_GAITS];
        let (cfg, c) =
            boot::build(&d, &gaits, &Ok(Record::of_device(&d)), built_in, &mut slots).unwrap();
        assert_eq!(cfg, d);
        assert_eq!(c.planned_gait(), Gait::Walk);
        assert!(c.supervisor().latched().is_empty());
    }
}

#[test]
fn a_verified_bundle_plays_its_gaits_in_order_on_the_fitted_device() {
    let d = device();
    let s = sector(&bundle_image(&d));
    let gaits = boot::gaits_in(&d, &s);
    let Gaits::Patient(b) = gaits else {
        panic!("refused: {gaits:?}")
    };
    assert_eq!(b.len(), 2);
    let mut slots: TableSlots<'_> = [None; MAX_GAITS];
    let (cfg, c) = calibrated(&d, &gaits, &mut slots);
    // The controller's model is the patient's, the rest the device's.
    assert_eq!(cfg.body.links(), b.patient().model.links());
    assert_ne!(cfg.fingerprint(), d.fingerprint());
    assert_eq!(cfg.drives, d.drives);
    // MODE's first choice is the bundle's first gait.
    assert_eq!(c.planned_gait(), Gait::StairDown);
    let t = c.sequencer().tables();
    assert_eq!(t.slot(0).map(|t| t.kind()), Some(GaitKind::StairDown));
    assert_eq!(t.slot(1).map(|t| t.kind()), Some(GaitKind::Walk));
    assert!(t.slot(2).is_none());
    assert!(c.supervisor().latched().is_empty());
}

#[test]
fn a_refused_bundle_plays_nothing_and_latches_0x0604_for_good() {
    let d = device();
    let good = bundle_image(&d);
    let mut flipped = good.clone();
    flipped[good.len() / 2] ^= 1;
    let mut foreign = good.clone();
    foreign[12] ^= 0xFF;
    let truncated = {
        let mut t = good.clone();
        t[8] = t[8].wrapping_add(8); // the header's length no longer matches
        t
    };
    for (image, why) in [
        (flipped, BundleError::BadCrc),
        (truncated, BundleError::BadCrc),
        (foreign.clone(), BundleError::BadCrc),
    ] {
        let s = sector(&image);
        let gaits = boot::gaits_in(&d, &s);
        let Gaits::Refused(e) = gaits else {
            panic!("accepted")
        };
        // A length or fingerprint byte changed also breaks the CRC, which
        // is checked first.
        assert_eq!(e, why);
        let mut slots: TableSlots<'_> = [None; MAX_GAITS];
        let (cfg, c) = calibrated(&d, &gaits, &mut slots);
        assert_eq!(cfg, d);
        assert!(c.sequencer().tables().slot(0).is_none());
        assert!(c.supervisor().latched().contains(FaultCode::BundleRefused));
        assert!(c.supervisor().present().contains(FaultCode::BundleRefused));
    }
    // Signed for another device: refused by name.
    let other = d.fingerprint() ^ 1;
    let mut img = bundle_image(&d);
    let len = img.len();
    img[12..16].copy_from_slice(&other.to_le_bytes());
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&img[..len - 4]);
    img[len - 4..].copy_from_slice(&crc.to_le_bytes());
    let s = sector(&img);
    assert_eq!(
        boot::gaits_in(&d, &s),
        Gaits::Refused(BundleError::ForeignDevice {
            bundle: other,
            device: d.fingerprint()
        })
    );
}

// ------------------------------------------------------------ calibration

fn readings(
    d: &DeviceConfig,
    rec: &Record,
) -> (
    [[u16; calibration::SAMPLES]; 6],
    [[u16; calibration::SAMPLES]; 4],
) {
    let _ = d;
    let mut enc = [[0u16; calibration::SAMPLES]; 6];
    for (e, &z) in enc.iter_mut().zip(&rec.encoder_zero_counts) {
        for (k, v) in e.iter_mut().enumerate() {
            // ±2 counts of jitter, wrapping at 14 bits.
            *v = ((i32::from(z) + (k as i32 % 5) - 2).rem_euclid(16384)) as u16;
        }
    }
    let mut f = [[0u16; calibration::SAMPLES]; 4];
    for (c, &z) in f.iter_mut().zip(&rec.force_zero_counts) {
        for (k, v) in c.iter_mut().enumerate() {
            *v = z + (k % 3) as u16 - 1;
        }
    }
    (enc, f)
}

#[test]
fn a_record_round_trips_and_every_corruption_is_refused() {
    let d = device();
    let mut rec = Record::of_device(&d);
    rec.encoder_zero_counts[3] = 16_383; // a zero next to the wrap
    let b = rec.encode();
    assert_eq!(Record::parse(&b, &d), Ok(rec));
    for byte in 0..calibration::RECORD_LEN {
        for bit in 0..8 {
            let mut x = b;
            x[byte] ^= 1 << bit;
            assert!(Record::parse(&x, &d).is_err(), "flip {byte}:{bit} accepted");
        }
    }
    assert_eq!(Record::parse(&[0xFF; 64], &d), Err(Refusal::Missing));
    assert_eq!(Record::parse(&b[..20], &d), Err(Refusal::Missing));
    // Plausibility, even under a good CRC.
    let mut loaded = rec;
    loaded.force_zero_counts[2] += 400;
    assert_eq!(
        Record::parse(&loaded.encode(), &d),
        Err(Refusal::ForceZero(2))
    );
    let mut wide = rec;
    wide.encoder_zero_counts[0] = 16_384;
    assert_eq!(
        Record::parse(&wide.encode(), &d),
        Err(Refusal::EncoderZero(0))
    );
}

#[test]
fn the_recording_procedure_finds_the_zeros_and_refuses_a_moving_device() {
    let d = device();
    let mut truth = Record::of_device(&d);
    truth.encoder_zero_counts = [1, 15_000, 8_191, 40, 3_000, 16_380];
    truth.force_zero_counts[0] += 37;
    let (enc, force) = readings(&d, &truth);
    assert_eq!(Record::from_readings(&d, &enc, &force), Ok(truth));
    let mut moved = enc;
    moved[1][40] = moved[1][40].wrapping_add(30);
    assert_eq!(
        Record::from_readings(&d, &moved, &force),
        Err(Refusal::EncoderMoved(1))
    );
    let mut pressed = force;
    pressed[3][10] += 200;
    assert_eq!(
        Record::from_readings(&d, &enc, &pressed),
        Err(Refusal::ForceMoved(3))
    );
}

#[test]
fn the_calibrated_device_reads_with_the_record_and_without_one_stays_off() {
    let d = device();
    let mut rec = Record::of_device(&d);
    // The simulated device's own record changes nothing.
    assert_eq!(d.calibrated(&rec).unwrap(), d);
    rec.encoder_zero_counts[4] = 123;
    rec.force_zero_counts[1] += 50;
    let c = d.calibrated(&rec).unwrap();
    assert_eq!(c.encoders[4].zero_offset_counts, 123);
    assert_eq!(c.encoders[4].direction, d.encoders[4].direction);
    assert_ne!(
        c.controller.force_calibration,
        d.controller.force_calibration
    );
    // Without a record: 0x0605 latched for good, motors off.
    let s = vec![0xFFu8; 4096];
    let gaits = boot::gaits_in(&d, &s);
    let mut slots: TableSlots<'_> = [None; MAX_GAITS];
    let (_, ctl) = boot::build(
        &d,
        &gaits,
        &Err(Refusal::Missing),
        GaitTables::default(),
        &mut slots,
    )
    .unwrap();
    assert!(
        ctl.supervisor()
            .latched()
            .contains(FaultCode::CalibrationRefused)
    );
    assert_eq!(
        ctl.supervisor().latched().reaction(),
        gait_control::faults::Reaction::DisableMotors
    );
}
