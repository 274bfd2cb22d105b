//! The association's angle index against every previous line tried, and a Gauss–Newton
//! step's association against the full one: the same matches, scores and normal equations,
//! bit for bit.
use super::*;
use crate::geom::normalise_line;

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
    /// 10^(lo..hi).
    fn log(&mut self, lo: f32, hi: f32) -> f32 {
        libm::powf(10.0, self.range(lo, hi))
    }
    fn pick(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// A random line's covariance: variances over many orders, any correlation.
fn cov(rng: &mut Rng) -> Sym2 {
    let (a, c) = (rng.log(-8.0, 0.5), rng.log(-2.0, 8.0));
    let corr = rng.range(-0.9999, 0.9999);
    Sym2 {
        a,
        b: corr * libm::sqrtf(a * c),
        c,
    }
}

/// A segment on the line (α, ρ), or none.
fn ext(rng: &mut Rng, a: f32, r: f32) -> Option<([f32; 2], [f32; 2])> {
    if rng.pick(5) == 0 {
        return None;
    }
    let (s, c) = (libm::sinf(a), libm::cosf(a));
    let (t0, t1) = (rng.range(-8000.0, 8000.0), rng.range(-8000.0, 8000.0));
    let at = |t: f32| [r * c - t * s, r * s + t * c];
    Some((at(t0), at(t1)))
}

fn rho(rng: &mut Rng) -> f32 {
    match rng.pick(6) {
        0 => rng.range(0.0, 200.0),
        1 => rng.range(0.0, 2.0e6),
        _ => rng.range(0.0, 20000.0),
    }
}

/// Two sets, the current one partly the previous one seen from `truth` (with noise),
/// partly anything; a few degenerate values pushed without checks.
fn sets(rng: &mut Rng, truth: &Pose, cfg: &Config) -> (Set, Set) {
    let (mut p, mut c) = (Set::new(), Set::new());
    let np = 2 + rng.pick(63) as usize;
    let inv = truth.inverse();
    for _ in 0..np {
        let (a, r) = (rng.range(-PI, PI), rho(rng));
        let e = ext(rng, a, r);
        p.push_line(a, r, cov(rng), e, rng.range(0.0, 5000.0), Some(cfg));
        if rng.pick(3) > 0 {
            let (ca, cr) = inv.transform_line(a, r);
            let (ca, cr) =
                normalise_line(ca + rng.range(-0.05, 0.05), cr + rng.range(-300.0, 300.0));
            let e = ext(rng, ca, cr);
            c.push_line(ca, cr, cov(rng), e, rng.range(0.0, 5000.0), Some(cfg));
        }
    }
    for _ in 0..rng.pick(20) {
        let (a, r) = (rng.range(-PI, PI), rho(rng));
        let e = ext(rng, a, r);
        c.push_line(a, r, cov(rng), e, 1.0, Some(cfg));
    }
    // Degenerate values (a map's lines are not checked): NaN, ∞, negative variances.
    for set in [&mut p, &mut c] {
        if rng.pick(4) == 0 {
            let bad = [f32::NAN, f32::INFINITY, -1.0, 3.0e9][rng.pick(4) as usize];
            let k = rng.pick(3);
            let cv = Sym2 {
                a: if k == 0 { bad } else { 1e-4 },
                b: 0.0,
                c: if k == 1 { bad } else { 100.0 },
            };
            let r = if k == 2 { bad.abs() } else { 1000.0 };
            set.push_line(0.3, r, cv, None, 1.0, None);
        }
    }
    for _ in 0..rng.pick(6) {
        let q = [rng.range(-5000.0, 5000.0), rng.range(-5000.0, 5000.0)];
        let cv = Sym2 {
            a: 100.0,
            b: 0.0,
            c: 100.0,
        };
        p.push_pt(q, cv, 1.0, Some(cfg));
        c.push_pt(inv.transform_point(q), cv, 1.0, Some(cfg));
    }
    (p, c)
}

fn same_normal(a: &Normal, b: &Normal) -> bool {
    let bits = |n: &Normal| {
        let mut v = [0u32; 14];
        for (i, x) in n.h.iter().flatten().chain(&n.g).enumerate() {
            v[i] = x.to_bits();
        }
        v[12] = n.chi2.to_bits();
        v[13] = n.score.to_bits();
        v
    };
    bits(a) == bits(b) && a.lines == b.lines && a.pts == b.pts
}

#[test]
fn indices_change_nothing() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut matched = 0usize;
    for round in 0..3000 {
        let mut cfg = Config::default();
        if round % 7 == 0 {
            cfg.gate = rng.range(0.5, 40.0);
            cfg.slack = [
                rng.range(0.0, 0.5),
                rng.range(0.0, 500.0),
                rng.range(0.0, 0.1),
            ];
        }
        let truth = Pose::new(
            rng.range(-3000.0, 3000.0),
            rng.range(-3000.0, 3000.0),
            rng.range(-PI, PI),
        );
        let (p, c) = sets(&mut rng, &truth, &cfg);
        for _ in 0..4 {
            let pose = if rng.pick(2) == 0 {
                Pose::new(
                    truth.x + rng.range(-200.0, 200.0),
                    truth.y + rng.range(-200.0, 200.0),
                    truth.theta + rng.range(-0.1, 0.1),
                )
            } else {
                Pose::new(
                    rng.range(-5000.0, 5000.0),
                    rng.range(-5000.0, 5000.0),
                    rng.range(-PI, PI),
                )
            };
            let slack = [1.0, 0.5, 0.25, 0.1, 0.0][rng.pick(5) as usize];
            let (mut s1, mut s2) = (Scratch::new(), Scratch::new());
            let mut fast = Work::new(&p, &c, &cfg, None, &mut s1);
            let mut brute = Work::new(&p, &c, &cfg, None, &mut s2);
            brute.brute = true;
            let (mut oa, mut ob) = (Assoc::new(), Assoc::new());
            let na = fast.associate(&pose, slack, Some(&mut oa));
            let nb = brute.associate(&pose, slack, Some(&mut ob));
            assert!(same_normal(&na, &nb), "round {round}: {pose:?}");
            assert_eq!((oa.lines, oa.pts), (ob.lines, ob.pts), "round {round}");
            assert_eq!(fast.nc, brute.nc);
            for (x, y) in fast.s.contrib.iter().zip(&brute.s.contrib).take(fast.nc) {
                assert!(x.iter().zip(y).all(|(u, v)| u.to_bits() == v.to_bits()));
            }
            // A Gauss–Newton step's association (no match recorded): the same equations.
            let ns = brute.associate_step(&pose, slack);
            assert!(same_normal(&ns, &nb), "round {round}: {pose:?}");
            let (sa, sb) = (fast.score(&pose, slack), brute.score(&pose, slack));
            assert_eq!(sa.to_bits(), sb.to_bits(), "round {round}");
            matched += usize::from(na.lines);
        }
    }
    // The cases must include matches, many of them.
    assert!(matched > 20_000, "{matched}");
}

/// Each previous line is indexed by its own reach: a query near one well-determined line
/// finds the lines near its angle (and a line too uncertain for the index), not every line
/// because one previous line's angle is uncertain.
#[test]
fn index_reach_is_per_line() {
    let cfg = Config::default();
    let mut p = Set::new();
    let sharp = Sym2 {
        a: 1e-6,
        b: 0.0,
        c: 100.0,
    };
    // Lines every 0.1 rad over a half turn, and one whose α is uncertain (σ 0.7 rad).
    for k in 0..16 {
        p.push_line(k as f32 * 0.1, 2000.0, sharp, None, 1.0, Some(&cfg));
    }
    let vague = Sym2 {
        a: 0.5,
        b: 0.0,
        c: 100.0,
    };
    p.push_line(-1.0, 2000.0, vague, None, 1.0, Some(&cfg));
    let c = p.clone();
    let mut s = Scratch::new();
    let w = Work::new(&p, &c, &cfg, None, &mut s);
    let var = c.lines().get(8).map_or(0.0, |l| l.cov.a);
    let bits = w.candidates(0.8, var, 1.0);
    // Every line within the widest gate of a pair (√(9.21 (2 σ² + 0.05²)) = 0.156 rad with
    // the floor's σ of 0.008 rad) of 0.8 rad, and the vague one.
    for k in (7..=9).chain([16]) {
        assert!(bits & (1 << k) != 0, "{k}: {bits:b}");
    }
    // Not the lines more than a bucket (0.098 rad) beyond that.
    for k in (0..=4).chain(12..16) {
        assert!(bits & (1 << k) == 0, "{k}: {bits:b}");
    }
    // A current line as vague as that one tries every line.
    assert_eq!(w.candidates(0.8, 0.5, 1.0), (1 << 17) - 1);
}
