//! Synthetic patch masks at the sizes of the paper's Table I models, for benches and tests
//! where no photo fits. It takes nothing but the shape's parameters and gives row-major
//! `Vec<bool>` masks (true = inside) that keep a margin from the image border, so every piece
//! has outside neighbours for its Dirichlet values. The horse model is not here: it comes from
//! the bundled silhouette asset.

use std::f64::consts::TAU;

/// A named mask of `width × height` pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct SyntheticMask {
    pub name: &'static str,
    pub width: usize,
    pub height: usize,
    pub inside: Vec<bool>,
}

impl SyntheticMask {
    fn from_fn(
        name: &'static str,
        width: usize,
        height: usize,
        inside: impl Fn(f64, f64) -> bool,
    ) -> Self {
        let inside = (0..width * height)
            .map(|p| inside((p % width) as f64 + 0.5, (p / width) as f64 + 0.5))
            .collect();
        Self {
            name,
            width,
            height,
            inside,
        }
    }

    pub fn inside_count(&self) -> usize {
        self.inside.iter().filter(|&&b| b).count()
    }
}

/// An Archimedean spiral band (the paper's Fig. 5 spiral, 770×743): three turns, arms about
/// 57 px wide with 45 px gaps, a round cap at the centre.
pub fn spiral(width: usize, height: usize) -> SyntheticMask {
    let (cx, cy) = (width as f64 / 2.0, height as f64 / 2.0);
    let outer = 0.45 * width.min(height) as f64;
    let turns = 3.0;
    let start = 0.08 * outer;
    let pitch = (outer - start) / (turns * TAU); // radius gained per radian
    let half_width = 0.28 * pitch * TAU;
    SyntheticMask::from_fn("spiral", width, height, |x, y| {
        let (dx, dy) = (x - cx, y - cy);
        let r = dx.hypot(dy);
        if r < start + half_width * 0.5 {
            return true;
        }
        let phase = dy.atan2(dx).rem_euclid(TAU);
        (0..=turns as usize).any(|k| {
            let theta = phase + TAU * k as f64;
            theta <= turns * TAU && (r - (start + pitch * theta)).abs() < half_width
        })
    })
}

/// An ellipse, mouth-like (121×85).
pub fn mouth(width: usize, height: usize) -> SyntheticMask {
    let (cx, cy) = (width as f64 / 2.0, height as f64 / 2.0);
    let (ax, ay) = (0.42 * width as f64, 0.36 * height as f64);
    SyntheticMask::from_fn("mouth", width, height, |x, y| {
        ((x - cx) / ax).powi(2) + ((y - cy) / ay).powi(2) < 1.0
    })
}

/// A tilted quadrilateral with a notch, raft-like (342×353).
pub fn raft(width: usize, height: usize) -> SyntheticMask {
    let (w, h) = (width as f64, height as f64);
    let (cx, cy) = (w / 2.0, h / 2.0);
    let (c, s) = (0.3f64.cos(), 0.3f64.sin());
    SyntheticMask::from_fn("raft", width, height, |x, y| {
        let (u, v) = (c * (x - cx) + s * (y - cy), -s * (x - cx) + c * (y - cy));
        let body = u.abs() < 0.33 * w && v.abs() < 0.28 * h;
        let notch = u > 0.1 * w && v.abs() < 0.05 * h;
        body && !notch
    })
}

/// A seven-frond star, palm-like (577×586): strongly non-convex, star-shaped.
pub fn palm(width: usize, height: usize) -> SyntheticMask {
    let (cx, cy) = (width as f64 / 2.0, height as f64 / 2.0);
    let radius = 0.45 * width.min(height) as f64;
    SyntheticMask::from_fn("palm", width, height, |x, y| {
        let (dx, dy) = (x - cx, y - cy);
        let theta = dy.atan2(dx);
        dx.hypot(dy) < radius * (0.45 + 0.55 * (3.5 * theta).cos().abs().powf(0.7))
    })
}

/// A sinusoidal band, snake-like (470×280).
pub fn snake(width: usize, height: usize) -> SyntheticMask {
    let (w, h) = (width as f64, height as f64);
    SyntheticMask::from_fn("snake", width, height, |x, y| {
        let centre = h / 2.0 + 0.25 * h * (TAU * x / (0.5 * w)).sin();
        (0.06 * w..0.94 * w).contains(&x) && (y - centre).abs() < 0.09 * h
    })
}

/// The synthetic Table-I models at the paper's image sizes (horse excluded, see module doc).
pub fn paper_masks() -> Vec<SyntheticMask> {
    vec![
        mouth(121, 85),
        raft(342, 353),
        spiral(770, 743),
        palm(577, 586),
        snake(470, 280),
    ]
}
