//! The application loop on the host: scans in, frames out, compared with pfe-core run
//! directly on the same codes and with the analytic scene.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use firmware::app::{App, AppError, ConfigChoice, RawScan, ScanSource};
use pfe_core::{Extractor, Feature, Scan, ScanGeometry};
use pfe_frame::{Counters, Feed, Frame, FrameDecoder, ScanStatus};

const G: ScanGeometry = ScanGeometry::LMS200_180_050;

/// A room: wall x = 2500 mm ahead, wall y = 1800 mm on the left, a pillar of radius 150 mm at
/// (1500, −600); everything else out of range. Codes in mm.
fn room(shift: f32) -> Vec<u16> {
    (0..361)
        .map(|i| {
            let b = G.bearing(i);
            let (c, s) = (b.cos(), b.sin());
            let mut r = f32::INFINITY;
            if c > 1e-3 {
                r = r.min((2500.0 + shift) / c);
            }
            if s > 1e-3 {
                r = r.min(1800.0 / s);
            }
            // Ray-circle intersection.
            let (cx, cy, rad) = (1500.0f32, -600.0f32, 150.0f32);
            let t = cx * c + cy * s;
            let d2 = cx * cx + cy * cy - t * t;
            if d2 < rad * rad && t > 0.0 {
                r = r.min(t - (rad * rad - d2).sqrt());
            }
            if r.is_finite() && r <= 8182.0 {
                r.round() as u16
            } else {
                8183
            }
        })
        .collect()
}

struct Source {
    scans: Vec<Vec<u16>>,
    next: usize,
}

impl ScanSource for Source {
    type Error = &'static str;
    fn next_scan(&mut self) -> Result<(RawScan<'_>, Counters), Self::Error> {
        let v = self.scans.get(self.next).ok_or("no more scans")?;
        self.next += 1;
        let counters = Counters {
            telegrams_ok: self.next as u32,
            crc_dropped: 2,
            bytes_skipped: 11,
            reinits: 0,
        };
        Ok((RawScan::lms_8m(G, v, 1.0), counters))
    }
}

struct Writer(Vec<u8>);
impl embedded_io::ErrorType for Writer {
    type Error = core::convert::Infallible;
}
impl embedded_io::Write for Writer {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.0.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

fn frames(bytes: &[u8]) -> Vec<Frame> {
    let mut dec = FrameDecoder::<8192>::new();
    let mut rest = bytes;
    let mut out = Vec::new();
    loop {
        match dec.feed(rest) {
            Feed::Consumed => return out,
            Feed::Frame { frame, remaining } => {
                out.push(frame);
                rest = remaining;
            }
            Feed::Error { error, .. } => panic!("{error}"),
        }
    }
}

fn direct(values: &[u16], choice: ConfigChoice) -> Vec<Feature> {
    let mut ex = Extractor::<361, 48>::new();
    let _ = ex.extract(&Scan::from_lms(G, values, 1.0), &choice.config());
    ex.features().to_vec()
}

#[test]
fn loop_sends_one_frame_per_scan_equal_to_direct_extraction() {
    for choice in [ConfigChoice::Paper, ConfigChoice::Default] {
        let scans: Vec<Vec<u16>> = (0..4).map(|k| room(k as f32 * 40.0)).collect();
        let mut src = Source {
            scans: scans.clone(),
            next: 0,
        };
        let mut app = App::<361, 48>::new(choice);
        let mut out = Writer(Vec::new());
        for _ in 0..4 {
            app.step(&mut src, &mut out).unwrap();
        }
        assert!(matches!(
            app.step(&mut src, &mut out),
            Err(AppError::Source("no more scans"))
        ));
        let got = frames(&out.0);
        assert_eq!(got.len(), 4);
        for (k, (f, v)) in got.iter().zip(&scans).enumerate() {
            let h = f.scan().unwrap();
            assert_eq!(h.seq, k as u32);
            assert_eq!(h.counters.telegrams_ok, k as u32 + 1);
            assert_eq!(h.counters.crc_dropped, 2);
            assert_eq!(h.status, ScanStatus::Ok);
            let sent: Vec<Feature> = f.features.to_vec();
            assert_eq!(sent, direct(v, choice), "{choice:?} scan {k}");
        }
    }
}

#[test]
fn default_config_finds_the_room_geometry() {
    let mut app = App::<361, 48>::new(ConfigChoice::Default);
    let mut out = Writer(Vec::new());
    let values = room(0.0);
    let scan = RawScan::lms_8m(G, &values, 1.0);
    app.process(&scan, Counters::default(), &mut out).unwrap();
    let f = &frames(&out.0)[0];
    let feats: Vec<Feature> = f.features.to_vec();
    // Noise-free but for the rounding of ranges to whole mm (σ = 1/√12 mm): the fits are
    // within a fraction of a mm and a few 10⁻⁴ rad of the room. Exactly four features: the
    // front wall in two pieces (the pillar's shadow), the left wall and the pillar.
    let (mut front, mut left, mut pillars) = (0, 0, 0);
    for f in &feats {
        match f {
            Feature::Line(l) if l.alpha.abs() < 0.1 => {
                front += 1;
                assert!(
                    l.alpha.abs() < 5e-4 && (l.rho - 2500.0).abs() < 0.5,
                    "front wall {l:?}"
                );
            }
            Feature::Line(l) if (l.alpha - core::f32::consts::FRAC_PI_2).abs() < 0.1 => {
                left += 1;
                assert!(
                    (l.alpha - core::f32::consts::FRAC_PI_2).abs() < 5e-4
                        && (l.rho - 1800.0).abs() < 0.5,
                    "left wall {l:?}"
                );
            }
            Feature::Circle(c) => {
                pillars += 1;
                assert!(
                    (c.center.x - 1500.0).abs() < 1.0
                        && (c.center.y + 600.0).abs() < 1.0
                        && (c.radius - 150.0).abs() < 1.0,
                    "pillar {c:?}"
                );
            }
            other => panic!("spurious feature {other:?}"),
        }
    }
    assert_eq!((front, left, pillars), (2, 1, 1), "{feats:#?}");
}

#[test]
fn cm_mode_scales_ranges() {
    let mm = room(0.0);
    let cm: Vec<u16> = mm
        .iter()
        .map(|&v| {
            if v > 8182 {
                v
            } else {
                (f32::from(v) / 10.0).round() as u16
            }
        })
        .collect();
    let mut app = App::<361, 48>::new(ConfigChoice::Default);
    let mut out = Writer(Vec::new());
    let scan = RawScan::lms_8m(G, &cm, 10.0);
    app.process(&scan, Counters::default(), &mut out).unwrap();
    let f = &frames(&out.0)[0];
    assert!(f.features.iter().any(|w| match *w {
        Feature::Line(l) => l.alpha.abs() < 0.03 && (l.rho - 2500.0).abs() < 30.0,
        _ => false,
    }));
}

#[test]
fn too_many_readings_and_full_buffer_are_reported_not_hidden() {
    let values = room(0.0);
    let scan = RawScan::lms_8m(G, &values, 1.0);
    let mut small = App::<100, 48>::new(ConfigChoice::Default);
    let mut out = Writer(Vec::new());
    let h = small.process(&scan, Counters::default(), &mut out).unwrap();
    assert_eq!(h.status, ScanStatus::TooManyReadings);
    assert_eq!(frames(&out.0)[0].features.len(), 0);

    let mut one = App::<361, 1>::new(ConfigChoice::Default);
    let mut out = Writer(Vec::new());
    let h = one.process(&scan, Counters::default(), &mut out).unwrap();
    assert_eq!(h.status, ScanStatus::FeatureCapacity);
    assert_eq!(h.n_features, 1);
    assert!(h.dropped >= 2, "{h:?}");
    assert_eq!(frames(&out.0)[0].features.len(), 1);
}

#[test]
fn output_errors_propagate() {
    let values = room(0.0);
    let scan = RawScan::lms_8m(G, &values, 1.0);
    let mut app = App::<361, 48>::new(ConfigChoice::Paper);
    let mut tiny = [0u8; 8];
    let mut out = &mut tiny[..];
    assert!(app.process(&scan, Counters::default(), &mut out).is_err());
}

/// The module docs' RAM figure for an `App<N, M>`, about 25·N + 68·M bytes and 7.7 KiB (7 900 B) for
/// the pose step: within 1 KiB of the real size for short and long scans, few and many features.
#[test]
fn app_size_matches_the_documented_figure() {
    use core::mem::size_of;
    let pose = size_of::<firmware::app::PoseStep>();
    assert!(pose.abs_diff(7900) < 100, "the pose step: {pose} B");
    let sizes = [
        (181, 16, size_of::<App<181, 16>>()),
        (401, 48, size_of::<App<401, 48>>()),
        (401, 96, size_of::<App<401, 96>>()),
        (801, 48, size_of::<App<801, 48>>()),
    ];
    for (n, m, real) in sizes {
        let figure = 25 * n + 68 * m + 7900;
        assert!(
            real.abs_diff(figure) < 1024,
            "App<{n}, {m}>: {real} B, the docs say about {figure} B"
        );
    }
    // The per-point and per-feature parts, not only the total.
    assert_eq!(sizes[3].2 - sizes[1].2, 25 * 400);
    assert_eq!(sizes[2].2 - sizes[1].2, 68 * 48);
}
