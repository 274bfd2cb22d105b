//! The refinement stops when it lands on a solution refined already, and only then.
use super::*;
use crate::geom::normalise_line;
use core::f32::consts::FRAC_PI_2;

#[test]
fn stops_on_a_solution_refined_already_and_only_there() {
    let cfg = Config::default();
    let truth = Pose::new(300.0, 100.0, 0.2);
    let inv = truth.inverse();
    let (mut p, mut c) = (Set::new(), Set::new());
    let cv = Sym2 {
        a: 1e-6,
        b: 0.0,
        c: 25.0,
    };
    let walls = [
        (0.0, 3000.0),
        (FRAC_PI_2, 2000.0),
        (PI, 1500.0),
        (-FRAC_PI_2, 2500.0),
        (0.7, 2200.0),
    ];
    for (a, r) in walls {
        p.push_line(a, r, cv, None, 1.0, Some(&cfg));
        let (ca, cr) = inv.transform_line(a, r);
        let (ca, cr) = normalise_line(ca, cr);
        c.push_line(ca, cr, cv, None, 1.0, Some(&cfg));
    }
    let mut s = Scratch::new();
    let mut w = Work::new(&p, &c, &cfg, None, &mut s);
    let start = Pose::new(380.0, 40.0, 0.23);
    let alone = converge(&mut w, start, None, &[]);
    assert!(alone.is_some_and(|a| (a.x - truth.x).abs() < 1.0
        && (a.y - truth.y).abs() < 1.0
        && (a.theta - truth.theta).abs() < 1e-4));
    let alone = alone.unwrap_or(start);
    let hyp = |pose: Pose| Hyp { pose, score: 1.0 };
    // Another start that reaches the same solution stops there.
    let other = Pose::new(250.0, 160.0, 0.17);
    assert!(converge(&mut w, other, None, &[hyp(alone)]).is_none());
    // Solutions apart from it in x, y or θ alone neither stop it nor change it.
    let bits = |p: Pose| [p.x.to_bits(), p.y.to_bits(), p.theta.to_bits()];
    for d in [
        Pose::new(alone.x + 40.0, alone.y, alone.theta),
        Pose::new(alone.x, alone.y - 40.0, alone.theta),
        Pose::new(alone.x, alone.y, alone.theta + 0.015),
    ] {
        let r = converge(&mut w, start, None, &[hyp(d)]);
        assert_eq!(r.map(bits), Some(bits(alone)), "{d:?}");
    }
}
