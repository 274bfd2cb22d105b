//! Pose benchmark on the shared CARMEN logs: registers every pair of consecutive scans without
//! a prior and compares with the logs' corrected poses.
//!
//! ```text
//! cargo run --release -p pfe-pose --example carmen_bench [-- [--max-pairs N] [--odometry] [LOG.log.gz ...]]
//! ```
//!
//! Without logs named, every `*.log.gz` in `../shared/data/carmen` (beside the checkout) is
//! read; when that folder is absent it says so loudly and exits with status 0 (nothing to
//! measure). Per log and pooled: pairs, failures (error > 0.2 m or > 5°; a pair flagged
//! degenerate whose error lies inside its own 99 % ellipsoid is not one; "none" is),
//! degenerate pairs, translational and rotational error of the registered pairs (median, mean,
//! 95th percentile), the NIS of the "ok" pairs with the reference's own scatter (σ = 15 mm per
//! axis, 0.4°) added to the stated covariance (median; χ²₃'s is 2.37) and how many lie inside
//! the 95 % ellipsoid (χ²₃ < 7.815), and the host time per scan (extraction + registration).
//!
//! The scans are read as `pfe extract --format carmen` reads them: FLASER lines, ranges in m
//! (no return at 0 or at or beyond 50 m, or 81.83 m when the log declares an 80 m laser),
//! bearing −90° + i·180°/(n−1) for odd n and −90° + i·180°/n for even n, the LMS2xx's sweeps
//! for its 0.25°/0.5° steps, the range grid of the readings as the scan's quantum,
//! `Config::default()` with σ_r = 10 mm and σ_sys = 5 mm. The reference motion is
//! `P_{k−1}⁻¹ ⊕ P_k` of the lines' laser poses.
#![allow(clippy::needless_range_loop)]

use std::f32::consts::PI;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::time::Instant;

use pfe_core::{BeamTiming, Config, Extractor, Scan, ScanGeometry};
use pfe_pose::{register_with, wrap, Observation, Odometry, Pose, Status};

/// One scan: ranges (mm, NaN = no return), geometry, laser pose (mm, rad).
struct Record {
    ranges: Vec<f32>,
    geometry: ScanGeometry,
    pose: Pose,
}

fn read_log(path: &Path) -> std::io::Result<Vec<Record>> {
    let file = std::fs::File::open(path)?;
    let reader: Box<dyn BufRead> = if path.extension().is_some_and(|e| e == "gz") {
        Box::new(BufReader::new(flate2::read::MultiGzDecoder::new(file)))
    } else {
        Box::new(BufReader::new(file))
    };
    let mut r_max = 50_000.0f32;
    let mut out = Vec::new();
    for line in reader.lines() {
        let line = line?;
        let mut t = line.split_ascii_whitespace();
        match t.next() {
            Some("PARAM") => {
                let long = t.next() == Some("robot_front_laser_max")
                    && t.next()
                        .and_then(|v| v.parse::<f32>().ok())
                        .is_some_and(|v| v >= 80.0);
                if long {
                    r_max = 81_830.0;
                }
            }
            Some("FLASER") => {
                let Some(n) = t.next().and_then(|v| v.parse::<usize>().ok()) else {
                    continue;
                };
                let ranges: Vec<f32> = t
                    .by_ref()
                    .take(n)
                    .map(|v| {
                        let mm = v.parse::<f32>().unwrap_or(f32::NAN) * 1000.0;
                        if mm > 0.0 && mm < r_max {
                            mm
                        } else {
                            f32::NAN
                        }
                    })
                    .collect();
                let p: Vec<f32> = t.take(3).filter_map(|v| v.parse().ok()).collect();
                if ranges.len() != n || p.len() != 3 {
                    continue;
                }
                let intervals = if n % 2 == 1 { n - 1 } else { n };
                out.push(Record {
                    ranges,
                    geometry: ScanGeometry {
                        start_angle: -PI / 2.0,
                        angle_step: PI / intervals.max(1) as f32,
                        r_max,
                    },
                    pose: Pose::new(p[0] * 1000.0, p[1] * 1000.0, p[2]),
                });
            }
            _ => {}
        }
    }
    Ok(out)
}

/// The coarsest grid (mm) all valid readings lie on (host-tests' `range_quantum`).
fn quantum(ranges: &[f32]) -> f32 {
    let whole: Vec<u32> = ranges
        .iter()
        .filter(|r| r.is_finite())
        .map(|r| r.round() as u32)
        .collect();
    if ranges
        .iter()
        .filter(|r| r.is_finite())
        .any(|r| (r - r.round()).abs() > 0.05)
    {
        return 0.0;
    }
    let mut distinct = whole.clone();
    distinct.sort_unstable();
    distinct.dedup();
    if whole.len() < 20 || distinct.len() < 5 {
        return 0.0;
    }
    [100u32, 50, 25, 20, 10, 5, 2, 1]
        .iter()
        .find(|&&q| whole.iter().all(|m| m % q == 0))
        .map_or(0.0, |&q| q as f32)
}

fn sweeps(g: &ScanGeometry) -> u8 {
    let deg = g.angle_step.abs().to_degrees();
    if [0.25f32, 0.5, 1.0]
        .iter()
        .any(|r| (deg / r - 1.0).abs() < 0.01)
    {
        BeamTiming::lms2xx(deg).sweeps
    } else {
        1
    }
}

#[derive(Default)]
struct Stats {
    pairs: usize,
    /// Failures in two consecutive "ok" pairs whose two-step motion agrees with the
    /// reference's (within 0.2 m and 2°): the middle reference pose is the suspect.
    suspect: usize,
    /// The last pair: (estimate, reference, an "ok" failure not yet counted as suspect).
    last: Option<(Pose, Pose, bool)>,
    failures: usize,
    none: usize,
    degenerate: usize,
    terr: Vec<f64>,
    rerr: Vec<f64>,
    nis: Vec<f64>,
    seconds: f64,
    scans: usize,
    /// Odometry: (metres travelled, translational error m, radians turned, rotational error
    /// rad, and the same errors of the chained pairs) per window.
    windows: Vec<(f64, f64, f64, f64, f64, f64)>,
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let i = ((v.len() - 1) as f64 * q).round() as usize;
    v[i.min(v.len() - 1)]
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// `eᵀ C⁻¹ e` in f64 (`None` when C is singular).
fn nis(c: &[[f64; 3]; 3], e: &[f64; 3]) -> Option<f64> {
    let det = c[0][0] * (c[1][1] * c[2][2] - c[1][2] * c[2][1])
        - c[0][1] * (c[1][0] * c[2][2] - c[1][2] * c[2][0])
        + c[0][2] * (c[1][0] * c[2][1] - c[1][1] * c[2][0]);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let (a, b) = ((j + 1) % 3, (j + 2) % 3);
            let (c1, d) = ((i + 1) % 3, (i + 2) % 3);
            inv[i][j] = (c[a][c1] * c[b][d] - c[a][d] * c[b][c1]) / det;
        }
    }
    let mut s = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            s += e[i] * inv[i][j] * e[j];
        }
    }
    Some(s)
}

fn to_f64(c: &[[f32; 3]; 3]) -> [[f64; 3]; 3] {
    c.map(|r| r.map(f64::from))
}

/// The registration settings: the defaults, or as overridden for experiments by
/// `PFE_POSE_CFG="name=value,..."`.
fn pose_config() -> pfe_pose::Config {
    let mut c = pfe_pose::Config::default();
    let Ok(spec) = std::env::var("PFE_POSE_CFG") else {
        return c;
    };
    for kv in spec.split(',').filter(|s| !s.is_empty()) {
        let (k, v) = kv.split_once('=').unwrap_or((kv, ""));
        let v: f32 = v.parse().unwrap_or(f32::NAN);
        match k {
            "max_translation" => c.max_translation = v,
            "max_rotation" => c.max_rotation = v,
            "floor_alpha" => c.line_floor[0] = v,
            "floor_rho" => c.line_floor[1] = v,
            "point_floor" => c.point_floor = v,
            "min_pair_angle" => c.min_pair_angle = v,
            "gate" => c.gate = v,
            "slack_alpha" => c.slack[0] = v,
            "slack_rho" => c.slack[1] = v,
            "slack_rel" => c.slack[2] = v,
            "overlap_slack" => c.overlap_slack = v,
            "degenerate_sigma" => c.degenerate_sigma = v,
            "overlap_weight" => c.overlap_weight = v,
            "visibility_weight" => c.visibility_weight = v,
            "confirm" => c.confirm = v > 0.0,
            "trusted_length" => c.trusted_length = v,
            "min_score" => c.min_score = v,
            "min_matches" => c.min_matches = v as usize,
            "scale" => c.scale_by_residuals = v > 0.0,
            "ambiguity" => c.ambiguity = v,
            _ => eprintln!("PFE_POSE_CFG: unknown setting {k}"),
        }
    }
    eprintln!("settings: {c:?}");
    c
}

fn run_log(path: &Path, max_pairs: usize, odometry: bool) -> std::io::Result<Stats> {
    let records = read_log(path)?;
    let mut ex = Box::new(Extractor::<1024, 256>::new());
    let cfg = Config::default().with_sigma_r(10.0).with_sigma_sys(5.0);
    let pose_cfg = pose_config();
    let mut st = Stats::default();
    let mut prev: Option<(Vec<Observation>, Pose)> = None;
    let mut odo = Box::new(Odometry::<64>::new(Default::default()));
    let mut track: Vec<(Pose, Pose, Pose)> = Vec::new();
    let mut chained = Pose::IDENTITY;
    for rec in records.iter().take(max_pairs.saturating_add(1)) {
        let t0 = Instant::now();
        let q = quantum(&rec.ranges);
        let scan = Scan::from_mm(rec.geometry, &rec.ranges)
            .with_sweeps(sweeps(&rec.geometry))
            .with_quantum(q);
        let obs: Vec<Observation> = match ex.extract(&scan, &cfg) {
            Ok(_) => ex
                .features()
                .iter()
                .filter_map(Observation::from_feature)
                .collect(),
            Err(_) => Vec::new(),
        };
        let reg = prev
            .as_ref()
            .map(|(p, _)| register_with(p, &obs, None, &pose_cfg));
        if odometry {
            let step = odo.update(&obs, None);
            if let (Some(r), Some((_, p0))) = (reg.as_ref(), prev.as_ref()) {
                if std::env::var_os("BENCH_ODO_STEP").is_some() && r.is_registered() {
                    let truth = p0.inverse().compose(&rec.pose);
                    eprintln!(
                        "STEP {} {} {} {}",
                        (step.rel.x - truth.x).hypot(step.rel.y - truth.y),
                        wrap(step.rel.theta - truth.theta).abs(),
                        (r.rel.x - truth.x).hypot(r.rel.y - truth.y),
                        wrap(r.rel.theta - truth.theta).abs()
                    );
                }
                if std::env::var_os("BENCH_ODO").is_some() {
                    let truth = p0.inverse().compose(&rec.pose);
                    let err = |p: &Pose| {
                        (p.x - truth.x).hypot(p.y - truth.y) > 200.0
                            || wrap(p.theta - truth.theta).abs() > 0.087
                    };
                    if err(&step.rel) != err(&r.rel) {
                        eprintln!(
                            "ODO scan {}: odo bad {} ({:?}) pair bad {} ({:?}) truth {:?} odo {:?} pair {:?}",
                            st.scans, err(&step.rel), step.status, err(&r.rel), r.status, truth, step.rel, r.rel
                        );
                    }
                }
            }
            if let Some(r) = reg.filter(|r| r.is_registered()) {
                chained = chained.compose(&r.rel);
            }
            track.push((step.pose, rec.pose, chained));
        }
        st.seconds += t0.elapsed().as_secs_f64();
        st.scans += 1;
        if let (Some(reg), Some((_, p0))) = (reg, prev.as_ref()) {
            let truth = p0.inverse().compose(&rec.pose);
            st.pairs += 1;
            let e = [
                f64::from(reg.rel.x - truth.x),
                f64::from(reg.rel.y - truth.y),
                f64::from(wrap(reg.rel.theta - truth.theta)),
            ];
            let (terr, rerr) = (e[0].hypot(e[1]), e[2].abs());
            let bad = terr > 200.0 || rerr > 5f64.to_radians();
            if std::env::var("BENCH_DUMP")
                .ok()
                .and_then(|v| v.parse::<usize>().ok())
                == Some(st.pairs)
            {
                let dump = |o: &[Observation]| -> String {
                    o.iter()
                        .map(|f| match f {
                            Observation::Line(l) => format!(
                                "L {} {} {} {} {} {}",
                                l.start[0], l.start[1], l.end[0], l.end[1], l.alpha, l.rho
                            ),
                            Observation::Point(p) => format!("P {} {}", p.x, p.y),
                        })
                        .collect::<Vec<_>>()
                        .join(";")
                };
                if let Some((p, _)) = prev.as_ref() {
                    eprintln!("DUMP prev {}", dump(p));
                }
                eprintln!("DUMP curr {}", dump(&obs));
                eprintln!("DUMP truth {} {} {}", truth.x, truth.y, truth.theta);
                eprintln!("DUMP got {} {} {}", reg.rel.x, reg.rel.y, reg.rel.theta);
                let ranges: Vec<String> = rec.ranges.iter().map(|r| format!("{r}")).collect();
                eprintln!(
                    "DUMP ranges {} {}",
                    rec.geometry.angle_step,
                    ranges.join(" ")
                );
            }
            if std::env::var_os("BENCH_VERBOSE").is_some() && (bad || !reg.is_registered()) {
                let c = [[2500.0, 0.0, 0.0], [0.0, 2500.0, 0.0], [0.0, 0.0, 1e-4]];
                let at_truth = prev
                    .as_ref()
                    .map(|(p, _)| register_with(p, &obs, Some((truth, c)), &pose_cfg));
                if let Some(t) = at_truth {
                    eprintln!(
                        "   with the truth as prior: ({:.0}, {:.0}, {:.1}°) {:?} matches {:?} chi2 {:.1}; free: chi2 {:.1}",
                        t.rel.x, t.rel.y, t.rel.theta.to_degrees(), t.status, t.matches, t.chi2, reg.chi2
                    );
                }
                eprintln!(
                    "{} pair {}{}: truth ({:.0}, {:.0}, {:.1}°) got ({:.0}, {:.0}, {:.1}°) {:?} matches {:?} features {}→{} sd ({:.0}, {:.0}, {:.2}°)",
                    path.display(), st.pairs,
                    if !reg.is_registered() || (bad && (matches!(reg.status, Status::Ok) || nis(&to_f64(&reg.cov), &e).unwrap_or(f64::INFINITY) > 11.345)) { " FAIL" } else { "" },
                    truth.x, truth.y, truth.theta.to_degrees(),
                    reg.rel.x, reg.rel.y, reg.rel.theta.to_degrees(), reg.status, reg.matches,
                    prev.as_ref().map_or(0, |p| p.0.len()), obs.len(),
                    reg.cov[0][0].sqrt(), reg.cov[1][1].sqrt(), reg.cov[2][2].sqrt().to_degrees()
                );
            }
            match reg.status {
                Status::None(_) => {
                    st.last = None;
                    st.none += 1;
                    st.failures += 1;
                }
                Status::Degenerate { .. } => {
                    st.last = None;
                    st.degenerate += 1;
                    let own = nis(&to_f64(&reg.cov), &e).unwrap_or(f64::INFINITY);
                    if bad && own > 11.345 {
                        st.failures += 1;
                    }
                    st.terr.push(terr);
                    st.rerr.push(rerr);
                }
                Status::Ok => {
                    if bad {
                        st.failures += 1;
                    }
                    if let Some((r0, t0, true)) = st.last {
                        let two = r0.compose(&reg.rel);
                        let ref_two = t0.compose(&truth);
                        if bad
                            && (two.x - ref_two.x).hypot(two.y - ref_two.y) < 200.0
                            && wrap(two.theta - ref_two.theta).abs() < 2f32.to_radians()
                        {
                            st.suspect += 2;
                            st.last = Some((reg.rel, truth, false));
                        } else {
                            st.last = Some((reg.rel, truth, bad));
                        }
                    } else {
                        st.last = Some((reg.rel, truth, bad));
                    }
                    st.terr.push(terr);
                    st.rerr.push(rerr);
                    let mut c = to_f64(&reg.cov);
                    c[0][0] += 15.0 * 15.0;
                    c[1][1] += 15.0 * 15.0;
                    c[2][2] += 0.4f64.to_radians().powi(2);
                    if let Some(v) = nis(&c, &e) {
                        st.nis.push(v);
                    }
                }
            }
        }
        if reg.is_none() {
            st.last = None;
        }
        prev = Some((obs, rec.pose));
    }
    // Odometry windows of 50 scans (start every 25).
    if odometry {
        let w = 50;
        let mut s = 0;
        while s + w < track.len() {
            let (e0, r0, c0) = track[s];
            let (e1, r1, c1) = track[s + w];
            let est = e0.inverse().compose(&e1);
            let re = r0.inverse().compose(&r1);
            let ch = c0.inverse().compose(&c1);
            let mut dist = 0.0;
            let mut turn = 0.0;
            for k in s..s + w {
                let d = track[k].1.inverse().compose(&track[k + 1].1);
                dist += f64::from(d.x.hypot(d.y)) / 1000.0;
                turn += f64::from(d.theta.abs());
            }
            let te = f64::from((est.x - re.x).hypot(est.y - re.y)) / 1000.0;
            let ae = f64::from(wrap(est.theta - re.theta).abs());
            let tc = f64::from((ch.x - re.x).hypot(ch.y - re.y)) / 1000.0;
            let ac = f64::from(wrap(ch.theta - re.theta).abs());
            st.windows.push((dist, te, turn, ae, tc, ac));
            s += 25;
        }
    }
    Ok(st)
}

fn row(name: &str, st: &mut Stats, odometry: bool) {
    let pct = |a: usize| 100.0 * a as f64 / st.pairs.max(1) as f64;
    let inside = st.nis.iter().filter(|&&v| v < 7.815).count();
    let mut t = st.terr.clone();
    let mut r: Vec<f64> = st.rerr.iter().map(|v| v.to_degrees()).collect();
    let mut nis = st.nis.clone();
    print!(
        "| {name} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} / {:.1} / {:.1} | {:.2} / {:.2} / {:.2} | {:.2} | {:.1} | {:.2} |",
        st.pairs,
        pct(st.failures),
        pct(st.suspect),
        pct(st.none),
        pct(st.degenerate),
        percentile(&mut t, 0.5) / 10.0,
        mean(&st.terr) / 10.0,
        percentile(&mut t, 0.95) / 10.0,
        percentile(&mut r, 0.5),
        mean(&r),
        percentile(&mut r, 0.95),
        percentile(&mut nis, 0.5),
        100.0 * inside as f64 / st.nis.len().max(1) as f64,
        1000.0 * st.seconds / st.scans.max(1) as f64,
    );
    if odometry {
        let mut sum = [0.0f64; 6];
        for w in &st.windows {
            for (s, v) in sum.iter_mut().zip([w.0, w.1, w.2, w.3, w.4, w.5]) {
                *s += v;
            }
        }
        let (d, a) = (sum[0].max(1e-9), sum[2].max(1e-9));
        print!(
            " {:.3} / {:.3} | {:.3} / {:.3} |",
            sum[1] / d,
            sum[4] / d,
            sum[3] / a,
            sum[5] / a
        );
    }
    println!();
}

fn main() {
    let mut max_pairs = usize::MAX;
    let mut odometry = false;
    let mut logs: Vec<PathBuf> = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--max-pairs" => {
                max_pairs = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(usize::MAX)
            }
            "--odometry" => odometry = true,
            _ => logs.push(PathBuf::from(a)),
        }
    }
    if logs.is_empty() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/carmen");
        match std::fs::read_dir(&dir) {
            Ok(entries) => {
                logs = entries
                    .filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| p.to_string_lossy().ends_with(".log.gz"))
                    .collect();
                logs.sort();
            }
            Err(_) => {
                eprintln!(
                    "SKIPPED: no CARMEN logs at {} (the shared data folder is absent): nothing measured",
                    dir.display()
                );
                return;
            }
        }
    }
    print!("| log | pairs | fail % | of which reference-suspect % | none % | degenerate % | trans. error cm (median / mean / p95) | rot. error ° (median / mean / p95) | NIS median | inside 95 % | ms/scan |");
    if odometry {
        print!(" 50-scan windows: m per m (odometry / chained pairs) | rad per rad (odometry / chained) |");
    }
    println!();
    print!("|---|---|---|---|---|---|---|---|---|---|---|");
    if odometry {
        print!("---|---|");
    }
    println!();
    let mut pooled = Stats::default();
    for log in &logs {
        let name = log
            .file_name()
            .map(|n| n.to_string_lossy().replace("-corrected.log.gz", ""))
            .unwrap_or_default();
        match run_log(log, max_pairs, odometry) {
            Ok(mut st) => {
                row(&name, &mut st, odometry);
                pooled.pairs += st.pairs;
                pooled.failures += st.failures;
                pooled.suspect += st.suspect;
                pooled.none += st.none;
                pooled.degenerate += st.degenerate;
                pooled.terr.extend(&st.terr);
                pooled.rerr.extend(&st.rerr);
                pooled.nis.extend(&st.nis);
                pooled.seconds += st.seconds;
                pooled.scans += st.scans;
                pooled.windows.extend(&st.windows);
            }
            Err(e) => eprintln!("{}: {e}", log.display()),
        }
    }
    row("pooled", &mut pooled, odometry);
}
