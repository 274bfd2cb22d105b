//! Lines on the beams two methods share. lines% weighs each method's lines by their own
//! points, so a method that also makes lines where another makes none is not scored on the
//! same beams as it. Here each beam of scan k is classed per method by the line of
//! ≥ [`MIN_LINE_POINTS`] points whose span (first to last beam) holds it: none, re-found in
//! k+1, or not re-found; pfe `default` is then compared with each other method on the beams
//! both hold in such lines, and on the beams only one of them does. A beam counts once per
//! pair of scans.

use serde::Serialize;

use super::compare::{rematch, Seen, MIN_LINE_POINTS};
use super::frame::FrameChange;

/// What a beam of scan k is in one method's lines of ≥ [`MIN_LINE_POINTS`] points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BeamLine {
    /// In no such line.
    None,
    /// In a line that re-appears in scan k+1.
    Refound,
    /// In a line that does not.
    Lost,
}

/// Each of `beams` beams of scan `a` classed by its lines and their match in `b`.
///
/// ```
/// use pfe_eval::realdata::shared::{beam_lines, BeamLine};
/// use pfe_eval::realdata::{LineObs, Seen};
/// // A wall 2 m ahead on beams 2..=13, seen again from the same pose.
/// let wall = LineObs {
///     alpha: 0.0, rho: 2000.0, cov: [[1e-6, 0.0], [0.0, 1.0]],
///     start: [2000.0, -500.0], end: [2000.0, 500.0], points: 12, beams: [2, 13],
/// };
/// let a = Seen { pose: [0.0; 3], lines: vec![wall], ..Seen::default() };
/// let b = a.clone();
/// let c = beam_lines(&a, &b, 16);
/// assert_eq!(c[1], BeamLine::None);
/// assert!(c[2..=13].iter().all(|&x| x == BeamLine::Refound));
/// // Not seen again: lost.
/// let empty = Seen { pose: [0.0; 3], ..Seen::default() };
/// assert_eq!(beam_lines(&a, &empty, 16)[5], BeamLine::Lost);
/// ```
pub fn beam_lines(a: &Seen, b: &Seen, beams: usize) -> Vec<BeamLine> {
    let change = FrameChange::between(a.pose, b.pose);
    let mut out = vec![BeamLine::None; beams];
    for l in a.lines.iter().filter(|l| l.points >= MIN_LINE_POINTS) {
        let class = if rematch(l, b, &change).is_some() {
            BeamLine::Refound
        } else {
            BeamLine::Lost
        };
        let [first, last] = l.beams;
        for c in out.iter_mut().take(last.saturating_add(1)).skip(first) {
            // A beam that two lines hold counts as re-found if either is.
            if *c != BeamLine::Refound {
                *c = class;
            }
        }
    }
    out
}

/// Beams of scan k over a log's pairs, pfe `default` (the reference) against one other method.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Shared {
    /// The other method.
    pub method: String,
    /// Beams both hold in lines.
    pub both: usize,
    /// Of those, beams whose reference line re-appears.
    pub both_reference_refound: usize,
    /// Of those, beams whose other method's line re-appears.
    pub both_other_refound: usize,
    /// Beams only the reference holds in lines.
    pub only_reference: usize,
    /// Of `only_reference`, re-found.
    pub only_reference_refound: usize,
    /// Beams only the other method holds in lines.
    pub only_other: usize,
    /// Of `only_other`, re-found.
    pub only_other_refound: usize,
}

impl Shared {
    /// An empty tally against `method`.
    pub fn new(method: &str) -> Self {
        Self {
            method: method.to_string(),
            ..Self::default()
        }
    }

    /// Adds one pair's beams, classed for the reference and the other method.
    pub fn add(&mut self, reference: &[BeamLine], other: &[BeamLine]) {
        use BeamLine::{Lost, None, Refound};
        for (&r, &o) in reference.iter().zip(other) {
            match (r, o) {
                (None, None) => {}
                (_, None) => {
                    self.only_reference += 1;
                    self.only_reference_refound += usize::from(r == Refound);
                }
                (None, _) => {
                    self.only_other += 1;
                    self.only_other_refound += usize::from(o == Refound);
                }
                (Refound | Lost, Refound | Lost) => {
                    self.both += 1;
                    self.both_reference_refound += usize::from(r == Refound);
                    self.both_other_refound += usize::from(o == Refound);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use BeamLine::{Lost, None, Refound};

    #[test]
    fn beams_are_counted_by_who_holds_them_and_who_finds_them_again() {
        let mut s = Shared::new("other");
        s.add(
            &[None, Refound, Refound, Lost, Lost, None, Refound],
            &[Refound, Lost, Refound, Refound, None, None, None],
        );
        assert_eq!(
            s,
            Shared {
                method: "other".into(),
                both: 3,
                both_reference_refound: 2,
                both_other_refound: 2,
                only_reference: 2,
                only_reference_refound: 1,
                only_other: 1,
                only_other_refound: 1,
            }
        );
    }

    #[test]
    fn short_lines_and_beams_past_the_scan_are_not_counted() {
        let line = |beams: [usize; 2], points| super::super::LineObs {
            alpha: 0.0,
            rho: 2000.0,
            cov: [[1e-6, 0.0], [0.0, 1.0]],
            start: [2000.0, -500.0],
            end: [2000.0, 500.0],
            points,
            beams,
        };
        let a = Seen {
            pose: [0.0; 3],
            lines: vec![line([0, 8], 9), line([10, 30], 21)],
            circles: vec![],
            objects: vec![],
        };
        let c = beam_lines(&a, &a, 20);
        assert_eq!(c.len(), 20);
        assert!(c[..10].iter().all(|&x| x == None));
        assert!(c[10..].iter().all(|&x| x == Refound));
    }
}
