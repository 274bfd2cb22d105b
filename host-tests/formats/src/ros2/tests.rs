//! Unit tests of the ROS 2 reader.

use super::*;
use crate::MAX_BEAMS;

/// A LaserScan in CDR, `little` or big endian, frame `frame` (its length moves the
/// alignment of every later field).
fn encode(little: bool, frame: &str, ranges: &[f32], intensities: &[f32]) -> Vec<u8> {
    let w = |b: &mut Vec<u8>, v: u32| {
        while (b.len() - 4) % 4 != 0 {
            b.push(0xee); // padding: any value
        }
        b.extend(if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        });
    };
    let mut b = vec![0, u8::from(little), 0, 0];
    w(&mut b, 1_700_000_000);
    w(&mut b, 250_000_000);
    w(&mut b, frame.len() as u32 + 1);
    b.extend(frame.as_bytes());
    b.push(0);
    for v in [-1.0f32, 1.0, 0.5, 0.001, 0.1, 0.05, 20.0] {
        w(&mut b, v.to_bits());
    }
    w(&mut b, ranges.len() as u32);
    for r in ranges {
        w(&mut b, r.to_bits());
    }
    w(&mut b, intensities.len() as u32);
    for r in intensities {
        w(&mut b, r.to_bits());
    }
    b
}

#[test]
fn both_byte_orders_and_every_alignment() {
    let ranges = [
        1.0,
        f32::INFINITY,
        0.01,
        20.0,
        20.5,
        f32::NAN,
        -1.0,
        f32::NEG_INFINITY,
        0.05,
    ];
    for little in [true, false] {
        for frame in ["", "a", "ab", "abc", "laser"] {
            let m = LaserScanMsg::decode(&encode(little, frame, &ranges, &[7.0; 9])).unwrap();
            assert_eq!((m.sec, m.nanosec), (1_700_000_000, 250_000_000));
            assert_eq!(m.frame_id, frame);
            assert_eq!(
                (m.angle_min, m.angle_max, m.angle_increment),
                (-1.0, 1.0, 0.5)
            );
            assert_eq!((m.time_increment, m.scan_time), (0.001, 0.1));
            assert_eq!((m.range_min, m.range_max), (0.05, 20.0));
            assert_eq!(m.ranges.len(), 9);
            assert_eq!(m.intensities, [7.0; 9]);
            assert_eq!(m.stamp_ns(), Ok(1_700_000_000_250_000_000));
            let r = m.record(4).unwrap();
            assert_eq!(r.id, 4);
            assert_eq!(r.geometry.r_max, 20_000.0);
            assert_eq!((r.geometry.start_angle, r.geometry.angle_step), (-1.0, 0.5));
            // In range (inclusive) → mm; below range_min, above range_max, NaN, ±inf → NaN.
            let mm: Vec<Option<f32>> = r
                .ranges_mm
                .iter()
                .map(|v| (!v.is_nan()).then_some(*v))
                .collect();
            assert_eq!(
                mm,
                [
                    Some(1000.0),
                    None,
                    None,
                    Some(20_000.0),
                    None,
                    None,
                    None,
                    None,
                    Some(50.0)
                ]
            );
        }
    }
}

#[test]
fn truncation_anywhere_is_an_error_naming_the_field() {
    let b = encode(true, "laser", &[1.0, 2.0], &[]);
    assert!(LaserScanMsg::decode(&b).is_ok());
    for n in 0..b.len() {
        let e = LaserScanMsg::decode(&b[..n]).unwrap_err();
        assert!(matches!(e, CdrError::Truncated { .. }), "cut at {n}: {e}");
    }
}

#[test]
fn lengths_beyond_the_data_are_refused_before_allocating() {
    let mut b = encode(true, "", &[1.0], &[]);
    // ranges count (after header 4 + stamp 8 + string 4+1 pad 3 + 7 floats 28 = offset 44).
    let at = 4 + 44;
    b[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    assert_eq!(
        LaserScanMsg::decode(&b),
        Err(CdrError::Truncated {
            field: "ranges",
            offset: 48
        })
    );
    let mut b = encode(false, "x", &[1.0], &[]);
    b[12..16].copy_from_slice(&0x7fff_ffffu32.to_be_bytes());
    assert!(matches!(
        LaserScanMsg::decode(&b),
        Err(CdrError::Truncated {
            field: "header.frame_id",
            ..
        })
    ));
}

#[test]
fn other_encapsulations_and_bad_strings() {
    let mut b = encode(true, "x", &[1.0], &[]);
    b[1] = 3; // PL_CDR_LE
    assert_eq!(
        LaserScanMsg::decode(&b),
        Err(CdrError::Encapsulation([0, 3]))
    );
    let mut b = encode(true, "x", &[1.0], &[]);
    b[4 + 8 + 4 + 1] = b'y'; // the string's NUL
    assert_eq!(LaserScanMsg::decode(&b), Err(CdrError::BadString));
}

#[test]
fn unusable_scans_are_errors() {
    let m = LaserScanMsg::decode(&encode(true, "", &[], &[])).unwrap();
    assert!(m.record(0).is_err());
    let mut m = LaserScanMsg::decode(&encode(true, "", &[1.0], &[])).unwrap();
    m.angle_increment = 0.0;
    assert!(m.record(0).unwrap_err().contains("unusable geometry"));
    m.angle_increment = 0.5;
    m.range_max = f32::INFINITY;
    assert!(m.record(0).is_err());
    m.range_max = 20.0;
    m.ranges = vec![1.0; MAX_BEAMS + 1];
    assert!(m.record(0).unwrap_err().contains("more than"));
    m.sec = -1;
    assert!(m.stamp_ns().is_err());
}
