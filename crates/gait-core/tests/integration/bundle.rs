//! The bundle format: what is written reads back, and every corruption,
//! truncation, foreign device or malformed part is refused.

use gait_core::BodyModel;
use gait_core::anthropometry::{self, ExoSegments, Options, Pilot, SegmentLengths};
use gait_core::bundle::{
    Bundle, BundleError, GaitInfo, GaitName, GaitSource, Patient, bundle_len, encode, stored_len,
};
use gait_core::flash_tables::{STAIR_DOWN, STAIR_UP, WALK};
use gait_core::tables::GaitKind;

const DEVICE: u32 = 0x1234_5678;

fn patient() -> Patient {
    let pilot = Pilot {
        height_m: 1.6,
        mass_kg: 55.0,
    };
    let lengths = SegmentLengths::winter(1.6);
    let model = anthropometry::body_model_with_lengths(
        &pilot,
        &lengths,
        &ExoSegments::paper_default(),
        &Options::default(),
    )
    .unwrap_or_else(|_| BodyModel::paper_table_iii());
    Patient {
        height_m: 1.6,
        mass_kg: 55.0,
        segments_m: [lengths.thigh_m, lengths.shank_m, lengths.foot_m],
        model,
    }
}

fn info(name: &str, kind: GaitKind, rise: f32) -> GaitInfo {
    GaitInfo {
        name: GaitName::new(name).unwrap_or_else(|| panic!("name {name}")),
        kind,
        step_length_m: 0.3,
        rise_m: rise,
        tread_m: if rise == 0.0 { 0.0 } else { 0.28 },
        step_time_s: 2.24,
        pace_m_s: 0.12,
        clearance_m: 0.05,
        // The descent carries none: the device's own limit.
        stance_hip_residual_nm: match kind {
            GaitKind::Walk => 70,
            GaitKind::StairUp => 85,
            GaitKind::StairDown => 0,
        },
    }
}

fn sources() -> Vec<GaitSource<'static>> {
    vec![
        GaitSource {
            info: info("walk-0.12", GaitKind::Walk, 0.0),
            table: &WALK,
        },
        GaitSource {
            info: info("up-0.094", GaitKind::StairUp, 0.0935),
            table: &STAIR_UP,
        },
        GaitSource {
            info: info("down-0.094", GaitKind::StairDown, -0.0935),
            table: &STAIR_DOWN,
        },
    ]
}

fn image() -> Vec<u8> {
    let g = sources();
    let mut buf = vec![0u8; bundle_len(&g)];
    let n = encode(DEVICE, 0x0001_0000, &patient(), &g, &mut buf).expect("encodes");
    assert_eq!(n, buf.len());
    buf
}

#[test]
fn round_trip() {
    let img = image();
    let b = Bundle::parse(&img, DEVICE).expect("verifies");
    assert_eq!(b.len(), 3);
    assert_eq!(b.device_fingerprint(), DEVICE);
    assert_eq!(b.generator_version(), 0x0001_0000);
    assert_eq!(b.patient(), &patient());
    assert_eq!(b.patient_hash(), patient().hash());
    let names: Vec<String> = (0..b.len())
        .filter_map(|i| b.gait(i))
        .map(|g| g.info.name.as_str().to_owned())
        .collect();
    assert_eq!(names, ["walk-0.12", "up-0.094", "down-0.094"]);
    let (i, up) = b.find("up-0.094").expect("found");
    assert_eq!(i, 1);
    assert_eq!(up.table.kind(), GaitKind::StairUp);
    assert_eq!(up.info.rise_m, 0.0935);
    // The stance hip's residual limit reaches the table the board plays.
    assert_eq!(up.info.stance_hip_residual_nm, 85);
    assert_eq!(up.table.stance_hip_residual_nm(), 85.0);
    let down = b.gait(2).expect("the descent");
    assert_eq!(down.info.stance_hip_residual_nm, 0);
    assert!(down.table.stance_hip_residual_nm().is_nan());
    assert!(b.gait(3).is_none());
    assert!(b.find("walk").is_none());
}

#[test]
fn a_sector_holds_the_bundle_and_erased_flash_after_it() {
    let img = image();
    let mut sector = vec![0xFFu8; 128 * 1024];
    sector[..img.len()].copy_from_slice(&img);
    assert_eq!(stored_len(&sector), Some(img.len()));
    let b = Bundle::parse_sector(&sector, DEVICE).expect("verifies");
    assert_eq!(
        b.crc(),
        u32::from_le_bytes(img[img.len() - 4..].try_into().unwrap())
    );
    let erased = vec![0xFFu8; 4096];
    assert_eq!(
        Bundle::parse_sector(&erased, DEVICE),
        Err(BundleError::BadMagic)
    );
}

#[test]
fn every_flipped_bit_is_refused() {
    let img = image();
    // Every byte of the header, patient block and directory, and a stride
    // through the tables and the trailer.
    let dir_end = 288 + 3 * 56;
    let bytes = (0..dir_end)
        .chain((dir_end..img.len()).step_by(97))
        .chain([img.len() - 1]);
    for byte in bytes {
        for bit in 0..8 {
            let mut b = img.clone();
            b[byte] ^= 1 << bit;
            assert!(
                Bundle::parse(&b, DEVICE).is_err(),
                "flip at {byte}:{bit} accepted"
            );
        }
    }
}

#[test]
fn truncated_foreign_and_unknown_are_refused_by_name() {
    let img = image();
    assert_eq!(
        Bundle::parse(&img[..img.len() - 1], DEVICE),
        Err(BundleError::BadLength)
    );
    assert_eq!(
        Bundle::parse(&img[..10], DEVICE),
        Err(BundleError::BadLength)
    );
    assert_eq!(
        Bundle::parse(&img, 0xDEAD_BEEF),
        Err(BundleError::ForeignDevice {
            bundle: DEVICE,
            device: 0xDEAD_BEEF
        })
    );
    assert_eq!(Bundle::parse(&WALK, DEVICE), Err(BundleError::BadMagic));
    let mut v = img.clone();
    v[4] = 9;
    assert_eq!(
        Bundle::parse(&v, DEVICE),
        Err(BundleError::UnknownVersion(9))
    );
}

#[test]
fn the_writer_refuses_what_the_reader_would() {
    let p = patient();
    let mut buf = vec![0u8; 64 * 1024];
    assert_eq!(
        encode(DEVICE, 1, &p, &[], &mut buf),
        Err(BundleError::BadGaitCount)
    );
    let mut wrong_kind = sources();
    wrong_kind[0].info.kind = GaitKind::StairUp;
    assert_eq!(
        encode(DEVICE, 1, &p, &wrong_kind, &mut buf),
        Err(BundleError::KindMismatch(0))
    );
    let mut nan = sources();
    nan[2].info.pace_m_s = f32::NAN;
    assert_eq!(
        encode(DEVICE, 1, &p, &nan, &mut buf),
        Err(BundleError::BadEntry(2))
    );
    let mut broken = WALK.to_vec();
    broken[100] ^= 1;
    let leaked: &'static [u8] = Box::leak(broken.into_boxed_slice());
    let mut bad_table = sources();
    bad_table[0].table = leaked;
    assert!(matches!(
        encode(DEVICE, 1, &p, &bad_table, &mut buf),
        Err(BundleError::Table(0, _))
    ));
    let mut small = vec![0u8; 100];
    assert_eq!(
        encode(DEVICE, 1, &p, &sources(), &mut small),
        Err(BundleError::BufferTooSmall)
    );
}

#[test]
fn names_are_short_printable_ascii() {
    assert!(GaitName::new("walk-0.30").is_some());
    assert!(GaitName::new("").is_none());
    assert!(GaitName::new("a name with space").is_none());
    assert!(GaitName::new("seventeen-chars-x").is_none());
    assert!(GaitName::new("gehen-ä").is_none());
}
