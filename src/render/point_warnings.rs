//! Points a scene names on a patch that miss it: takes the renderer's rest meshes and the
//! scene's pins and drags, and gives a warning for each pin or drag grab point lying outside
//! its patch. Both act on the mesh vertex nearest to them, so a pin outside holds a point
//! the user did not name, and a drag grabbing far outside pulls a thin spike out of the
//! patch.

use glam::DVec2;

use super::Renderer;
use crate::mesh::{Mesh, Segment};

/// How far outside its patch (px, source coordinates) a point may lie unremarked: the
/// mesh boundary runs along outside pixel centres, so a point on a mask's edge pixel is in.
const OUTSIDE_TOLERANCE: f64 = 2.0;

impl Renderer {
    /// One sentence per pin or drag point more than 2 px outside its patch's rest mesh.
    pub fn point_warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        for (patch, placed) in self.scene().patches.iter().zip(self.placed_meshes()) {
            let mesh = placed.mesh;
            for pin in &patch.pins {
                if let Some((distance, nearest)) = outside(mesh, pin.at) {
                    out.push(format!(
                        "patch `{}`: the pin at {} lies {distance:.1} px outside the patch; it holds the nearest mesh point, {}, instead",
                        patch.name,
                        point(pin.at),
                        point(nearest)
                    ));
                }
            }
            for handle in &patch.handles {
                if let Some((distance, nearest)) = outside(mesh, handle.from) {
                    out.push(format!(
                        "patch `{}`: the drag grabs {}, {distance:.1} px outside the patch; it pulls the nearest mesh point, {}, which can draw a thin spike out of the patch",
                        patch.name,
                        point(handle.from),
                        point(nearest)
                    ));
                }
            }
        }
        out
    }
}

fn point(p: DVec2) -> String {
    format!("[{}, {}]", round(p.x), round(p.y))
}

fn round(v: f64) -> f64 {
    (v * 10.0).round() / 10.0
}

/// `Some((distance to the mesh, nearest vertex))` when `p` lies more than the tolerance
/// outside every triangle of `mesh`.
fn outside(mesh: &Mesh, p: DVec2) -> Option<(f64, DVec2)> {
    let mut distance = f64::INFINITY;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        if contains(a, b, c, p) {
            return None;
        }
        for (s, e) in [(a, b), (b, c), (c, a)] {
            distance = distance.min(Segment::new(s, e).distance(p));
        }
    }
    if distance.is_nan() || distance <= OUTSIDE_TOLERANCE {
        return None;
    }
    let nearest = mesh
        .positions
        .iter()
        .copied()
        .min_by(|x, y| x.distance_squared(p).total_cmp(&y.distance_squared(p)))?;
    Some((distance, nearest))
}

/// Whether `p` lies in the triangle (either orientation, edges included).
fn contains(a: DVec2, b: DVec2, c: DVec2, p: DVec2) -> bool {
    let d1 = (b - a).perp_dot(p - a);
    let d2 = (c - b).perp_dot(p - b);
    let d3 = (a - c).perp_dot(p - c);
    let negative = d1 < 0.0 || d2 < 0.0 || d3 < 0.0;
    let positive = d1 > 0.0 || d2 > 0.0 || d3 > 0.0;
    !(negative && positive)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Mesh {
        Mesh {
            positions: vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(10.0, 0.0),
                DVec2::new(10.0, 10.0),
                DVec2::new(0.0, 10.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            loops: Vec::new(),
            is_boundary: vec![true; 4],
            piece: vec![0; 4],
            piece_count: 1,
        }
    }

    #[test]
    fn points_inside_or_near_pass_and_far_ones_name_the_nearest_vertex() {
        let mesh = square();
        assert_eq!(outside(&mesh, DVec2::new(5.0, 5.0)), None);
        assert_eq!(outside(&mesh, DVec2::new(11.5, 5.0)), None);
        let (distance, nearest) = outside(&mesh, DVec2::new(13.0, 14.0)).unwrap();
        assert_eq!(distance, 5.0);
        assert_eq!(nearest, DVec2::new(10.0, 10.0));
        let (distance, _) = outside(&mesh, DVec2::new(-3.0, 5.0)).unwrap();
        assert_eq!(distance, 3.0);
    }
}
