//! The analytic room the `pfe odometry` tests drive through: walls and pillars ray-cast from
//! known poses, written as CARMEN or csv (shared by `cli_odometry` and `cli_odometry_outputs`).
#![allow(dead_code)] // each test binary uses its part

use std::path::PathBuf;

use super::common::TempDir;
use serde_json::Value;

/// A convex room of seven walls (mm, counter-clockwise) and three pillars (centre, radius).
pub const WALLS: [(f64, f64); 7] = [
    (-4000.0, -3000.0),
    (5000.0, -3500.0),
    (6000.0, 2000.0),
    (2000.0, 3500.0),
    (-1000.0, 3000.0),
    (-3500.0, 2500.0),
    (-4500.0, 0.0),
];
pub const PILLARS: [(f64, f64, f64); 3] = [
    (2000.0, -1500.0, 150.0),
    (-2000.0, 1500.0, 150.0),
    (3500.0, 1500.0, 200.0),
];

/// The range (mm) from `p` along the world direction `a`: nearest wall or pillar.
pub fn cast(p: (f64, f64), a: f64) -> f64 {
    let (dx, dy) = (a.cos(), a.sin());
    let mut best = f64::INFINITY;
    for i in 0..WALLS.len() {
        let (a0, a1) = (WALLS[i], WALLS[(i + 1) % WALLS.len()]);
        let (ex, ey) = (a1.0 - a0.0, a1.1 - a0.1);
        let den = dx * ey - dy * ex;
        if den.abs() < 1e-12 {
            continue;
        }
        let (wx, wy) = (a0.0 - p.0, a0.1 - p.1);
        let t = (wx * ey - wy * ex) / den;
        let u = (wx * dy - wy * dx) / den;
        if t > 0.0 && (0.0..=1.0).contains(&u) {
            best = best.min(t);
        }
    }
    for &(cx, cy, r) in &PILLARS {
        let (wx, wy) = (cx - p.0, cy - p.1);
        let b = wx * dx + wy * dy;
        let disc = b * b - (wx * wx + wy * wy - r * r);
        if disc >= 0.0 {
            let t = b - disc.sqrt();
            if t > 0.0 {
                best = best.min(t);
            }
        }
    }
    best
}

/// Deterministic Gaussian noise (xorshift + Box–Muller).
pub struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn gauss(&mut self, sigma: f64) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        sigma * (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// The true poses (mm, rad): a drive through the room, 150–250 mm and up to 0.08 rad a step.
pub fn truth() -> Vec<[f64; 3]> {
    (0..40)
        .map(|k| {
            let s = k as f64;
            [
                -2500.0 + 110.0 * s,
                -800.0 + 600.0 * (0.12 * s).sin(),
                0.25 * (0.2 * s).sin() + 0.004 * s,
            ]
        })
        .collect()
}

/// 361 ranges (mm) over 180° from pose `p`, with σ noise.
pub fn ranges(p: &[f64; 3], noise: &mut Noise, sigma: f64) -> Vec<f64> {
    (0..361)
        .map(|i| {
            let b = (-90.0 + 0.5 * i as f64).to_radians();
            cast((p[0], p[1]), p[2] + b) + noise.gauss(sigma)
        })
        .collect()
}

/// A CARMEN log of the drive: FLASER lines with the true pose and odometry `odom` (m, rad).
pub fn carmen(poses: &[[f64; 3]], odom: &[[f64; 3]]) -> String {
    let mut noise = Noise(0x9e37_79b9_7f4a_7c15);
    let mut s = String::from("PARAM robot_front_laser_max 50.0\n");
    for (k, (p, o)) in poses.iter().zip(odom).enumerate() {
        let r: Vec<String> = ranges(p, &mut noise, 5.0)
            .iter()
            .map(|r| format!("{:.4}", r / 1000.0))
            .collect();
        s += &format!(
            "FLASER 361 {} {:.6} {:.6} {:.6} {:.6} {:.6} {:.6} {}.0 host {}.0\n",
            r.join(" "),
            p[0] / 1000.0,
            p[1] / 1000.0,
            p[2],
            o[0] / 1000.0,
            o[1] / 1000.0,
            o[2],
            k,
            k
        );
    }
    s
}

/// The csv of the same drive (ranges in mm, no pose).
pub fn csv(poses: &[[f64; 3]]) -> String {
    let mut noise = Noise(0x1234_5678_9abc_def1);
    let mut s = String::new();
    for (k, p) in poses.iter().enumerate() {
        let r: Vec<String> = ranges(p, &mut noise, 5.0)
            .iter()
            .map(|r| format!("{r:.1}"))
            .collect();
        s += &format!("{k},-90,0.5,{}\n", r.join(","));
    }
    s
}

/// `a⁻¹ ⊕ b` (mm, rad).
pub fn between(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    let (s, c) = a[2].sin_cos();
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let t = b[2] - a[2];
    [c * dx + s * dy, -s * dx + c * dy, t.sin().atan2(t.cos())]
}

/// (x, y, θ, the 3×3 covariance) of a printed pose.
pub fn pose_of(v: &Value) -> ([f64; 3], [f64; 9]) {
    let f = |k: &str| v[k].as_f64().unwrap();
    let cov: Vec<f64> = v["cov"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap())
        .collect();
    ([f("x"), f("y"), f("theta")], cov.try_into().unwrap())
}

/// Components (rel and pose, x y θ) beyond their stated 3σ, of how many; every scan
/// registered with rel σ under 25 mm and 0.01 rad; the worst rel error (mm, rad).
pub fn check_against_truth(lines: &[Value], poses: &[[f64; 3]]) -> (usize, usize, f64, f64) {
    assert_eq!(lines.len(), poses.len());
    let (mut beyond, mut total, mut worst_t, mut worst_r) = (0, 0, 0.0f64, 0.0f64);
    for (k, l) in lines.iter().enumerate().skip(1) {
        let status = l["status"].as_str().unwrap();
        assert_eq!(status, "ok", "scan {k}: {l}");
        let (rel, rel_cov) = pose_of(&l["rel"]);
        let (pose, cov) = pose_of(&l["pose"]);
        // The stated uncertainty is informative (pfe-pose's model floor is 15 mm and 0.46°
        // a line), so that 3σ is a real bound.
        assert!(
            rel_cov[0].sqrt() < 25.0 && rel_cov[4].sqrt() < 25.0 && rel_cov[8].sqrt() < 0.01,
            "scan {k}: {l}"
        );
        let truth_rel = between(&poses[k - 1], &poses[k]);
        let truth_pose = between(&poses[0], &poses[k]);
        for (est, c, t) in [(rel, rel_cov, truth_rel), (pose, cov, truth_pose)] {
            for i in 0..3 {
                let mut e = est[i] - t[i];
                if i == 2 {
                    e = e.sin().atan2(e.cos());
                }
                let sd = c[4 * i].sqrt();
                assert!(sd.is_finite() && sd > 0.0, "scan {k}: {l}");
                total += 1;
                if e.abs() > 3.0 * sd {
                    beyond += 1;
                    eprintln!("scan {k} component {i}: error {e} beyond 3σ = {}", 3.0 * sd);
                }
            }
        }
        worst_t = worst_t.max((rel[0] - truth_rel[0]).hypot(rel[1] - truth_rel[1]));
        worst_r = worst_r.max((rel[2] - truth_rel[2]).abs());
    }
    (beyond, total, worst_t, worst_r)
}

pub fn write(dir: &TempDir, name: &str, text: &str) -> PathBuf {
    let p = dir.0.join(name);
    std::fs::write(&p, text).unwrap();
    p
}
