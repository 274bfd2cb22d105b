//! Scene generators (office, clutter, pillars, corridor). All lengths in mm. Each builds in its
//! own axis-aligned frame; the random scanner heading rotates the view.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{FRAC_PI_2, PI};
use std::ops::Range;

use super::vec2::{add, cross, dir, norm, scale, sub, wrap_pi, V2};
use super::{SceneKind, Shape};

/// Free distance straight ahead of a sampled scanner pose, mm.
pub const MIN_FORWARD_MM: f64 = 1500.0;

/// Something the scanner must not stand inside.
#[derive(Clone, Debug)]
enum Solid {
    /// Convex polygon (counter-clockwise or clockwise).
    Poly(Vec<V2>),
    Disc(V2, f64),
}

impl Solid {
    fn contains(&self, p: V2, margin: f64) -> bool {
        match self {
            Solid::Disc(c, r) => norm(sub(p, *c)) < r + margin,
            Solid::Poly(v) => {
                let n = v.len();
                let mut sign = 0.0f64;
                for k in 0..n {
                    let (a, b) = (v[k], v[(k + 1) % n]);
                    let c = cross(sub(b, a), sub(p, a));
                    if sign == 0.0 {
                        sign = c.signum();
                    } else if c.signum() != sign && c != 0.0 {
                        return false;
                    }
                }
                true
            }
        }
    }
}

/// A scene under construction.
#[derive(Clone, Debug, Default)]
pub(super) struct Scene {
    pub(super) shapes: Vec<Shape>,
    solids: Vec<Solid>,
    /// Where the scanner may stand: x range, y range.
    area: [f64; 4],
    /// Heading: `None` uniform, `Some((mean, spread))` mean ± spread (also mean + π).
    heading: Option<(f64, f64)>,
}

impl Scene {
    fn seg(&mut self, a: V2, b: V2) {
        if norm(sub(b, a)) > 1.0 {
            self.shapes.push(Shape::Segment { a, b });
        }
    }

    fn circle(&mut self, c: V2, r: f64) {
        self.shapes.push(Shape::Circle {
            center: c,
            radius: r,
        });
        self.solids.push(Solid::Disc(c, r));
    }

    /// A rectangle box centred at `c`, sides `w × h`, rotated by `angle`.
    fn rect(&mut self, c: V2, w: f64, h: f64, angle: f64) {
        let (u, v) = (dir(angle), dir(angle + FRAC_PI_2));
        let corners: Vec<V2> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .iter()
            .map(|(sx, sy)| add(c, add(scale(u, sx * w / 2.0), scale(v, sy * h / 2.0))))
            .collect();
        for k in 0..4 {
            self.seg(corners[k], corners[(k + 1) % 4]);
        }
        self.solids.push(Solid::Poly(corners));
    }

    /// Whether a disc of radius `r` at `c` is clear of all solids and shapes.
    fn free(&self, c: V2, r: f64) -> bool {
        self.solids.iter().all(|s| !s.contains(c, r))
            && self.shapes.iter().all(|s| s.distance(c) > r)
    }

    /// A wall from `a` to `b` (room on its left) with `doors` gaps; behind a gap, with some
    /// probability, the wall of the next room. Returns the intervals (along the wall) that
    /// stayed solid.
    fn wall(
        &mut self,
        rng: &mut ChaCha8Rng,
        a: V2,
        b: V2,
        doors: usize,
        recess: bool,
    ) -> Vec<(f64, f64)> {
        let len = norm(sub(b, a));
        let u = scale(sub(b, a), 1.0 / len);
        let out = [u[1], -u[0]]; // right of a→b = outside the room
        let mut gaps: Vec<(f64, f64)> = Vec::new();
        for _ in 0..doors {
            let w = rng.gen_range(800.0..1300.0);
            if len < w + 1200.0 {
                break;
            }
            let s = rng.gen_range(500.0..len - w - 500.0);
            if gaps
                .iter()
                .all(|&(g0, g1)| s + w + 300.0 < g0 || s > g1 + 300.0)
            {
                gaps.push((s, s + w));
            }
        }
        gaps.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut solid = Vec::new();
        let mut pos = 0.0;
        let at = |s: f64| add(a, scale(u, s));
        for &(g0, g1) in &gaps {
            solid.push((pos, g0));
            self.seg(at(pos), at(g0));
            if recess && rng.gen_bool(0.5) {
                // A recessed door: the door leaf set back into the wall.
                let depth = rng.gen_range(100.0..300.0);
                let (p0, p1) = (
                    add(at(g0), scale(out, depth)),
                    add(at(g1), scale(out, depth)),
                );
                self.seg(at(g0), p0);
                self.seg(p0, p1);
                self.seg(p1, at(g1));
            } else if rng.gen_bool(0.7) {
                // The far wall of the room behind, parallel.
                let depth = rng.gen_range(1500.0..5000.0);
                let ext = rng.gen_range(1000.0..3000.0);
                self.seg(
                    add(at(g0 - ext), scale(out, depth)),
                    add(at(g1 + ext), scale(out, depth)),
                );
                // Side walls of the gap (door jambs) as thin returns are short: skipped.
            }
            pos = g1;
        }
        solid.push((pos, len));
        self.seg(at(pos), at(len));
        solid
    }

    /// A pillar embedded in the wall `a → b` (room on the left) at arc length `s`.
    fn wall_pillar(&mut self, a: V2, b: V2, s: f64, r: f64, protrude: f64) {
        let len = norm(sub(b, a));
        let u = scale(sub(b, a), 1.0 / len);
        let inward = [-u[1], u[0]];
        let c = add(add(a, scale(u, s)), scale(inward, protrude - r));
        self.circle(c, r);
    }

    /// A rectangular pilaster (or cabinet) `width × depth` standing against the wall `a → b`
    /// (room on the left) at arc length `s`.
    fn pilaster(&mut self, a: V2, b: V2, s: f64, width: f64, depth: f64) {
        let len = norm(sub(b, a));
        let u = scale(sub(b, a), 1.0 / len);
        let inward = [-u[1], u[0]];
        let c = add(add(a, scale(u, s)), scale(inward, depth / 2.0));
        self.rect(c, width, depth, u[1].atan2(u[0]));
    }

    /// Up to `n` pilasters on the wall `a → b`, where the room side is free.
    fn pilasters(&mut self, rng: &mut ChaCha8Rng, a: V2, b: V2, n: usize, max_depth: f64) {
        let len = norm(sub(b, a));
        let inward = scale([-(b[1] - a[1]), b[0] - a[0]], 1.0 / len);
        for _ in 0..n {
            let width = rng.gen_range(200.0..900.0);
            let depth = rng.gen_range(80.0..max_depth);
            if len < width + 800.0 {
                return;
            }
            let s = rng.gen_range(400.0 + width / 2.0..len - 400.0 - width / 2.0);
            let probe = add(
                add(a, scale(sub(b, a), s / len)),
                scale(inward, depth + 150.0),
            );
            if self
                .solids
                .iter()
                .all(|x| !x.contains(probe, width / 2.0 + depth + 150.0))
            {
                self.pilaster(a, b, s, width, depth);
            }
        }
    }

    /// A random scanner pose: at least 350 mm from everything, not inside a solid, and not
    /// facing an obstacle closer than [`MIN_FORWARD_MM`] straight ahead (a robot does not
    /// drive with its nose against a wall); the last candidate when none qualifies.
    pub(super) fn sample_pose(&self, rng: &mut ChaCha8Rng) -> [f64; 3] {
        let [x0, x1, y0, y1] = self.area;
        let mut best = [(x0 + x1) / 2.0, (y0 + y1) / 2.0, 0.0];
        for _ in 0..500 {
            let q = [
                rng.gen_range(x0..x1.max(x0 + 1.0)),
                rng.gen_range(y0..y1.max(y0 + 1.0)),
            ];
            let heading = match self.heading {
                None => rng.gen_range(-PI..PI),
                Some((m, s)) => {
                    let base = if rng.gen_bool(0.5) { m } else { m + PI };
                    wrap_pi(base + rng.gen_range(-s..s))
                }
            };
            if !self.free(q, 350.0) {
                continue;
            }
            best = [q[0], q[1], heading];
            let ahead = self
                .shapes
                .iter()
                .filter_map(|s| s.ray_hit(q, dir(heading)))
                .fold(f64::INFINITY, f64::min);
            if ahead >= MIN_FORWARD_MM {
                break;
            }
        }
        best
    }

    /// Places up to `n` items of radius `r(rng)` at free random spots in the area.
    fn scatter(
        &mut self,
        rng: &mut ChaCha8Rng,
        n: usize,
        margin: f64,
        mut place: impl FnMut(&mut Scene, &mut ChaCha8Rng, V2) -> f64,
        size: impl Fn(&mut ChaCha8Rng) -> f64,
    ) {
        let [x0, x1, y0, y1] = self.area;
        let mut placed = 0;
        for _ in 0..20 * n {
            if placed == n {
                break;
            }
            let r = size(rng);
            let (ax0, ax1, ay0, ay1) = (
                x0 + r + margin,
                x1 - r - margin,
                y0 + r + margin,
                y1 - r - margin,
            );
            if ax1 <= ax0 || ay1 <= ay0 {
                break;
            }
            let c = [rng.gen_range(ax0..ax1), rng.gen_range(ay0..ay1)];
            if self.free(c, r + margin) {
                place(self, rng, c);
                placed += 1;
            }
        }
    }

    /// Up to `n` circles of a radius drawn from `radii`, each needing `reach` mm of free room.
    fn scatter_circles(
        &mut self,
        rng: &mut ChaCha8Rng,
        n: usize,
        margin: f64,
        radii: Range<f64>,
        reach: f64,
    ) {
        let place = |sc: &mut Scene, rng: &mut ChaCha8Rng, c| {
            let r = rng.gen_range(radii.clone());
            sc.circle(c, r);
            0.0
        };
        self.scatter(rng, n, margin, place, |_| reach);
    }

    /// Up to `n` boxes of a size drawn from `widths × heights` at any angle, each needing
    /// `reach` mm of free room.
    fn scatter_boxes(
        &mut self,
        rng: &mut ChaCha8Rng,
        n: usize,
        margin: f64,
        [widths, heights]: [Range<f64>; 2],
        reach: f64,
    ) {
        let place = |sc: &mut Scene, rng: &mut ChaCha8Rng, c| {
            let (bw, bh) = (
                rng.gen_range(widths.clone()),
                rng.gen_range(heights.clone()),
            );
            let angle = rng.gen_range(-PI..PI);
            sc.rect(c, bw, bh, angle);
            0.0
        };
        self.scatter(rng, n, margin, place, |_| reach);
    }
}

/// Four walls of a `w × h` room (counter-clockwise, room inside) with doors.
fn room(
    sc: &mut Scene,
    rng: &mut ChaCha8Rng,
    w: f64,
    h: f64,
    max_doors: usize,
    recess: bool,
) -> [(V2, V2); 4] {
    let walls = [
        ([0.0, 0.0], [w, 0.0]),
        ([w, 0.0], [w, h]),
        ([w, h], [0.0, h]),
        ([0.0, h], [0.0, 0.0]),
    ];
    for &(a, b) in &walls {
        let doors = rng.gen_range(0..=max_doors);
        sc.wall(rng, a, b, doors, recess);
    }
    sc.area = [300.0, w - 300.0, 300.0, h - 300.0];
    walls
}

pub(super) fn build_scene(kind: SceneKind, rng: &mut ChaCha8Rng) -> Scene {
    let mut sc = Scene::default();
    match kind {
        SceneKind::LongCorridor => return long_corridor(rng),
        SceneKind::Office | SceneKind::Mixed => {
            let (w, h) = (
                rng.gen_range(5000.0..12000.0),
                rng.gen_range(3500.0..8000.0),
            );
            let walls = room(&mut sc, rng, w, h, 2, false);
            for &(a, b) in &walls {
                let k = rng.gen_range(1..=3);
                sc.pilasters(rng, a, b, k, 600.0);
            }
            // Furniture: against a wall or free-standing.
            let n = rng.gen_range(6..=11);
            sc.scatter(
                rng,
                n,
                150.0,
                |sc, rng, c| {
                    let (bw, bh) = (rng.gen_range(400.0..1600.0), rng.gen_range(400.0..900.0));
                    let angle = if rng.gen_bool(0.5) {
                        rng.gen_range(0..4) as f64 * FRAC_PI_2
                    } else {
                        rng.gen_range(-PI..PI)
                    };
                    sc.rect(c, bw, bh, angle);
                    0.0
                },
                |rng| rng.gen_range(300.0..600.0),
            );
            if rng.gen_bool(0.4) {
                sc.scatter_circles(rng, 1, 300.0, 150.0..400.0, 400.0);
            }
            if rng.gen_bool(0.3) {
                let (a, b) = walls[rng.gen_range(0..4)];
                let len = norm(sub(b, a));
                let r = rng.gen_range(200.0..450.0);
                if len > 4.0 * r {
                    let s = rng.gen_range(2.0 * r..len - 2.0 * r);
                    let p = rng.gen_range(0.3..1.2) * r;
                    sc.wall_pillar(a, b, s, r, p);
                }
            }
        }
        SceneKind::Clutter => {
            let (w, h) = (
                rng.gen_range(5000.0..10000.0),
                rng.gen_range(4000.0..8000.0),
            );
            room(&mut sc, rng, w, h, 1, false);
            let n = rng.gen_range(12..=22);
            sc.scatter_boxes(rng, n, 200.0, [200.0..700.0, 200.0..700.0], 500.0);
            let m = rng.gen_range(0..=3);
            sc.scatter_circles(rng, m, 200.0, 80.0..250.0, 250.0);
        }
        SceneKind::Pillars => {
            let (w, h) = (
                rng.gen_range(6000.0..14000.0),
                rng.gen_range(5000.0..10000.0),
            );
            let walls = room(&mut sc, rng, w, h, 1, false);
            let k = rng.gen_range(2..=4);
            for _ in 0..k {
                let (a, b) = walls[rng.gen_range(0..4)];
                let len = norm(sub(b, a));
                let r = rng.gen_range(150.0..450.0);
                let s = rng.gen_range(2.0 * r..len - 2.0 * r);
                let p = rng.gen_range(0.3..1.3) * r;
                if sc.free(add(a, scale(sub(b, a), s / len)), 2.0 * r) || sc.solids.is_empty() {
                    sc.wall_pillar(a, b, s, r, p);
                }
            }
            for &(a, b) in &walls {
                let k = rng.gen_range(0..=2);
                sc.pilasters(rng, a, b, k, 400.0);
            }
            let n = rng.gen_range(8..=14);
            sc.scatter_circles(rng, n, 300.0, 100.0..500.0, 500.0);
            if rng.gen_bool(0.5) {
                sc.scatter_boxes(rng, 1, 300.0, [400.0..1200.0, 400.0..1200.0], 700.0);
            }
        }
        SceneKind::Corridor => {
            let len = rng.gen_range(15000.0..40000.0);
            let wid = rng.gen_range(1500.0..3000.0);
            // Side walls with doors (some recessed), end walls.
            let doors_r = (len / rng.gen_range(2000.0..5000.0)) as usize;
            let doors_l = (len / rng.gen_range(2000.0..5000.0)) as usize;
            let right = sc.wall(rng, [0.0, 0.0], [len, 0.0], doors_r, true);
            let left = sc.wall(rng, [len, wid], [0.0, wid], doors_l, true);
            for (a, b) in [([0.0, 0.0], [len, 0.0]), ([len, wid], [0.0, wid])] {
                let k = (len / rng.gen_range(3000.0..8000.0)) as usize;
                sc.pilasters(rng, a, b, k, 0.15 * wid);
            }
            sc.seg([len, 0.0], [len, wid]);
            sc.seg([0.0, wid], [0.0, 0.0]);
            // Columns in the walls, on solid stretches.
            let cols = rng.gen_range(1..=5);
            for _ in 0..cols {
                let (a, b, solid) = if rng.gen_bool(0.5) {
                    ([0.0, 0.0], [len, 0.0], &right)
                } else {
                    ([len, wid], [0.0, wid], &left)
                };
                let r = rng.gen_range(150.0..350.0);
                if let Some(&(s0, s1)) = solid.get(rng.gen_range(0..solid.len().max(1))) {
                    if s1 - s0 > 4.0 * r {
                        let s = rng.gen_range(s0 + 2.0 * r..s1 - 2.0 * r);
                        let p = rng.gen_range(0.2..0.8) * r;
                        sc.wall_pillar(a, b, s, r, p);
                    }
                }
            }
            if rng.gen_bool(0.3) {
                let r: f64 = rng.gen_range(150.0..300.0_f64).min(wid / 6.0);
                let c = [
                    rng.gen_range(2000.0..len - 2000.0),
                    wid / 2.0 + rng.gen_range(-0.2..0.2) * wid,
                ];
                sc.circle(c, r);
            }
            sc.area = [800.0, len - 800.0, 0.3 * wid, 0.7 * wid];
            sc.heading = Some((0.0, 0.5));
        }
    }
    sc
}

/// A corridor 30–80 m long and 2–4 m wide, side walls with doors (some recessed, some opening
/// on a room behind) and shallow pilasters, closed at both ends; the scanner looks along it
/// (heading within ±0.3 rad of the axis), so the side walls are seen far away at grazing
/// incidence.
pub(super) fn long_corridor(rng: &mut ChaCha8Rng) -> Scene {
    let mut sc = Scene::default();
    let len = rng.gen_range(30000.0..80000.0);
    let wid = rng.gen_range(2000.0..4000.0);
    let doors_r = (len / rng.gen_range(3000.0..8000.0)) as usize;
    let doors_l = (len / rng.gen_range(3000.0..8000.0)) as usize;
    sc.wall(rng, [0.0, 0.0], [len, 0.0], doors_r, true);
    sc.wall(rng, [len, wid], [0.0, wid], doors_l, true);
    for (a, b) in [([0.0, 0.0], [len, 0.0]), ([len, wid], [0.0, wid])] {
        let k = (len / rng.gen_range(5000.0..15000.0)) as usize;
        sc.pilasters(rng, a, b, k, 0.1 * wid);
    }
    sc.seg([len, 0.0], [len, wid]);
    sc.seg([0.0, wid], [0.0, 0.0]);
    sc.area = [800.0, len - 800.0, 0.3 * wid, 0.7 * wid];
    sc.heading = Some((0.0, 0.3));
    sc
}
