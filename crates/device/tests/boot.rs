//! What the board plays from its bundle sector: the built-in tables when
//! it is erased, a verified patient's gaits in the clinician's order, and
//! nothing (fault 0x0604 latched, no reset) when a bundle is refused.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs
)]

use exogait_device::DeviceConfig;
use exogait_device::boot::{self, Gaits, TableSlots};
use exogait_device::fitting::{Measures, fit};
use gait_control::faults::FaultCode;
use gait_control::operator::Gait;
use gait_control::sequencer::GaitTables;
use gait_core::bundle::{
    BundleError, GaitInfo, GaitName, GaitSource, MAX_GAITS, bundle_len, encode,
};
use gait_core::flash_tables::{STAIR_DOWN, WALK};
use gait_core::tables::GaitKind;

fn device() -> DeviceConfig {
    DeviceConfig::exogait().unwrap()
}

fn info(name: &str, kind: GaitKind) -> GaitInfo {
    GaitInfo {
        name: GaitName::new(name).unwrap(),
        kind,
        step_length_m: 0.3,
        rise_m: 0.0,
        tread_m: 0.0,
        step_time_s: 2.24,
        pace_m_s: 0.1,
        clearance_m: 0.05,
    }
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
    let gaits = [
        GaitSource {
            info: info("down", GaitKind::StairDown),
            table: &STAIR_DOWN,
        },
        GaitSource {
            info: info("walk", GaitKind::Walk),
            table: &WALK,
        },
    ];
    let mut img = vec![0u8; bundle_len(&gaits)];
    encode(device.fingerprint(), 1, &patient, &gaits, &mut img).unwrap();
    img
}

fn sector(image: &[u8]) -> Vec<u8> {
    let mut s = vec![0xFF; 128 * 1024];
    s[..image.len()].copy_from_slice(image);
    s
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
        let (cfg, c) = boot::build(&d, &gaits, built_in, &mut slots).unwrap();
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
    let (cfg, c) = boot::build(&d, &gaits, GaitTables::default(), &mut slots).unwrap();
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
        let (cfg, c) = boot::build(&d, &gaits, GaitTables::default(), &mut slots).unwrap();
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
