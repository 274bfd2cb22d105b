//! What the integration tests share: a small deterministic generator, so every run sees the
//! same numbers.
#![allow(dead_code)]

/// xorshift64* with Box–Muller normals.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f32 {
        (lo + (hi - lo) * self.uniform()) as f32
    }
    pub fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// A scene: wall segments (ends, mm) and pillars (centres, mm).
pub struct World {
    pub walls: Vec<([f32; 2], [f32; 2])>,
    pub pillars: Vec<[f32; 2]>,
}

/// The corners (mm) of an irregular convex room about 9 m × 7 m: no wall hides another from
/// inside.
pub const ROOM: [[f32; 2]; 7] = [
    [-4000.0, -3000.0],
    [1000.0, -3600.0],
    [5200.0, -2000.0],
    [5600.0, 1500.0],
    [2500.0, 3800.0],
    [-2500.0, 3400.0],
    [-4600.0, 800.0],
];

/// A closed polygon of walls (corners, mm), no pillar.
pub fn polygon(c: &[[f32; 2]]) -> World {
    World {
        walls: (0..c.len()).map(|i| (c[i], c[(i + 1) % c.len()])).collect(),
        pillars: Vec::new(),
    }
}

/// A straight corridor 2.4 m wide along x, its walls in pieces (doors between), no pillar.
pub fn corridor() -> World {
    let mut walls = Vec::new();
    for k in -6..6 {
        let x0 = k as f32 * 1500.0;
        walls.push(([x0 + 1200.0, 1200.0], [x0, 1200.0]));
        walls.push(([x0 + 300.0, -1200.0], [x0 + 1400.0, -1200.0]));
    }
    World {
        walls,
        pillars: Vec::new(),
    }
}
