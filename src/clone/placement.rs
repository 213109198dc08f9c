//! Placement of a patch in the target: a 2D similarity (uniform scale, rotation,
//! translation) from rest (source-image) coordinates to target pixels. Takes the pivot, the
//! target position of the pivot, a scale and an angle; gives the map and its inverse.

use glam::{DAffine2, DVec2};

/// Where a patch goes: the rest point `pivot` lands on `at`, the patch scaled by `scale` and
/// rotated by `rotation_deg` (positive turns x towards y, i.e. clockwise on screen because y
/// points down) around the pivot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub pivot: DVec2,
    pub at: DVec2,
    pub scale: f64,
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

    /// Maps every rest point into `out` (resized to fit; reused across frames).
    pub fn apply(&self, rest: &[DVec2], out: &mut Vec<DVec2>) {
        let map = self.to_affine();
        out.clear();
        out.extend(rest.iter().map(|&p| map.transform_point2(p)));
    }

    pub fn is_finite(&self) -> bool {
        self.pivot.is_finite()
            && self.at.is_finite()
            && self.scale.is_finite()
            && self.rotation_deg.is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
