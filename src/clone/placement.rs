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

#[cfg(test)]
mod tests {
    use super::*;

    /// OpenCV's placement: the box's top-left pixel lands on p − (⌊w/2⌋, ⌊h/2⌋), for even and
    /// odd sides and negative targets, by a whole-pixel shift.
    #[test]
    fn centred_on_pixel_puts_the_top_left_pixel_where_opencv_does() {
        for (min, max, p, top_left) in [
            ((95.0, 40.0), (331.0, 261.0), [288, 143], (170.0, 33.0)),
            ((10.0, 21.0), (101.0, 80.0), [150, 100], (105.0, 71.0)),
            ((0.0, 0.0), (1.0, 1.0), [-7, 3], (-7.0, 3.0)),
        ] {
            let (min, max) = (DVec2::from(min), DVec2::from(max));
            let placement = Placement::centred_on_pixel(min, max, p);
            let mut placed = Vec::new();
            placement.apply(&[min, max], &mut placed);
            assert_eq!(placed[0], DVec2::from(top_left));
            assert_eq!(placed[1] - placed[0], max - min);
        }
    }

    #[test]
    fn pivot_lands_on_target_position() {
        let placement = Placement {
            pivot: DVec2::new(10.0, 20.0),
            at: DVec2::new(100.0, 50.0),
            scale: 2.5,
            rotation_deg: 33.0,
        };
        let moved = placement.to_affine().transform_point2(placement.pivot);
        assert!((moved - placement.at).length() < 1e-12);
    }

    #[test]
    fn scale_and_rotation_act_around_the_pivot() {
        let placement = Placement {
            pivot: DVec2::new(10.0, 10.0),
            at: DVec2::new(0.0, 0.0),
            scale: 2.0,
            rotation_deg: 90.0,
        };
        let moved = placement
            .to_affine()
            .transform_point2(DVec2::new(11.0, 10.0));
        // (1, 0) from the pivot, scaled by 2 and turned by 90° towards +y.
        assert!((moved - DVec2::new(0.0, 2.0)).length() < 1e-12);
    }

    #[test]
    fn applied_points_are_the_affine_map_on_the_grid() {
        let placement = Placement {
            pivot: DVec2::new(10.3, 7.77),
            at: DVec2::new(401.123_456_7, -52.987_654_3),
            scale: 1.37,
            rotation_deg: 21.5,
        };
        let rest: Vec<DVec2> = (0..500)
            .map(|k| DVec2::new(k as f64 * 0.713_13, (k * k % 97) as f64 * 0.331_7))
            .collect();
        let mut placed = Vec::new();
        placement.apply(&rest, &mut placed);
        let map = placement.to_affine();
        for (p, q) in rest.iter().zip(&placed) {
            assert!(
                (map.transform_point2(*p) - *q).abs().max_element() <= 0.5 * PLACED_GRID + 1e-9
            );
            assert_eq!(
                *q,
                (*q / PLACED_GRID).round() * PLACED_GRID,
                "{q} off the grid"
            );
        }
    }

    #[test]
    fn whole_pixel_moves_shift_every_placed_point_exactly() {
        // Arbitrary fractional positions and a rotation: the plain affine map rounds its sums
        // differently after a move, the grid does not.
        let base = Placement {
            pivot: DVec2::new(123.456_789, 98.765_432_1),
            at: DVec2::new(500.318_7, 436.902_1),
            scale: 0.913,
            rotation_deg: -12.25,
        };
        let rest: Vec<DVec2> = (0..2000)
            .map(|k| {
                DVec2::new(
                    (k as f64).sqrt() * 13.131_7,
                    (k as f64 * 0.618_034).fract() * 301.7,
                )
            })
            .collect();
        let (mut before, mut after) = (Vec::new(), Vec::new());
        base.apply(&rest, &mut before);
        for shift in [
            DVec2::new(3.0, 2.0),
            DVec2::new(-117.0, 45.0),
            DVec2::new(0.0, -1.0),
        ] {
            let moved = Placement {
                at: base.at + shift,
                ..base
            };
            moved.apply(&rest, &mut after);
            let exact = before
                .iter()
                .zip(&after)
                .filter(|(b, a)| **b + shift == **a)
                .count();
            assert_eq!(exact, rest.len(), "shift {shift}");
        }
    }
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
