//! Adversarial scans for the worst-case bound (`cargo xtask bench-mcu --worst`): structured
//! scans that stress each part of pfe-core's default mode, and a hill-climb on
//! [`pfe_core::Stats`] work counters that looks for more.
//!
//! Every scan is LMS range codes (as a B0 telegram carries them) with its unit: 361 values
//! (180° at 0.5°) unless stated, 401 values for 100° at 0.25°.

use pfe_core::{Config, Extractor, Feature, Ranges, Scan, ScanGeometry, Stats, LMS_MAX_VALID_8M};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One adversarial scan.
#[derive(Clone, Debug, PartialEq)]
pub struct AdversarialScan {
    /// What it stresses (the table's row).
    pub kind: &'static str,
    /// Range codes (0 = no return).
    pub codes: Vec<u16>,
    /// True in mm mode, false in cm mode (10 mm per code).
    pub mm: bool,
}

impl AdversarialScan {
    fn new(kind: &'static str, codes: Vec<u16>, mm: bool) -> Self {
        Self { kind, codes, mm }
    }

    /// Beam geometry of the scan's LMS200 variant (from its value count), `r_max` the
    /// unit's largest valid range (as the firmware's driver sets it).
    pub fn geometry(&self) -> ScanGeometry {
        let mut g = match self.codes.len() {
            401 => ScanGeometry::lms200(100.0, 0.25),
            201 => ScanGeometry::lms200(100.0, 0.5),
            181 => ScanGeometry::lms200(180.0, 1.0),
            101 => ScanGeometry::lms200(100.0, 1.0),
            _ => ScanGeometry::LMS200_180_050,
        };
        g.r_max = f32::from(LMS_MAX_VALID_8M) * self.mm_per_unit();
        g
    }

    /// mm per range code.
    pub fn mm_per_unit(&self) -> f32 {
        if self.mm {
            1.0
        } else {
            10.0
        }
    }

    /// The host's [`Work`] of the board's default configuration on this scan
    /// (`ConfigChoice::Default`: the worst case is the board's).
    pub fn stats(&self) -> Work {
        // As the firmware builds it (`RawScan::to_pfe`): sweeps from the variant, grid from
        // the codes.
        let ranges = Ranges::Raw {
            values: &self.codes,
            mm_per_unit: self.mm_per_unit(),
            max_valid: LMS_MAX_VALID_8M,
        };
        let scan = Scan::lms2xx(self.geometry(), ranges);
        let mut ex = Extractor::<401, 48>::new();
        let _ = ex.extract(&scan, &BOARD_CONFIG);
        let circles = ex
            .features()
            .iter()
            .filter(|f| matches!(f, Feature::Circle(_)))
            .count();
        Work {
            stats: ex.stats(),
            circles,
        }
    }
}

/// The board firmware's configuration, `firmware::app::ConfigChoice::Default` (host-tests'
/// `board_config` test keeps the two equal; pfe-eval does not depend on the firmware crate).
pub const BOARD_CONFIG: Config = Config::default_config().for_lms2xx();

/// What pfe-core did with a scan: its counters and the circles among its features (a circle
/// costs an algebraic fit and its geometric refinement).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Work {
    /// pfe-core's counters.
    pub stats: Stats,
    /// Circle features.
    pub circles: usize,
}

/// Codes of a straight wall at perpendicular distance `d` mm, normal at bearing `phi`, seen
/// by beam `i` of `g` (`None` where the beam runs away from it).
fn wall(g: &ScanGeometry, i: usize, d: f32, phi: f32) -> Option<f32> {
    let c = (g.bearing(i) - phi).cos();
    (c > 0.05).then(|| d / c)
}

fn code(mm: f32, mm_per_unit: f32) -> u16 {
    (mm / mm_per_unit)
        .round()
        .clamp(1.0, f32::from(LMS_MAX_VALID_8M)) as u16
}

/// Range of beam `i` on a circle of radius `r` centred at range `c` on beam `centre`
/// (`None` where it misses).
fn circle(g: &ScanGeometry, i: usize, centre: usize, c: f32, r: f32) -> Option<f32> {
    let t = g.bearing(i) - g.bearing(centre);
    let b = c * t.cos();
    let disc = b * b - (c * c - r * r);
    (disc >= 0.0).then(|| b - disc.sqrt())
}

/// `n` codes from `f` (range in mm per beam, `None` no return).
fn scan_of(n: usize, mm_per_unit: f32, mut f: impl FnMut(usize) -> Option<f32>) -> Vec<u16> {
    (0..n)
        .map(|i| f(i).map_or(0, |r| code(r, mm_per_unit)))
        .collect()
}

/// Arcs of `width` beams side by side (pillars of radius `r` at range `c`).
fn arcs(g: &ScanGeometry, n: usize, width: usize, c: f32, r: f32, mm_per_unit: f32) -> Vec<u16> {
    scan_of(n, mm_per_unit, |i| {
        let centre = i - i % width + width / 2;
        circle(g, i, centre, c, r).or(Some(c))
    })
}

/// The structured adversarial scans (deterministic).
pub fn structured() -> Vec<AdversarialScan> {
    let g = ScanGeometry::LMS200_180_050;
    let g401 = ScanGeometry::lms200(100.0, 0.25);
    let mut rng = ChaCha8Rng::seed_from_u64(20);
    let mut out = Vec::new();
    let mut add = |kind, codes, mm| out.push(AdversarialScan::new(kind, codes, mm));
    // Zigzags: walls meeting at corners every `p` beams (a boundary to locate and refine at
    // each corner, a merge test after each).
    for p in [6usize, 9, 12] {
        let codes = scan_of(361, 1.0, |i| {
            let t = (i % (2 * p)) as f32 / p as f32;
            let tri = if t < 1.0 { t } else { 2.0 - t };
            Some(2000.0 + 300.0 * tri)
        });
        add("zigzag", codes, true);
    }
    // Every beam a breakpoint: a jump at every beam.
    let codes = scan_of(361, 1.0, |i| Some(if i % 2 == 0 { 1500.0 } else { 4000.0 }));
    add("every beam a breakpoint", codes, true);
    // All short segments: runs of 2 or 3 beams (below min_points), a jump between them.
    for w in [2usize, 3] {
        let codes = scan_of(361, 1.0, |i| {
            Some(if (i / w) % 2 == 0 { 1800.0 } else { 3000.0 })
        });
        add("all short segments", codes, true);
    }
    // All arcs: pillars side by side (arc fits, circle typing and refinement per segment).
    for (w, c, r) in [
        (16usize, 1000.0, 50.0),
        (12, 2000.0, 120.0),
        (24, 1200.0, 150.0),
    ] {
        add("all arcs", arcs(&g, 361, w, c, r, 1.0), true);
    }
    // Features at capacity and beyond: 4- to 7-beam walls at alternating depths, each its
    // own feature (more segments than the 48 features the firmware keeps).
    for w in [4usize, 5, 7] {
        let codes = scan_of(361, 1.0, |i| {
            let d = if (i / w) % 2 == 0 { 1600.0 } else { 2600.0 };
            wall(&g, i, d, g.bearing(i - i % w))
        });
        add("features at capacity", codes, true);
    }
    // Alternating invalid readings: every other beam (or every third) no return.
    for p in [2usize, 3] {
        let codes = scan_of(361, 1.0, |i| {
            (i % p != 0).then(|| wall(&g, i, 2500.0, 0.0))?
        });
        add("alternating invalid", codes, true);
    }
    // 401 values at 0.25°: zigzag, arcs and noise over the longest scan.
    let codes = scan_of(401, 1.0, |i| {
        let t = (i % 16) as f32 / 8.0;
        Some(2000.0 + 200.0 * if t < 1.0 { t } else { 2.0 - t })
    });
    for codes in [codes, arcs(&g401, 401, 10, 1500.0, 40.0, 1.0)] {
        add("401 values at 0.25°", codes, true);
    }
    // cm mode: ranges up to 81.82 m (a far wall, arcs far away, jumps across the range).
    let far_wall = scan_of(361, 10.0, |i| {
        wall(&g, i, 30_000.0, 0.0).map(|r| r.min(81_820.0))
    });
    let far_arcs = arcs(&g, 361, 12, 60_000.0, 3_000.0, 10.0);
    let jumps = scan_of(361, 10.0, |i| {
        Some(if (i / 5) % 2 == 0 { 81_820.0 } else { 20_000.0 })
    });
    for codes in [far_wall, far_arcs, jumps] {
        add("cm mode to 81.82 m", codes, false);
    }
    // Near-collinear noise: a wall with noise at the edge of the line test, so the cached
    // window keeps failing and is refitted (and arcs, boundaries tried) at many points.
    for amp in [8.0f32, 12.0, 16.0, 24.0] {
        let codes = scan_of(361, 1.0, |i| {
            let n: f32 = rng.gen_range(-amp..=amp);
            wall(&g, i, 2000.0, 0.0).map(|r| r + n)
        });
        add("near-collinear noise", codes, true);
    }
    out
}

/// The work a scan causes, by its counters: predictions (one per point and test), segments,
/// features fitted, and circles weighted by their refinement (weights: rough instruction
/// ratios, predictions the unit).
pub fn work(w: &Work) -> usize {
    let s = &w.stats;
    s.predictions + 8 * s.segments + 32 * (s.features + s.dropped + s.degenerate) + 400 * w.circles
}

/// Random-mutation hill-climb on [`work`] from each structured scan of 361 or 401 values in
/// mm mode: `iterations` mutations (a few beams moved, blanked or copied from a
/// neighbour), kept when the work does not drop; returns the `keep` scans with the most work.
pub fn search(seed: u64, iterations: usize, keep: usize) -> Vec<AdversarialScan> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut found: Vec<(usize, AdversarialScan)> = Vec::new();
    let starts: Vec<AdversarialScan> = structured().into_iter().filter(|s| s.mm).collect();
    let per_start = iterations / starts.len().max(1);
    for start in starts {
        let mut best = AdversarialScan::new("searched", start.codes.clone(), start.mm);
        let mut best_work = work(&best.stats());
        for _ in 0..per_start {
            let mut cand = best.clone();
            let n = cand.codes.len();
            for _ in 0..rng.gen_range(1..=4) {
                let i = rng.gen_range(0..n);
                let v = match rng.gen_range(0..4) {
                    0 => 0,
                    1 => cand.codes.get(i.saturating_sub(1)).copied().unwrap_or(0),
                    2 => rng.gen_range(500..6000),
                    _ => {
                        let c = cand.codes.get(i).copied().unwrap_or(0);
                        c.saturating_add_signed(rng.gen_range(-30..=30))
                    }
                };
                if let Some(slot) = cand.codes.get_mut(i) {
                    *slot = v;
                }
            }
            let w = work(&cand.stats());
            if w >= best_work {
                best = cand;
                best_work = w;
            }
        }
        found.push((best_work, best));
    }
    found.sort_by_key(|f| std::cmp::Reverse(f.0));
    found.into_iter().take(keep).map(|(_, s)| s).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn structured_scans_are_lms_scans_that_work_hard() {
        let all = structured();
        for s in &all {
            assert!(matches!(s.codes.len(), 361 | 401), "{}", s.kind);
            assert!(s.codes.iter().all(|&c| c <= LMS_MAX_VALID_8M), "{}", s.kind);
        }
        let stats = |kind| {
            all.iter()
                .filter(|s| s.kind == kind)
                .map(AdversarialScan::stats)
                .collect::<Vec<_>>()
        };
        assert!(stats("every beam a breakpoint")
            .iter()
            .all(|w| w.stats.segments >= 300));
        assert!(stats("features at capacity")
            .iter()
            .any(|w| w.stats.dropped > 0));
        // Runs of 1–3 returns between jumps: short segments, or (3 returns ≤ 0.3 m across) small
        // objects, which take their run as one segment (those past the capacity dropped).
        let short = stats("all short segments");
        assert!(
            short
                .iter()
                .all(|w| w.stats.short_segments + w.stats.objects + w.stats.dropped >= 100),
            "{:?}",
            short.iter().map(|w| w.stats).collect::<Vec<_>>()
        );
        let arcs = stats("all arcs");
        // The circle path (algebraic fit, refinement) is exercised: with the board's
        // extraction (the checks for real scans, 2 sweeps at 0.5°) the pillars of 150 mm at
        // 1.2 m are circles; the touching 50 mm and 120 mm ones are typed as lines there (see
        // the closing note of issue 39's stop 44).
        assert!(
            arcs.iter().any(|w| w.circles >= 10),
            "{:?}",
            arcs.iter()
                .map(|w| (w.circles, w.stats))
                .collect::<Vec<_>>()
        );
    }

    #[test]
    fn search_is_deterministic_and_never_loses_work() {
        let a = search(7, 60, 2);
        assert_eq!(a, search(7, 60, 2));
        let most = structured()
            .iter()
            .filter(|s| s.mm)
            .map(|s| work(&s.stats()))
            .max()
            .unwrap_or(0);
        assert!(a.first().is_some_and(|s| work(&s.stats()) >= most));
    }
}
