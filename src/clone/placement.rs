//! Placement of a patch in the target: a 2D similarity (uniform scale, rotation,
//! translation) from rest (source-image) coordinates to target pixels. Takes the pivot, the
//! target position of the pivot, a scale and an angle; gives the map and its inverse.

use glam::{DAffine2, DVec2};

/// Where a patch goes: the rest point `pivot` lands on `at`, the patch scaled by `scale` and
/// rotated by `rotation_deg` (positive turns x towards y, i.e. clockwise on screen because y
/// points down) around the pivot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Rest (source) point the placement is anchored at.
    pub pivot: DVec2,
    /// Where `pivot` lands in the target, pixels.
    pub at: DVec2,
    /// Uniform scale about the pivot (> 0).
    pub scale: f64,
    /// Rotation about the pivot, degrees (clockwise on screen).
    pub rotation_deg: f64,
}

impl Placement {
    /// The identity placement: every rest point stays where it is.
    pub fn identity() -> Self {
        Self {
            pivot: DVec2::ZERO,
            at: DVec2::ZERO,
            scale: 1.0,
            rotation_deg: 0.0,
        }
    }

    /// A pure translation moving the rest point `pivot` to `at`.
    pub fn translate(pivot: DVec2, at: DVec2) -> Self {
        Self {
            pivot,
            at,
            scale: 1.0,
            rotation_deg: 0.0,
        }
    }

    /// OpenCV's `seamlessClone` placement of a patch whose mask's inside pixels span
    /// `bbox_min`..`bbox_max` (pixel corners, whole numbers): the box's centre goes to the
    /// target pixel `p` as OpenCV puts it, its top-left pixel landing on
    /// `p − (⌊w / 2⌋, ⌊h / 2⌋)`. The patch moves by whole pixels, so it is never resampled.
    pub fn centred_on_pixel(bbox_min: DVec2, bbox_max: DVec2, p: [i64; 2]) -> Self {
        let half = ((bbox_max - bbox_min) / 2.0).floor();
        Self::translate(bbox_min, DVec2::new(p[0] as f64, p[1] as f64) - half)
    }

    /// The rest → target map.
    pub fn to_affine(&self) -> DAffine2 {
        DAffine2::from_translation(self.at)
            * DAffine2::from_scale_angle_translation(
                DVec2::splat(self.scale),
                self.rotation_deg.to_radians(),
                DVec2::ZERO,
            )
            * DAffine2::from_translation(-self.pivot)
    }

    /// Maps every rest point into `out` (resized to fit; reused across frames), on the grid
    /// of `PLACED_GRID` (2⁻¹⁶ px): `on_grid(map′(p)) + ⌊at⌋`, where `map′` places the pivot at
    /// `at − ⌊at⌋`.
    ///
    /// Why: moving `at` by whole pixels then moves every placed point by exactly that many
    /// pixels (the grid's sums are exact), so the raster's per-triangle maps, which depend
    /// only on differences of placed points, come out bit for bit the same and a whole-pixel
    /// drag moves the drawn patch without resampling it differently. With the plain affine
    /// map the sums would round differently at each position. The grid moves a point by at
    /// most 2⁻¹⁷ px.
    pub fn apply(&self, rest: &[DVec2], out: &mut Vec<DVec2>) {
        let whole = self.at.floor();
        let map = Placement {
            at: self.at - whole, // exact: the fractional part
            ..*self
        }
        .to_affine();
        out.clear();
        out.extend(
            rest.iter()
                .map(|&p| on_placed_grid(map.transform_point2(p)) + whole),
        );
    }

    /// Whether every number is finite and the scale positive.
    pub fn is_finite(&self) -> bool {
        self.pivot.is_finite()
            && self.at.is_finite()
            && self.scale.is_finite()
            && self.rotation_deg.is_finite()
    }
}

/// Placed points are multiples of this (px); see [`Placement::apply`]. Sums of such points
/// and whole pixels are exact below 2³⁶ px, far beyond any canvas.
pub const PLACED_GRID: f64 = 1.0 / 65536.0;

/// The nearest point of the [`PLACED_GRID`] (NaN stays NaN).
fn on_placed_grid(p: DVec2) -> DVec2 {
    (p / PLACED_GRID).round() * PLACED_GRID
}

/// Which rest point `--at` / a placement's position refers to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Anchor {
    /// The centre of the mask's bounding box (of its inside pixels).
    #[default]
    Centre,
    /// The top-left corner of the mask's bounding box.
    TopLeft,
}

impl Anchor {
    /// The anchor point of a bounding box given by its corners `min` and `max`.
    pub fn point(self, min: DVec2, max: DVec2) -> DVec2 {
        match self {
            Anchor::Centre => (min + max) * 0.5,
            Anchor::TopLeft => min,
        }
    }
}
