//! Deterministic synthetic masks for tests and benchmarks: takes sizes (and a seed where
//! random) and gives a [`BitMask`]. The paper's spiral strip, disc, annulus, a patch with two
//! holes, a comb with deep slots, nested holes with islands, 1-px lines, speckle noise and
//! random blobs. Everything is a pure function of its arguments. Shared by the library's
//! unit tests (as `crate::mesh::synth`), the integration tests and the benchmarks with
//! `#[path = "…/tests/common/synth_masks.rs"] mod synth;`.
#![allow(dead_code)]

use glam::DVec2;
use lapclone::mesh::BitMask;

/// A tiny deterministic generator (SplitMix64), so masks do not depend on a `rand` version.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
}

fn centre_of(width: usize, height: usize) -> DVec2 {
    DVec2::new(width as f64 / 2.0, height as f64 / 2.0)
}

fn pixel_centre(x: usize, y: usize) -> DVec2 {
    DVec2::new(x as f64 + 0.5, y as f64 + 0.5)
}

/// The paper's "spiral": an Archimedean spiral band of 4.5 turns whose width grows from
/// 3 px at the centre to about 20 px (at 770×743) on the outside.
pub fn spiral(width: usize, height: usize) -> BitMask {
    let centre = centre_of(width, height);
    let outer_radius = 0.47 * width.min(height) as f64;
    let start_radius = 0.05 * width.min(height) as f64;
    let turns = 4.5;
    let theta_max = std::f64::consts::TAU * turns;
    let pitch = (outer_radius - start_radius) / turns;
    let growth = pitch / std::f64::consts::TAU;
    let half_min = 1.5;
    let half_max = (10.0 * width.min(height) as f64 / 743.0)
        .min(0.3 * pitch)
        .max(half_min);
    BitMask::from_fn(width, height, |x, y| {
        let d = pixel_centre(x, y) - centre;
        let r = d.length();
        let phi = d.y.atan2(d.x).rem_euclid(std::f64::consts::TAU);
        let turn = ((r - start_radius) / pitch - phi / std::f64::consts::TAU).round();
        (-1..=1).any(|k| {
            let theta = phi + std::f64::consts::TAU * (turn + k as f64);
            if !(0.0..=theta_max).contains(&theta) {
                return false;
            }
            let half = half_min + (half_max - half_min) * theta / theta_max;
            (r - (start_radius + growth * theta)).abs() <= half
        })
    })
}

/// The spiral at the paper's size, 770×743.
pub fn spiral_default() -> BitMask {
    spiral(770, 743)
}

/// A centred disc of the given radius.
pub fn disc(width: usize, height: usize, radius: f64) -> BitMask {
    let centre = centre_of(width, height);
    BitMask::from_fn(width, height, |x, y| {
        pixel_centre(x, y).distance(centre) <= radius
    })
}

/// A centred ring between `inner` and `outer` radii (one hole).
pub fn annulus(width: usize, height: usize, inner: f64, outer: f64) -> BitMask {
    let centre = centre_of(width, height);
    BitMask::from_fn(width, height, |x, y| {
        let r = pixel_centre(x, y).distance(centre);
        r <= outer && r > inner
    })
}

/// A rounded-corner rectangle with two round holes side by side.
pub fn two_holes(width: usize, height: usize) -> BitMask {
    let (w, h) = (width as f64, height as f64);
    let holes = [DVec2::new(0.3 * w, 0.5 * h), DVec2::new(0.7 * w, 0.5 * h)];
    let hole_radius = 0.12 * w.min(h);
    let margin = 0.1 * w.min(h);
    BitMask::from_fn(width, height, |x, y| {
        let p = pixel_centre(x, y);
        let in_rect = p.x > margin && p.x < w - margin && p.y > margin && p.y < h - margin;
        in_rect && holes.iter().all(|c| p.distance(*c) > hole_radius)
    })
}

/// A comb: a bar along the top with teeth hanging down, separated by deep slots `slot` px
/// wide (teeth as wide as `tooth` px).
pub fn comb(width: usize, height: usize, tooth: usize, slot: usize) -> BitMask {
    let bar = (height / 6).max(2);
    let (margin_x, margin_y) = (width / 20, height / 20);
    BitMask::from_fn(width, height, |x, y| {
        if x < margin_x || x >= width - margin_x || y < margin_y || y >= height - margin_y {
            return false;
        }
        y < margin_y + bar || (x - margin_x) % (tooth + slot) < tooth
    })
}

/// Nested rings: a disc with a ring-shaped hole, an island inside it that has its own hole,
/// and a small island inside that hole (2 holes, 3 pieces).
pub fn nested(width: usize, height: usize) -> BitMask {
    let centre = centre_of(width, height);
    let s = 0.48 * width.min(height) as f64;
    // Radii bands, outside in: inside, hole, island, hole, island.
    let bands = [1.0, 0.8, 0.6, 0.4, 0.2];
    BitMask::from_fn(width, height, |x, y| {
        let r = pixel_centre(x, y).distance(centre) / s;
        let band = bands.iter().filter(|&&b| r <= b).count();
        band % 2 == 1
    })
}

/// A 1-pixel-wide horizontal line through the middle, `length` pixels long.
pub fn line(width: usize, height: usize, length: usize) -> BitMask {
    let x0 = width.saturating_sub(length) / 2;
    BitMask::from_fn(width, height, |x, y| {
        y == height / 2 && x >= x0 && x < x0 + length
    })
}

/// A 1-pixel diagonal staircase: pixels touching only at corners (one piece via saddles).
pub fn diagonal_line(size: usize) -> BitMask {
    BitMask::from_fn(size, size, |x, y| x == y)
}

/// Random pixels, each inside with probability `fraction`.
pub fn speckle(width: usize, height: usize, fraction: f64, seed: u64) -> BitMask {
    let mut rng = SplitMix64::new(seed);
    let mut mask = BitMask::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let inside = rng.next_f64() < fraction;
            mask.set(x as i64, y as i64, inside);
        }
    }
    mask
}

/// Random union of discs minus smaller discs (holes, thin parts, border contact), from a seed.
pub fn blobs(width: usize, height: usize, seed: u64) -> BitMask {
    let mut rng = SplitMix64::new(seed);
    let (w, h) = (width as f64, height as f64);
    let scale = w.min(h);
    let count = 2 + (rng.next_u64() % 5) as usize;
    let mut discs = Vec::new();
    for _ in 0..count {
        let c = DVec2::new(rng.range(0.0, w), rng.range(0.0, h));
        discs.push((c, rng.range(0.05, 0.3) * scale));
    }
    let hole_count = (rng.next_u64() % 4) as usize;
    let mut holes = Vec::new();
    for _ in 0..hole_count {
        let (c, r) = discs[(rng.next_u64() % count as u64) as usize];
        let offset = DVec2::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5)) * r;
        holes.push((c + offset, rng.range(0.1, 0.4) * r));
    }
    BitMask::from_fn(width, height, |x, y| {
        let p = pixel_centre(x, y);
        discs.iter().any(|(c, r)| p.distance(*c) <= *r)
            && holes.iter().all(|(c, r)| p.distance(*c) > *r)
    })
}
