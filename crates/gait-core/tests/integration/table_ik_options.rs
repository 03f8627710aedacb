//! The IK options in a gait table's header (format version 2): written by
//! the encoder, read back by the parser, checked with `IkOptions::new`, and
//! the flash tables carry the options they were generated with.

use gait_core::flash_tables;
use gait_core::ik::{IkOptions, KneeRange};
use gait_core::problem::PeriodicStep;
use gait_core::tables::{
    FORMAT_VERSION, GaitKind, GaitTable, HEADER_LEN, IK_CAP_OFFSET, IK_RANGE_OFFSET, MAGIC,
    SAMPLE_LEN, TableError, encode, image_len,
};

const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

const SAMPLES: [[f32; 5]; 3] = [
    [0.0, 0.1, 0.0, 3.0, 3.2],
    [0.1, 0.0, 0.05, 2.9, 3.3],
    [0.2, -0.1, 0.1, 2.8, 3.4],
];

fn image(ik: IkOptions<f32>) -> Vec<u8> {
    let mut buf = vec![0u8; image_len(SAMPLES.len())];
    let n = encode(GaitKind::StairDown, 10_000, ik, &SAMPLES, &mut buf).unwrap();
    assert_eq!(n, buf.len());
    buf
}

/// Rewrites the CRC after an edit, so that only the edited field is wrong.
fn fix_crc(img: &mut [u8]) {
    let end = img.len() - 4;
    let crc = CRC32.checksum(&img[..end]);
    img[end..].copy_from_slice(&crc.to_le_bytes());
}

#[test]
fn the_header_is_version_2_with_the_samples_after_24_bytes() {
    assert_eq!(FORMAT_VERSION, 2);
    assert_eq!(HEADER_LEN, 24);
    assert_eq!(HEADER_LEN % 8, 0);
    assert_eq!(image_len(3), 24 + 3 * SAMPLE_LEN + 4);
    let img = image(IkOptions::paper());
    assert_eq!(&img[..4], &MAGIC);
    assert_eq!(u16::from_le_bytes([img[4], img[5]]), 2);
    // The reserved bytes after the knee-range tag are zero.
    assert_eq!(&img[21..24], &[0, 0, 0]);
    // The first sample starts right after the header.
    assert_eq!(&img[24..28], &SAMPLES[0][0].to_le_bytes());
}

#[test]
fn ik_options_round_trip_through_encode_and_parse() {
    let options = [
        IkOptions::paper(),
        PeriodicStep::<f32>::stair_down().ik,
        IkOptions::new(60f32.to_radians(), KneeRange::Human).unwrap(),
        IkOptions::new(core::f32::consts::FRAC_PI_2, KneeRange::Reach).unwrap(),
        IkOptions::new(1e-6, KneeRange::Human).unwrap(),
    ];
    for ik in options {
        let img = image(ik);
        // Little-endian f32 cap at 16, the tag at 20.
        let cap = f32::from_le_bytes(img[IK_CAP_OFFSET..IK_CAP_OFFSET + 4].try_into().unwrap());
        assert_eq!(cap.to_bits(), ik.stance_knee_max_rad.to_bits());
        let tag = match ik.knee_range {
            KneeRange::Reach => 0,
            KneeRange::Human => 1,
        };
        assert_eq!(img[IK_RANGE_OFFSET], tag);
        let t = GaitTable::parse(&img).unwrap();
        assert_eq!(t.ik_options(), ik);
        // The rest of the table is unaffected.
        assert_eq!(t.kind(), GaitKind::StairDown);
        assert_eq!(t.len(), SAMPLES.len());
        assert_eq!(t.sample(2), Some(SAMPLES[2]));
    }
}

#[test]
fn a_corrupted_ik_field_with_a_valid_crc_is_refused() {
    let good = image(PeriodicStep::<f32>::stair_down().ik);
    let caps = [
        0.0,
        -0.5,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        2.0,
        // The next f32 above π/2.
        f32::from_bits(core::f32::consts::FRAC_PI_2.to_bits() + 1),
    ];
    for cap in caps {
        let mut img = good.clone();
        img[IK_CAP_OFFSET..IK_CAP_OFFSET + 4].copy_from_slice(&cap.to_le_bytes());
        fix_crc(&mut img);
        assert_eq!(
            GaitTable::parse(&img),
            Err(TableError::BadIkOptions),
            "cap {cap}"
        );
    }
    for tag in [2u8, 3, 0x80, 0xff] {
        let mut img = good.clone();
        img[IK_RANGE_OFFSET] = tag;
        fix_crc(&mut img);
        assert_eq!(
            GaitTable::parse(&img),
            Err(TableError::BadIkOptions),
            "tag {tag}"
        );
    }
    // A valid edit with the CRC fixed is a valid table with those options.
    let mut img = good.clone();
    img[IK_RANGE_OFFSET] = 0;
    fix_crc(&mut img);
    assert_eq!(
        GaitTable::parse(&img).unwrap().ik_options().knee_range,
        KneeRange::Reach
    );
    assert!(!TableError::BadIkOptions.to_string().is_empty());
}

#[test]
fn the_writer_refuses_ik_options_the_reader_would() {
    let mut buf = vec![0u8; image_len(SAMPLES.len())];
    for cap in [0.0, -1.0, f32::NAN, f32::INFINITY, 1.6] {
        let ik = IkOptions {
            stance_knee_max_rad: cap,
            knee_range: KneeRange::Human,
        };
        assert_eq!(
            encode(GaitKind::Walk, 10_000, ik, &SAMPLES, &mut buf),
            Err(TableError::BadIkOptions),
            "cap {cap}"
        );
    }
}

/// A version-1 image (16-byte header, no IK options), written as the
/// version-1 writer did.
fn version_1_image() -> Vec<u8> {
    let mut img = Vec::new();
    img.extend_from_slice(&MAGIC);
    img.extend_from_slice(&1u16.to_le_bytes());
    img.extend_from_slice(&[0, 0]);
    img.extend_from_slice(&10_000u32.to_le_bytes());
    img.extend_from_slice(&(SAMPLES.len() as u16).to_le_bytes());
    img.extend_from_slice(&[0, 0]);
    for v in SAMPLES.iter().flatten() {
        img.extend_from_slice(&v.to_le_bytes());
    }
    let crc = CRC32.checksum(&img);
    img.extend_from_slice(&crc.to_le_bytes());
    assert_eq!(img.len(), 16 + SAMPLES.len() * SAMPLE_LEN + 4);
    img
}

#[test]
fn version_1_images_are_refused_with_the_version_error() {
    assert_eq!(
        GaitTable::parse(&version_1_image()),
        Err(TableError::UnknownVersion(1))
    );
    // A version-2 image relabelled as version 1 (CRC fixed) too.
    let mut img = image(IkOptions::paper());
    img[4..6].copy_from_slice(&1u16.to_le_bytes());
    fix_crc(&mut img);
    assert_eq!(GaitTable::parse(&img), Err(TableError::UnknownVersion(1)));
}

#[test]
fn the_flash_tables_carry_the_ik_options_they_were_generated_with() {
    // The descent's are its periodic step's (Human range, 90° cap), as the
    // sequencer assumed before the tables carried them.
    let down = flash_tables::stair_down().unwrap();
    assert_eq!(down.ik_options(), PeriodicStep::<f32>::stair_down().ik);
    // All three are clinical-mode steps (gait-opt's `ClinicalCase`, whose
    // options gait-opt's `flash_tables` test compares exactly): the Human
    // knee range, and every sample's stance knee within the cap the IK
    // chose its thigh under (φ2 ∈ [φ1 − cap, φ1]).
    for kind in [GaitKind::Walk, GaitKind::StairUp, GaitKind::StairDown] {
        let t = flash_tables::of(kind).unwrap();
        let ik = t.ik_options();
        assert_eq!(ik.knee_range, KneeRange::Human, "{kind:?}");
        assert_eq!(
            IkOptions::new(ik.stance_knee_max_rad, ik.knee_range),
            Ok(ik)
        );
        for k in 0..t.len() {
            let phi = t.sample(k).unwrap();
            let flexion = phi[0] - phi[1];
            assert!(
                flexion <= ik.stance_knee_max_rad + 1e-5,
                "{kind:?} sample {k}: stance knee {flexion} rad over the cap {}",
                ik.stance_knee_max_rad
            );
        }
    }
}
