//! Whether a scan is made of 2 or 4 interleaved sweeps, decided from its ranges alone.
//!
//! An LMS2xx at 0.5° (0.25°) takes beam `i` in sweep `i mod 2` (`i mod 4`), one mirror turn
//! after the sweep before. A scanner that moves between turns sees each sweep from another
//! pose, so along a smooth surface the ranges of the sweeps are offset from each other: the
//! second difference `a_j = r_j − (r_{j−1} + r_{j+1})/2` takes a pattern that repeats with the
//! sweeps (2 sweeps: `±Δ`, alternating; 4 sweeps moving evenly: `−2Δ, 0, 0, 2Δ`), where one
//! sweep leaves only the surface's curvature, the same on neighbouring beams.
//!
//! [`detect`] cuts the scan into chunks of at most [`CHUNK`] consecutive returns without a
//! jump, and in each chunk estimates the four phase means of `a_j` (beam index mod 4), with
//! outliers (corners) beyond 5σ removed. Their alternating part `h₂ = (m₀ − m₁ + m₂ − m₃)/4`
//! is the 2-sweep offset, `((m₀ − m₂)/2, (m₁ − m₃)/2)` the part that only 4 sweeps have; each
//! is divided by its standard error from the range noise (`a_j` of neighbouring beams share
//! readings: their covariance is banded, 1.5σ², −σ², σ²/4), σ estimated from the scan by
//! `(r_{k+1} − r_k) − (r_{k+5} − r_{k+4})`, which no offset of 2 or 4 sweeps reaches. Over
//! the `K` chunks the squared z values add up to a χ² of `K` (2-sweep) and `2K` (4-sweep)
//! degrees of freedom under one sweep; each chunk's share is capped at [`CAP`] per degree of
//! freedom (one chunk of a fence or a radiator at the beam spacing cannot decide alone), and
//! its excess over the degrees of freedom in standard deviations, `(χ² − K)/√(2K)`, is the
//! evidence. A scan is declared interleaved when the evidence exceeds [`THRESHOLD`]: far in the
//! tail of one sweep's distribution, so that a one-sweep scan is not declared interleaved
//! (that would cost accuracy on plain scans), at the price of not seeing small offsets
//! (a robot standing still, whose sweeps agree: then aligning them would change nothing).
//!
//! No allocation: about 6 KiB of stack (one chunk's work, and up to 128 chunks' fits kept from the
//! noise pass for the evidence pass). Never panics; a scan with no usable chunk
//! is one sweep.

use crate::math;
use crate::scan::Scan;

/// Most second differences one chunk holds (its ranges: 2 more).
pub const CHUNK: usize = 32;
/// Fewest second differences a chunk must keep to count.
const MIN_ROWS: usize = 16;
/// Fewest chunks a scan needs to be declared interleaved.
const MIN_CHUNKS: usize = 4;
/// A jump between neighbouring returns ends a chunk: more than this many mm plus
/// [`JUMP_REL`] of the range.
const JUMP_MM: f32 = 100.0;
/// The range-proportional part of a jump.
const JUMP_REL: f32 = 0.05;
/// Outliers of a chunk's second differences (corners), in standard deviations.
const OUTLIER: f32 = 5.0;
/// Noise floor, mm: a noise-free scan is still not read to better than this.
const SIGMA_FLOOR: f32 = 0.25;
/// Most one chunk adds to the χ² per degree of freedom.
pub const CAP: f32 = 16.0;
/// Evidence (standard deviations of the χ² above its degrees of freedom) beyond which a
/// scan is declared made of 2 sweeps.
pub const THRESHOLD: f32 = 8.0;
/// Evidence of the period-4 offsets beyond which a scan is declared made of 4 sweeps (its
/// tail on one sweep is heavier than that of the alternating offset: two degrees of freedom
/// a chunk, and a curvature that changes along the chunk leaks into them).
pub const THRESHOLD4: f32 = 12.0;

/// Largest bearing step, rad, at which 4 sweeps are considered (0.375°): an LMS2xx
/// interleaves sweeps of 1°, 4 of them at 0.25°. At 0.5°, real 2-sweep scans (the CARMEN logs)
/// show period-4 offsets beyond [`THRESHOLD4`] in 17 of 6800 scans.
pub const MAX_STEP4: f32 = 0.375 * core::f32::consts::PI / 180.0;

/// What [`detect`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct Interleaving {
    /// The sweeps the scan is made of: 1, 2 or 4.
    pub sweeps: u8,
    /// Evidence of an offset between even and odd beams: `(χ² − K)/√(2K)` over `K` chunks.
    pub evidence2: f32,
    /// Evidence of an offset between beams 0 and 2 or 1 and 3 (mod 4) that only 4 sweeps
    /// have: `(χ² − 2K)/√(4K)`.
    pub evidence4: f32,
    /// Root mean square of the chunks' offset between even and odd ranges, mm.
    pub offset_mm: f32,
    /// The range noise estimated from the scan (with its floors), mm.
    pub sigma_mm: f32,
    /// Chunks used.
    pub chunks: u16,
}

impl Interleaving {
    /// One sweep, no evidence.
    const NONE: Interleaving = Interleaving {
        sweeps: 1,
        evidence2: 0.0,
        evidence4: 0.0,
        offset_mm: 0.0,
        sigma_mm: 0.0,
        chunks: 0,
    };
}

/// The sweeps `scan` is made of, from its ranges alone (its [`Scan::sweeps`] and
/// [`Scan::motion`] are not read): 2 or 4 when the offset between its sweeps shows beyond its
/// noise ([`THRESHOLD`]), else 1.
///
/// ```
/// use pfe_core::interleave::detect;
/// use pfe_core::{Scan, ScanGeometry};
/// // A wall 2 m ahead; the odd beams 8 mm further (a scanner moving back between sweeps).
/// let g = ScanGeometry::LMS200_180_050;
/// let ranges: Vec<f32> = (0..361)
///     .map(|i| {
///         let c = g.bearing(i).cos();
///         let r = if c > 0.3 { 2000.0 / c } else { f32::NAN };
///         r + if i % 2 == 1 { 8.0 } else { 0.0 }
///     })
///     .collect();
/// assert_eq!(detect(&Scan::from_mm(g, &ranges)).sweeps, 2);
/// let plain: Vec<f32> = ranges.iter().enumerate().map(|(i, r)| r - (i % 2) as f32 * 8.0).collect();
/// assert_eq!(detect(&Scan::from_mm(g, &plain)).sweeps, 1);
/// ```
pub fn detect(scan: &Scan) -> Interleaving {
    // Pass 1: a robust range noise, pooled over the chunks, for the outlier cut.
    let mut noise = Noise::default();
    chunks(scan, |_, r| noise.add(r));
    let Some(sigma0) = noise.sigma(scan.quantum) else {
        return Interleaving::NONE;
    };
    // Pass 2: the noise the fits leave, pooled; the fits kept for pass 3 where they fit.
    let mut residual = Residual::default();
    chunks(scan, |first, r| residual.add(first, r, sigma0));
    let Some(sigma) = residual.sigma(scan.quantum) else {
        return Interleaving::NONE;
    };
    // Pass 3: each chunk's offsets against that noise.
    let mut sum = Evidence::default();
    match residual.fits.get(..residual.count) {
        Some(fits) if !residual.overflow => fits.iter().for_each(|f| sum.add(f, sigma)),
        _ => chunks(scan, |first, r| {
            if let Some(f) = fit_chunk(first, r, sigma0) {
                sum.add(&f, sigma);
            }
        }),
    }
    sum.decide(sigma, math::abs(scan.geometry.angle_step) < MAX_STEP4)
}

/// Calls `f(first, ranges)` for each chunk of at most `CHUNK + 2` consecutive returns without
/// a jump (`first`: the beam of `ranges[0]`); consecutive chunks of one run share two ranges,
/// so that each second difference is in one chunk.
fn chunks(scan: &Scan, mut f: impl FnMut(usize, &[f32])) {
    let r_max = scan.geometry.r_max;
    let mut buf = [0.0f32; CHUNK + 2];
    let (mut len, mut first) = (0usize, 0usize);
    for i in 0..scan.ranges.len() {
        let r = scan.ranges.get_mm(i, r_max);
        let joins = match (r, len.checked_sub(1).and_then(|k| buf.get(k))) {
            (Some(r), Some(&prev)) => math::abs(r - prev) <= JUMP_MM + JUMP_REL * r.min(prev),
            _ => false,
        };
        if !joins {
            if len >= MIN_ROWS + 2 {
                f(first, buf.get(..len).unwrap_or(&[]));
            }
            len = 0;
        }
        let Some(r) = r else { continue };
        if len == 0 {
            first = i;
        }
        if let Some(slot) = buf.get_mut(len) {
            *slot = r;
            len += 1;
        }
        if len == CHUNK + 2 {
            f(first, &buf);
            // The next chunk starts with this one's last two ranges.
            buf.copy_within(CHUNK.., 0);
            len = 2;
            first = i - 1;
        }
    }
    if len >= MIN_ROWS + 2 {
        f(first, buf.get(..len).unwrap_or(&[]));
    }
}

/// The pooled noise of the chunks: `u_k = (r_{k+1} − r_k) − (r_{k+5} − r_{k+4})` has no
/// sweep offset (beams `k`, `k + 4` and `k + 1`, `k + 5` share a sweep of 2 or 4) and variance
/// 4σ²; around the chunk's median, beyond 3.5 robust standard deviations left out.
#[derive(Default)]
struct Noise {
    sum_sq: f32,
    count: u32,
}

impl Noise {
    fn add(&mut self, r: &[f32]) {
        let mut u = [0.0f32; CHUNK];
        let mut n = 0usize;
        for w in r.windows(6) {
            if let ([r0, r1, .., r4, r5], Some(slot)) = (w, u.get_mut(n)) {
                *slot = (r1 - r0) - (r5 - r4);
                n += 1;
            }
        }
        let Some(u) = u.get_mut(..n) else { return };
        if n < 4 {
            return;
        }
        let centre = median(u);
        let mut dev = [0.0f32; CHUNK];
        for (d, v) in dev.iter_mut().zip(u.iter()) {
            *d = math::abs(v - centre);
        }
        let mad = median(dev.get_mut(..n).unwrap_or(&mut []));
        let cut = 3.5 * 1.4826 * mad;
        for v in u.iter() {
            let d = v - centre;
            if math::abs(d) <= cut {
                self.sum_sq += d * d;
                self.count += 1;
            }
        }
    }

    /// σ, mm: at least the rounding's `q/√12` and [`SIGMA_FLOOR`]; `None` without data.
    fn sigma(&self, quantum: f32) -> Option<f32> {
        if self.count < 8 {
            return None;
        }
        let s = floored(math::sqrt(self.sum_sq / (4.0 * self.count as f32)), quantum);
        math::finite(s).then_some(s)
    }
}

/// Median of `v` (sorted in place; 0 for none). Insertion sort: at most [`CHUNK`] values.
fn median(v: &mut [f32]) -> f32 {
    for i in 1..v.len() {
        let mut j = i;
        while j > 0 {
            match (v.get(j - 1).copied(), v.get(j).copied()) {
                (Some(a), Some(b)) if b < a => v.swap(j - 1, j),
                _ => break,
            }
            j -= 1;
        }
    }
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v.get(n / 2).copied().unwrap_or(0.0),
        n => {
            0.5 * (v.get(n / 2 - 1).copied().unwrap_or(0.0) + v.get(n / 2).copied().unwrap_or(0.0))
        }
    }
}

/// Parameters of a chunk's fit of its second differences `a_j`: a line (the curvature and its
/// change), the alternating offset and its change, and the two of period 4.
const P: usize = 6;

/// The regressors of the second difference of beam `g`, centred at `c`.
fn regressors(g: usize, c: f32) -> [f32; P] {
    let t = (g as f32 - c) / CHUNK as f32;
    let alt = if g % 2 == 0 { 1.0 } else { -1.0 };
    let (cos, sin) = match g % 4 {
        0 => (1.0, 0.0),
        1 => (0.0, 1.0),
        2 => (-1.0, 0.0),
        _ => (0.0, -1.0),
    };
    [1.0, t, alt, alt * t, cos, sin]
}

/// One chunk's fit: the alternating offset `h` and the period-4 pair, their variances in units
/// of σ², its residual sum of squares and that sum's expectation in units of σ².
#[derive(Clone, Copy)]
struct ChunkFit {
    est: [f32; 3],
    var: [f32; 3],
    ss: f32,
    dof: f32,
}

impl ChunkFit {
    const ZERO: ChunkFit = ChunkFit {
        est: [0.0; 3],
        var: [0.0; 3],
        ss: 0.0,
        dof: 0.0,
    };
}

/// Least squares of the chunk's second differences on [`regressors`], leaving out those
/// beyond [`OUTLIER`] `sigma` (standardised residuals), once.
fn fit_chunk(first: usize, r: &[f32], sigma: f32) -> Option<ChunkFit> {
    let mut a = [0.0f32; CHUNK];
    let mut keep = [false; CHUNK];
    let mut m = 0usize;
    for (w, (slot, k)) in r.windows(3).zip(a.iter_mut().zip(keep.iter_mut())) {
        if let [r0, r1, r2] = w {
            *slot = r1 - 0.5 * (r0 + r2);
            *k = true;
            m += 1;
        }
    }
    // a[j] is beam first + 1 + j.
    let c = first as f32 + 1.0 + 0.5 * m as f32;
    let x = |j: usize| regressors(first + 1 + j, c);
    let cut = OUTLIER * sigma * math::sqrt(1.5);
    let mut inv = [[0.0f32; P]; P];
    for round in 0..2 {
        let kept = keep.iter().take(m).filter(|&&k| k).count();
        if kept < MIN_ROWS {
            return None;
        }
        let mut xtx = [[0.0f32; P]; P];
        for j in (0..m).filter(|&j| keep.get(j).copied().unwrap_or(false)) {
            let xj = x(j);
            for (row, xa) in xtx.iter_mut().zip(xj) {
                for (v, xb) in row.iter_mut().zip(xj) {
                    *v += xa * xb;
                }
            }
        }
        inv = invert(xtx)?;
        if round == 1 {
            break;
        }
        let beta = solve(&inv, &a, &keep, m, &x);
        for j in 0..m {
            let xj = x(j);
            let hjj = quad(&inv, &xj, &xj);
            let res = a.get(j).copied().unwrap_or(0.0) - dot(&beta, &xj);
            let lim = cut * math::sqrt((1.0 - hjj).max(0.05));
            if let Some(k) = keep.get_mut(j) {
                if *k && !(math::abs(res) <= lim) {
                    *k = false;
                }
            }
        }
    }
    let beta = solve(&inv, &a, &keep, m, &x);
    let kept = |j: usize| keep.get(j).copied().unwrap_or(false);
    // g[j] = (XᵀX)⁻¹ x_j: its component p is row j's weight in parameter p (the inverse is
    // symmetric), and x_k · g[j] is the hat matrix's (k, j).
    let mut g = [[0.0f32; P]; CHUNK];
    for (j, gj) in g.iter_mut().enumerate().take(m) {
        let xj = x(j);
        for (v, row) in gj.iter_mut().zip(&inv) {
            *v = dot(row, &xj);
        }
    }
    let zero = [0.0f32; P];
    let mut ss = 0.0f32;
    let mut trace_h_sigma = 0.0f32;
    let mut var = [0.0f32; 3];
    let mut n = 0usize;
    for j in (0..m).filter(|&j| kept(j)) {
        let gj = g.get(j).unwrap_or(&zero);
        let res = a.get(j).copied().unwrap_or(0.0) - dot(&beta, &x(j));
        ss += res * res;
        n += 1;
        for k in (j..(j + 3).min(m)).filter(|&k| kept(k)) {
            let gk = g.get(k).unwrap_or(&zero);
            let f = if k == j { 1.0 } else { 2.0 } * rho(k - j);
            trace_h_sigma += f * dot(&x(k), gj);
            for (v, p) in var.iter_mut().zip([2usize, 4, 5]) {
                *v += f * gj.get(p).copied().unwrap_or(0.0) * gk.get(p).copied().unwrap_or(0.0);
            }
        }
    }
    let est = [
        beta.get(2).copied().unwrap_or(0.0),
        beta.get(4).copied().unwrap_or(0.0),
        beta.get(5).copied().unwrap_or(0.0),
    ];
    let dof = 1.5 * n as f32 - trace_h_sigma;
    (math::all_finite(&est) && math::all_finite(&var) && var.iter().all(|&v| v > 0.0) && dof > 0.0)
        .then_some(ChunkFit { est, var, ss, dof })
}

fn dot(a: &[f32; P], b: &[f32; P]) -> f32 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `aᵀ M b`.
fn quad(m: &[[f32; P]; P], a: &[f32; P], b: &[f32; P]) -> f32 {
    m.iter().zip(a).map(|(row, x)| x * dot(row, b)).sum()
}

/// `(XᵀX)⁻¹ Xᵀ a` over the kept rows.
fn solve(
    inv: &[[f32; P]; P],
    a: &[f32; CHUNK],
    keep: &[bool; CHUNK],
    m: usize,
    x: &impl Fn(usize) -> [f32; P],
) -> [f32; P] {
    let mut xta = [0.0f32; P];
    for j in 0..m {
        if let (Some(&v), Some(true)) = (a.get(j), keep.get(j)) {
            for (s, xv) in xta.iter_mut().zip(x(j)) {
                *s += xv * v;
            }
        }
    }
    let mut beta = [0.0f32; P];
    for (b, row) in beta.iter_mut().zip(inv) {
        *b = dot(row, &xta);
    }
    beta
}

/// The inverse of a symmetric positive definite matrix by Gauss–Jordan with partial
/// pivoting; `None` when it is (nearly) singular.
fn invert(mut m: [[f32; P]; P]) -> Option<[[f32; P]; P]> {
    let mut inv = [[0.0f32; P]; P];
    for (i, row) in inv.iter_mut().enumerate() {
        if let Some(v) = row.get_mut(i) {
            *v = 1.0;
        }
    }
    let scale = m
        .iter()
        .enumerate()
        .map(|(i, r)| r.get(i).copied().unwrap_or(0.0))
        .fold(0.0f32, f32::max);
    for col in 0..P {
        let mut piv = col;
        for row in col..P {
            let v = |r: usize| {
                m.get(r)
                    .and_then(|x| x.get(col))
                    .map_or(0.0, |v| math::abs(*v))
            };
            if v(row) > v(piv) {
                piv = row;
            }
        }
        m.swap(col, piv);
        inv.swap(col, piv);
        let d = m.get(col).and_then(|r| r.get(col)).copied().unwrap_or(0.0);
        if !(math::abs(d) > 1e-6 * scale) {
            return None;
        }
        let (mrow, irow) = (m.get(col).copied()?, inv.get(col).copied()?);
        let (mrow, irow) = (mrow.map(|v| v / d), irow.map(|v| v / d));
        for r in 0..P {
            let f = if r == col {
                continue;
            } else {
                m.get(r).and_then(|x| x.get(col)).copied().unwrap_or(0.0)
            };
            if let (Some(mr), Some(ir)) = (m.get_mut(r), inv.get_mut(r)) {
                for (v, p) in mr.iter_mut().zip(mrow) {
                    *v -= f * p;
                }
                for (v, p) in ir.iter_mut().zip(irow) {
                    *v -= f * p;
                }
            }
        }
        if let (Some(mr), Some(ir)) = (m.get_mut(col), inv.get_mut(col)) {
            *mr = mrow;
            *ir = irow;
        }
    }
    math::all_finite(inv.as_flattened()).then_some(inv)
}

/// Covariance of the second differences of beams `d` apart, in units of σ².
fn rho(d: usize) -> f32 {
    match d {
        0 => 1.5,
        1 => -1.0,
        2 => 0.25,
        _ => 0.0,
    }
}

/// Most chunk fits pass 2 keeps for pass 3 (4096 second differences); a longer scan is
/// fitted again.
const KEPT_FITS: usize = 128;

/// The residual variance of the chunks' fits, pooled, and the fits.
struct Residual {
    ss: f32,
    dof: f32,
    fits: [ChunkFit; KEPT_FITS],
    count: usize,
    overflow: bool,
}

impl Default for Residual {
    fn default() -> Self {
        Self {
            ss: 0.0,
            dof: 0.0,
            fits: [ChunkFit::ZERO; KEPT_FITS],
            count: 0,
            overflow: false,
        }
    }
}

impl Residual {
    fn add(&mut self, first: usize, r: &[f32], sigma0: f32) {
        if let Some(f) = fit_chunk(first, r, sigma0) {
            self.ss += f.ss;
            self.dof += f.dof;
            match self.fits.get_mut(self.count) {
                Some(slot) => {
                    *slot = f;
                    self.count += 1;
                }
                None => self.overflow = true,
            }
        }
    }

    /// σ, mm, with the floors; `None` without data.
    fn sigma(&self, quantum: f32) -> Option<f32> {
        if !(self.dof >= 8.0) {
            return None;
        }
        Some(floored(math::sqrt(self.ss / self.dof), quantum))
    }
}

/// `s` raised to the rounding's `q/√12` and [`SIGMA_FLOOR`].
fn floored(s: f32, quantum: f32) -> f32 {
    let q = if quantum > 0.0 && math::finite(quantum) {
        quantum / math::sqrt(12.0)
    } else {
        0.0
    };
    s.max(q).max(SIGMA_FLOOR)
}

/// The capped χ² sums over the chunks.
#[derive(Default)]
struct Evidence {
    chi2_2: f32,
    chi2_4: f32,
    chunks: u32,
    offset_sq: f32,
}

impl Evidence {
    fn add(&mut self, f: &ChunkFit, sigma: f32) {
        let [h, c4, s4] = f.est;
        let [vh, vc, vs] = f.var.map(|v| v * sigma * sigma);
        let z2 = h * h / vh;
        let z4 = c4 * c4 / vc + s4 * s4 / vs;
        if !(math::finite(z2) && math::finite(z4)) {
            return;
        }
        self.chi2_2 += z2.min(CAP);
        self.chi2_4 += z4.min(2.0 * CAP);
        self.offset_sq += h * h;
        self.chunks += 1;
    }

    fn decide(&self, sigma: f32, four: bool) -> Interleaving {
        let k = self.chunks as f32;
        if self.chunks == 0 {
            return Interleaving {
                sigma_mm: sigma,
                ..Interleaving::NONE
            };
        }
        let evidence2 = (self.chi2_2 - k) / math::sqrt(2.0 * k);
        let evidence4 = (self.chi2_4 - 2.0 * k) / math::sqrt(4.0 * k);
        let enough = self.chunks as usize >= MIN_CHUNKS;
        let sweeps = if enough && four && evidence4 > THRESHOLD4 {
            4
        } else if enough && evidence2 > THRESHOLD {
            2
        } else {
            1
        };
        Interleaving {
            sweeps,
            evidence2,
            evidence4,
            offset_mm: math::sqrt(self.offset_sq / k),
            sigma_mm: sigma,
            chunks: u16::try_from(self.chunks).unwrap_or(u16::MAX),
        }
    }
}

#[cfg(test)]
#[path = "interleave_leverage.rs"]
mod leverage;

#[cfg(test)]
mod tests {
    use super::*;

    /// A chunk's variance factors and degrees of freedom against their definitions, in f64 with
    /// every matrix written out: the second differences' covariance is banded (1.5, −1, 1/4 σ²
    /// at lags 0, 1, 2), so with G = (XᵀX)⁻¹Xᵀ the estimates' variances are the diagonal of
    /// G Σ Gᵀ and the residuals' expected sum of squares is tr((I − XG) Σ) = 1.5 m − tr(XGΣ).
    /// Ranges all equal (no outliers: every row kept), chunks of 18, 25 and 32 rows.
    #[test]
    #[allow(clippy::indexing_slicing)]
    fn a_chunk_s_variances_and_dof_follow_the_banded_covariance() {
        for (first, m) in [(5usize, 18usize), (8, 32), (3, 25)] {
            let row = |k: usize| super::leverage::model_row(first, m, k);
            let cov = |j: usize, k: usize| match j.abs_diff(k) {
                0 => 1.5,
                1 => -1.0,
                2 => 0.25,
                _ => 0.0,
            };
            // [XᵀX | I] reduced to [I | (XᵀX)⁻¹].
            let mut a = [[0.0f64; 12]; 6];
            for k in 0..m {
                let x = row(k);
                for p in 0..6 {
                    for q in 0..6 {
                        a[p][q] += x[p] * x[q];
                    }
                }
            }
            for p in 0..6 {
                a[p][6 + p] = 1.0;
            }
            super::leverage::gauss_jordan(&mut a);
            // G's column k: (XᵀX)⁻¹ x_k.
            let g: [[f64; 6]; CHUNK] = core::array::from_fn(|k| {
                let x = row(k);
                core::array::from_fn(|p| (0..6).map(|q| a[p][6 + q] * x[q]).sum())
            });
            let mut var = [0.0f64; 3];
            let mut trace = 0.0f64;
            for j in 0..m {
                for k in 0..m {
                    let s = cov(j, k);
                    for (v, p) in var.iter_mut().zip([2usize, 4, 5]) {
                        *v += g[j][p] * s * g[k][p];
                    }
                    // (XG)_{jk} Σ_{kj}.
                    let h: f64 = (0..6).map(|p| row(j)[p] * g[k][p]).sum();
                    trace += h * s;
                }
            }
            let dof = 1.5 * m as f64 - trace;
            let r = [3000.0f32; CHUNK + 2];
            let f = fit_chunk(first, &r[..m + 2], 1.0).expect("a fit");
            let close = |got: f32, want: f64| (f64::from(got) - want).abs() <= 1e-3 * want.abs();
            for (got, want) in f.var.iter().zip(var) {
                assert!(
                    close(*got, want),
                    "first {first}, m {m}: {:?} against {var:?}",
                    f.var
                );
            }
            assert!(
                close(f.dof, dof),
                "first {first}, m {m}: dof {} against {dof}",
                f.dof
            );
            assert_eq!((f.est, f.ss), ([0.0; 3], 0.0));
        }
    }

    /// A chunk's evidence is each estimate squared over its variance (σ² times the fit's
    /// factor), capped: the half offset's 2² / (0.25 · 2²) = 4 for 2 sweeps; the quarter
    /// offsets' 3² / (0.5 · 2²) + 1² / (0.125 · 2²) = 4.5 + 2 = 6.5 for 4 (a remainder in place
    /// of the first quotient gives 1 + 2), and a large one capped at 2 · CAP.
    #[test]
    fn a_chunk_s_evidence_is_its_estimates_over_their_variances() {
        let fit = |est: [f32; 3]| ChunkFit {
            est,
            var: [0.25, 0.5, 0.125],
            ..ChunkFit::ZERO
        };
        let mut e = Evidence::default();
        e.add(&fit([2.0, 3.0, 1.0]), 2.0);
        assert_eq!((e.chi2_2, e.chi2_4, e.chunks), (4.0, 6.5, 1));
        assert_eq!(e.offset_sq, 4.0);
        e.add(&fit([0.0, 30.0, 0.0]), 2.0);
        assert_eq!((e.chi2_2, e.chi2_4, e.chunks), (4.0, 6.5 + 2.0 * CAP, 2));
    }

    /// σ from the differences' sum of squares: each difference of two two-beam differences
    /// has 4 σ² of variance; the rounding's q/√12 and the floor bound it below.
    #[test]
    fn sigma_is_the_root_of_a_quarter_of_the_mean_square() {
        let noise = |sum_sq: f32, count: u32| Noise { sum_sq, count };
        assert_eq!(noise(4.0 * 100.0 * 25.0, 100).sigma(0.0), Some(5.0));
        assert_eq!(noise(4.0 * 10.0 * 9.0, 10).sigma(1.0), Some(3.0));
        assert_eq!(
            noise(4.0 * 10.0 * 9.0, 10).sigma(50.0),
            Some(50.0 / 12f32.sqrt())
        );
        assert_eq!(noise(0.0, 10).sigma(0.0), Some(SIGMA_FLOOR));
        assert_eq!(noise(1.0, 7).sigma(0.0), None);
    }

    #[test]
    fn median_of_few() {
        assert_eq!(median(&mut []), 0.0);
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
    }

    /// `median` sorts its values (a value moves as far as it must, not one place) and takes
    /// the middle one, or the mean of the middle two: values in descending order and a
    /// shuffle, against the median of the values counted from their definition.
    #[test]
    fn median_sorts_values_that_move_far() {
        let mut v = [3.0f32, 2.0, 1.0];
        assert_eq!(median(&mut v), 2.0);
        assert_eq!(v, [1.0, 2.0, 3.0]);
        let mut v = [6.0f32, 5.0, 4.0, 3.0, 2.0, 1.0];
        assert_eq!(median(&mut v), 3.5);
        assert_eq!(v, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        let mut v = [9.0f32, 4.0, 7.0, 1.0, 8.0, 2.0, 6.0, 3.0, 5.0];
        let want = v
            .iter()
            .copied()
            .find(|&x| v.iter().filter(|&&y| y < x).count() == 4);
        assert_eq!(Some(median(&mut v)), want);
    }
}
