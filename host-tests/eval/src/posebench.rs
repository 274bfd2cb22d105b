//! The pose benchmark (issue 40): pfe-pose's registration of consecutive scans of CARMEN logs
//! against the logs' corrected poses, as `pfe posebench` and `cargo xtask pose` run it.
//!
//! Scans are read by [`pfe_formats::carmen`] and their features extracted as
//! `pfe extract --format carmen` does ([`observations`]): `Config::default()` with the
//! format's σ_r (10 mm) and σ_sys (5 mm), the LMS2xx's sweeps, the range grid as quantum.
//! Every consecutive pair is registered without a prior and compared with the reference
//! motion `P_{k−1}⁻¹ ⊕ P_k` of the logs' poses. A failure is an error > 0.2 m or > 5° (a
//! pair flagged degenerate whose error lies inside its own 99 % ellipsoid is not one; "none"
//! is). Errors are over the registered pairs; the NIS over the "ok" pairs with the
//! reference's own scatter (σ = 15 mm per axis, 0.4°) added to the stated covariance (χ²₃'s
//! median is 2.37), and how many lie inside the 95 % ellipsoid (χ²₃ < 7.815).
//! "Reference-suspect": two consecutive failing "ok" pairs whose two-step motion agrees with
//! the reference's within 0.2 m and 2° (the middle reference pose is off, not the
//! registration). Host time: extraction + registration per scan.
//!
//! Diagnostics (environment): `PFE_POSE_CFG="name=value,..."` overrides registration
//! settings; `BENCH_VERBOSE=1` prints each failing pair with the registration seeded at the
//! reference, its stated covariance, χ² and the points' agreement at the reference and at
//! the answer; `BENCH_DUMP=K` dumps pair K's features and ranges; `BENCH_ODO=1` and
//! `BENCH_ODO_STEP=1` compare odometry steps with the pairs; `BENCH_TRACK=DIR` writes each
//! log's odometry track (`DIR/LOG.tsv`: scan, odometry pose, reference pose, status, the
//! pair's registration and its status) for the analysis of its windows; `BENCH_NIS=1` prints
//! each "ok" pair's error, stated covariance, NIS, matches, χ² and the path that gave it.
#![allow(clippy::needless_range_loop)]

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use pfe_core::{Config, ScanGeometry};
use pfe_formats::{Format, Record};
use pfe_pose::points::{agreement, register_scans, RangeScan};
use pfe_pose::{register_with, wrap, Observation, Odometry, Pose, Status};

use crate::methods::{Method, Pfe, ScanContext};

/// The scans' extractor of `pfe extract --format carmen`: the default configuration with the
/// format's noise.
pub fn carmen_method() -> Pfe {
    extractor_for(Format::Carmen, None, None)
}

/// The default configuration's extractor for `format`, with range noise `sigma_r` and
/// systematic error `sigma_sys` mm (default: the format's).
pub fn extractor_for(format: Format, sigma_r: Option<f32>, sigma_sys: Option<f32>) -> Pfe {
    Pfe::new(
        "pfe-default",
        Config::default()
            .with_sigma_r(sigma_r.unwrap_or(format.sigma_r()))
            .with_sigma_sys(sigma_sys.unwrap_or(format.sigma_sys())),
    )
}

/// The features of `record` as pfe-pose's observations, extracted by `method` as
/// `pfe extract` does: `sweeps` (or the record's, or the format's rule) and the range grid as
/// quantum. A scan the extractor refuses gives none.
pub fn observations(
    method: &mut Pfe,
    format: Format,
    record: &Record,
    sweeps: Option<u8>,
) -> Vec<Observation> {
    let context = ScanContext {
        odometry: None,
        sweeps: usize::from(
            sweeps
                .or(record.sweeps)
                .unwrap_or_else(|| pfe_formats::sweeps_of(format, &record.geometry)),
        ),
        quantum: pfe_formats::range_quantum(&record.ranges_mm, record.geometry.r_max),
    };
    let ex = method.extract_in(&record.geometry, &record.ranges_mm, &context);
    ex.features
        .iter()
        .filter_map(Observation::from_feature)
        .collect()
}

/// One scan: ranges (mm, NaN = no return), geometry, laser pose (mm, rad).
struct Rec {
    ranges: Vec<f32>,
    geometry: ScanGeometry,
    pose: Pose,
}

/// One log's (or the pooled) figures.
#[derive(Default, Clone)]
pub struct Stats {
    /// Consecutive pairs with a reference motion.
    pub pairs: usize,
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
            "verify_margin" => c.verify_margin = v,
            "verify_accept" => c.verify_accept = v,
            "verify_keep" => c.verify_keep = v,
            "verify_track" => c.verify_track = v,
            "points_resolve" => c.points_resolve = v > 0.0,
            _ => eprintln!("PFE_POSE_CFG: unknown setting {k}"),
        }
    }
    eprintln!("settings: {c:?}");
    c
}

/// Registers the consecutive scans of the CARMEN log `path` (the first `max_pairs` pairs),
/// and with `odometry` runs [`Odometry`] too; bad input is a [`pfe_formats::InputError`].
pub fn run_log(path: &Path, max_pairs: usize, odometry: bool) -> anyhow::Result<Stats> {
    Ok(run_log_with(path, max_pairs, odometry, false)?.pfe)
}

/// The figures of one log: pfe-pose's, and with `baseline` PL-ICP's ([`crate::plicp`]) from
/// the identity and from the noisy prior (the reference motion perturbed by σ = 50 mm + 10 %
/// of the translation per axis and 2° + 10 % of the rotation, seed 40).
pub struct LogFigures {
    /// pfe-pose without a prior.
    pub pfe: Stats,
    /// PL-ICP from the identity (with `baseline`).
    pub icp_identity: Option<Stats>,
    /// PL-ICP from the noisy prior (with `baseline`).
    pub icp_prior: Option<Stats>,
}

/// [`run_log`], and with `baseline` PL-ICP beside it ([`LogFigures`]).
pub fn run_log_with(
    path: &Path,
    max_pairs: usize,
    odometry: bool,
    baseline: bool,
) -> anyhow::Result<LogFigures> {
    use rand::SeedableRng as _;
    use rand_distr::Distribution as _;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(40);
    let unit = rand_distr::StandardNormal;
    let mut icp = [Stats::default(), Stats::default()];
    let mut prev_points: Option<Vec<[f64; 2]>> = None;
    let input = pfe_formats::open_for(path, Format::Carmen, |r| r)
        .with_context(|| format!("{}: cannot open", path.display()))?;
    let mut method = carmen_method();
    let pose_cfg = pose_config();
    let mut st = Stats::default();
    let mut prev: Option<(Vec<Observation>, Pose)> = None;
    // The scans' ranges for the points' verification and fallback, and the last registered
    // motion (the fallback's first guess).
    let points = std::env::var("PFE_POSE_POINTS").map_or(true, |v| v != "0");
    let mut prev_pts = Box::new(RangeScan::<{ pfe_pose::points::SCAN_BEAMS }>::new());
    let mut curr_pts = Box::new(RangeScan::<{ pfe_pose::points::SCAN_BEAMS }>::new());
    let mut last_motion: Option<Pose> = None;
    let mut odo = Box::new(Odometry::<64, { pfe_pose::points::SCAN_BEAMS }>::new(
        pose_cfg,
    ));
    let mut track: Vec<(Pose, Pose, Pose)> = Vec::new();
    let mut chained = Pose::IDENTITY;
    // PL-ICP from the noisy prior, chained (its answer, or the prior where it gives none).
    let mut icp_chain = Pose::IDENTITY;
    let mut icp_track: Vec<Pose> = Vec::new();
    let track_dir = std::env::var_os("BENCH_TRACK").map(PathBuf::from);
    let mut track_tsv = String::new();
    for record in pfe_formats::scans(Format::Carmen, input).take(max_pairs.saturating_add(1)) {
        let record =
            record.map_err(|e| anyhow::Error::new(e).context(path.display().to_string()))?;
        // A scan without a pose breaks the chain of reference motions.
        let Some(p) = record.pose else {
            prev = None;
            st.last = None;
            continue;
        };
        let t0 = Instant::now();
        let obs = observations(&mut method, Format::Carmen, &record, None);
        let rec = Rec {
            pose: Pose::new((p[0] * 1000.0) as f32, (p[1] * 1000.0) as f32, p[2] as f32),
            geometry: record.geometry,
            ranges: record.ranges_mm,
        };
        if points {
            curr_pts.set(
                rec.geometry.start_angle,
                rec.geometry.angle_step,
                &rec.ranges,
            );
        }
        let reg = prev.as_ref().map(|(p, _)| {
            if points {
                register_scans(p, &prev_pts, &obs, &curr_pts, last_motion, &pose_cfg)
            } else {
                register_with(p, &obs, None, &pose_cfg)
            }
        });
        last_motion = reg.filter(|r| r.is_registered()).map(|r| r.rel);
        if let (Some(r), Some((_, p0)), true) = (
            reg.as_ref(),
            prev.as_ref(),
            std::env::var_os("BENCH_AGREE").is_some(),
        ) {
            let truth = p0.inverse().compose(&rec.pose);
            let bad = (r.rel.x - truth.x).hypot(r.rel.y - truth.y) > 200.0
                || wrap(r.rel.theta - truth.theta).abs() > 0.087;
            eprintln!(
                "AGREE {} {} {:?} {:.3} {:.3}",
                st.pairs + 1,
                u8::from(bad),
                r.status,
                agreement(&prev_pts, &curr_pts, &truth).score(),
                agreement(&prev_pts, &curr_pts, &r.rel).score()
            );
        }
        core::mem::swap(&mut prev_pts, &mut curr_pts);
        if odometry {
            let step = if points {
                odo.update_with_points(&obs, &prev_pts, None)
            } else {
                odo.update(&obs, None)
            };
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
            if track_dir.is_some() {
                let (pr, ps) = reg
                    .map_or((Pose::new(f32::NAN, f32::NAN, f32::NAN), "-".into()), |r| {
                        (r.rel, format!("{:?}", r.status).replace(' ', ""))
                    });
                let (e, p) = (step.pose, rec.pose);
                let _ = writeln!(
                    track_tsv,
                    "{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}",
                    track.len() - 1,
                    e.x,
                    e.y,
                    e.theta,
                    p.x,
                    p.y,
                    p.theta,
                    format!("{:?}", step.status).replace(' ', ""),
                    pr.x,
                    pr.y,
                    pr.theta,
                    ps
                );
            }
        }
        st.seconds += t0.elapsed().as_secs_f64();
        let points: Vec<[f64; 2]> = if baseline {
            rec.ranges
                .iter()
                .enumerate()
                .filter(|(_, r)| r.is_finite())
                .map(|(i, &r)| {
                    let b = f64::from(rec.geometry.bearing(i));
                    [f64::from(r) * b.cos(), f64::from(r) * b.sin()]
                })
                .collect()
        } else {
            Vec::new()
        };
        if let (true, Some(p0), Some((_, pose0))) = (baseline, prev_points.as_ref(), prev.as_ref())
        {
            let truth = pose0.inverse().compose(&rec.pose);
            let t = [
                f64::from(truth.x),
                f64::from(truth.y),
                f64::from(truth.theta),
            ];
            let sxy = 50.0 + 0.1 * t[0].hypot(t[1]);
            let sth = 2f64.to_radians() + 0.1 * t[2].abs();
            let mut draw = || -> f64 { unit.sample(&mut rng) };
            let noisy = [
                t[0] + sxy * draw(),
                t[1] + sxy * draw(),
                t[2] + sth * draw(),
            ];
            for (k, guess) in [[0.0; 3], noisy].into_iter().enumerate() {
                let t0 = Instant::now();
                let a = crate::plicp::plicp(p0, &points, guess, &crate::plicp::Params::default());
                icp[k].seconds += t0.elapsed().as_secs_f64();
                if k == 1 {
                    let step = a.as_ref().map_or(guess, |a| a.pose);
                    icp_chain = icp_chain.compose(&Pose::new(
                        step[0] as f32,
                        step[1] as f32,
                        step[2] as f32,
                    ));
                }
                icp[k].scans += 1;
                account(&mut icp[k], a.map(|a| (a.pose, a.cov)), &truth);
            }
        }
        prev_points = baseline.then_some(points);
        if odometry && baseline {
            icp_track.push(icp_chain);
        }
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
                eprintln!(
                    "   cov {:?} own chi2 {:.2} points at truth {:.3} at answer {:.3}",
                    reg.cov,
                    nis(&to_f64(&reg.cov), &e).unwrap_or(f64::INFINITY),
                    agreement(&curr_pts, &prev_pts, &truth).score(),
                    agreement(&curr_pts, &prev_pts, &reg.rel).score()
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
                    if std::env::var_os("BENCH_NIS").is_some() {
                        // Which path gave the answer: the features' own registration
                        // ("feat"), its pose polished by the points ("polish") or another
                        // (the ICP's covariance, "icp").
                        let f = prev
                            .as_ref()
                            .map(|(p, _)| register_with(p, &obs, None, &pose_cfg));
                        let path_name = match f {
                            Some(f) if f.rel == reg.rel && f.cov == reg.cov => "feat",
                            Some(f) if f.cov == reg.cov => "polish",
                            _ => "icp",
                        };
                        let r = &reg.cov;
                        eprintln!(
                            "NIS {} {} {:.2} {:.2} {:.5} {:.3} {:.3} {:.6} {:.3} {:.6} {:.9} {:.3} {} {} {:.2} {}",
                            st.pairs, u8::from(bad), e[0], e[1], e[2],
                            r[0][0], r[0][1], r[0][2], r[1][1], r[1][2], r[2][2],
                            nis(&c, &e).unwrap_or(f64::INFINITY),
                            reg.matches.0, reg.matches.1, reg.chi2, path_name
                        );
                        // The scans were swapped after the registration: `curr_pts` is the
                        // previous scan's.
                        eprintln!(
                            "AGR {} {:.3}",
                            st.pairs,
                            agreement(&curr_pts, &prev_pts, &reg.rel).score()
                        );
                    }
                }
            }
        }
        if reg.is_none() {
            st.last = None;
        }
        prev = Some((obs, rec.pose));
    }
    if let Some(dir) = track_dir.filter(|_| odometry) {
        let file = dir.join(format!("{}.tsv", log_name(path)));
        std::fs::write(&file, &track_tsv)
            .with_context(|| format!("{}: cannot write", file.display()))?;
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
            if let (Some(i0), Some(i1)) = (icp_track.get(s), icp_track.get(s + w)) {
                let est = i0.inverse().compose(i1);
                let ti = f64::from((est.x - re.x).hypot(est.y - re.y)) / 1000.0;
                let ai = f64::from(wrap(est.theta - re.theta).abs());
                icp[1].windows.push((dist, ti, turn, ai, ti, ai));
            }
            s += 25;
        }
    }
    let [a, b] = icp;
    Ok(LogFigures {
        pfe: st,
        icp_identity: baseline.then_some(a),
        icp_prior: baseline.then_some(b),
    })
}

/// Adds a baseline's answer for one pair (`None`: no answer, a failure) against `truth`.
fn account(st: &mut Stats, answer: Option<([f64; 3], [[f64; 3]; 3])>, truth: &Pose) {
    st.pairs += 1;
    let Some((p, cov)) = answer else {
        st.none += 1;
        st.failures += 1;
        return;
    };
    let e = [
        p[0] - f64::from(truth.x),
        p[1] - f64::from(truth.y),
        f64::from(wrap((p[2] - f64::from(truth.theta)) as f32)),
    ];
    let (terr, rerr) = (e[0].hypot(e[1]), e[2].abs());
    if terr > 200.0 || rerr > 5f64.to_radians() {
        st.failures += 1;
    }
    st.terr.push(terr);
    st.rerr.push(rerr);
    let mut c = cov;
    c[0][0] += 15.0 * 15.0;
    c[1][1] += 15.0 * 15.0;
    c[2][2] += 0.4f64.to_radians().powi(2);
    if let Some(v) = nis(&c, &e) {
        st.nis.push(v);
    }
}

fn row(out: &mut String, name: &str, st: &mut Stats, odometry: bool) {
    let pct = |a: usize| 100.0 * a as f64 / st.pairs.max(1) as f64;
    let inside = st.nis.iter().filter(|&&v| v < 7.815).count();
    let mut t = st.terr.clone();
    let mut r: Vec<f64> = st.rerr.iter().map(|v| v.to_degrees()).collect();
    let mut nis = st.nis.clone();
    let _ = write!(
        out,
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
    if odometry && st.windows.is_empty() {
        out.push_str(" – | – |");
    } else if odometry {
        let mut sum = [0.0f64; 6];
        for w in &st.windows {
            for (s, v) in sum.iter_mut().zip([w.0, w.1, w.2, w.3, w.4, w.5]) {
                *s += v;
            }
        }
        let (d, a) = (sum[0].max(1e-9), sum[2].max(1e-9));
        let _ = write!(
            out,
            " {:.3} / {:.3} | {:.3} / {:.3} |",
            sum[1] / d,
            sum[4] / d,
            sum[3] / a,
            sum[5] / a
        );
    }
    out.push('\n');
}

/// The header of [`table`]'s Markdown table.
fn header(odometry: bool) -> String {
    let mut s = String::from("| log | pairs | fail % | of which reference-suspect % | none % | degenerate % | trans. error cm (median / mean / p95) | rot. error ° (median / mean / p95) | NIS median | inside 95 % | ms/scan |");
    if odometry {
        s.push_str(" 50-scan windows: m per m (odometry / chained pairs; PL-ICP rows: its chained pairs twice) | rad per rad (odometry / chained) |");
    }
    s.push_str("\n|---|---|---|---|---|---|---|---|---|---|---|");
    if odometry {
        s.push_str("---|---|");
    }
    s.push('\n');
    s
}

/// The Markdown table of the logs' figures `(name, stats)`, one row each and a pooled row
/// (when more than one log), with the odometry columns when `odometry`.
pub fn table(logs: &[(String, Stats)], odometry: bool) -> String {
    let mut out = header(odometry);
    rows(&mut out, logs, odometry, "");
    out
}

/// [`table`] with the rows of further methods below pfe-pose's, `(suffix of their rows'
/// names, rows)` (pooled per method).
pub fn table_with(
    logs: &[(String, Stats)],
    others: &[(&str, Vec<(String, Stats)>)],
    odometry: bool,
) -> String {
    let mut out = header(odometry);
    rows(&mut out, logs, odometry, "");
    for (suffix, logs) in others {
        rows(&mut out, logs, odometry, suffix);
    }
    out
}

/// The rows of `logs` and their pooled row, each name followed by `suffix`.
fn rows(out: &mut String, logs: &[(String, Stats)], odometry: bool, suffix: &str) {
    let mut pooled = Stats::default();
    for (name, st) in logs {
        row(out, &format!("{name}{suffix}"), &mut st.clone(), odometry);
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
    if logs.len() > 1 {
        row(out, &format!("pooled{suffix}"), &mut pooled, odometry);
    }
}

/// A log's name in the table: its file name without `-corrected.log.gz` (or `.gz`, `.log`,
/// `.clf`).
pub fn log_name(path: &Path) -> String {
    let n = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let n = n.strip_suffix(".gz").unwrap_or(&n);
    let n = n
        .strip_suffix(".log")
        .or_else(|| n.strip_suffix(".clf"))
        .unwrap_or(n);
    n.strip_suffix("-corrected").unwrap_or(n).to_string()
}

/// The CARMEN logs (`*.log`, `*.clf`, gzipped or not) in `dir`, sorted; `None` when `dir`
/// cannot be read.
pub fn logs_in(dir: &Path) -> Option<Vec<PathBuf>> {
    let mut logs: Vec<PathBuf> = std::fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| pfe_formats::carmen::is_log_name(&n.to_string_lossy()))
        })
        .collect();
    logs.sort();
    Some(logs)
}

impl Stats {
    /// Percentage of the pairs that fail.
    pub fn fail_pct(&self) -> f64 {
        100.0 * self.failures as f64 / self.pairs.max(1) as f64
    }

    /// Percentage of the pairs not registered.
    pub fn none_pct(&self) -> f64 {
        100.0 * self.none as f64 / self.pairs.max(1) as f64
    }

    /// Percentage of the pairs flagged degenerate.
    pub fn degenerate_pct(&self) -> f64 {
        100.0 * self.degenerate as f64 / self.pairs.max(1) as f64
    }

    /// Median translational error of the registered pairs, mm (NaN when none).
    pub fn median_translation_mm(&self) -> f64 {
        percentile(&mut self.terr.clone(), 0.5)
    }

    /// Median rotational error of the registered pairs, rad (NaN when none).
    pub fn median_rotation(&self) -> f64 {
        percentile(&mut self.rerr.clone(), 0.5)
    }

    /// Median NIS of the "ok" pairs (NaN when none).
    pub fn median_nis(&self) -> f64 {
        percentile(&mut self.nis.clone(), 0.5)
    }

    /// Percentage of the "ok" pairs whose error lies inside their 95 % ellipsoid.
    pub fn inside_95_pct(&self) -> f64 {
        let inside = self.nis.iter().filter(|&&v| v < 7.815).count();
        100.0 * inside as f64 / self.nis.len().max(1) as f64
    }
}
