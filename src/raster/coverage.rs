//! Anti-aliased silhouette coverage: takes the placed patch and gives a tiny-skia mask over
//! the work rectangle holding the coverage of the *union* of all placed triangles, exact
//! inside and anti-aliased only at the union's outline.
//!
//! Rule under self-overlap: the winding number of the placed boundary loops at a point is
//! (#non-inverted − #inverted) triangles covering it, so overlaps of same-orientation layers
//! are already non-zero but a fold (an inverted flap over a normal layer) can cancel to 0.
//! Adding every inverted triangle twice, wound like a non-inverted one, turns the winding into
//! the plain count of covering triangles: the non-zero fill of that path is exactly the union.
//! Folds are rare, so the path stays about the size of the boundary. Without loops, every
//! triangle goes into the path (same union, slower).

use tiny_skia::{FillRule, Mask, PathBuilder, Transform};

use super::setup::TriangleSetup;
use super::{Patch, PixelRect};

/// Fills `mask` (grown to at least the work size, cleared over it) with the silhouette
/// coverage. Returns the mask row stride in pixels.
pub(crate) fn fill_silhouette(
    patch: &Patch,
    setups: &[TriangleSetup],
    work: PixelRect,
    builder_slot: &mut Option<PathBuilder>,
    mask_slot: &mut Option<Mask>,
) -> usize {
    let mask = ensure_mask(mask_slot, work);
    let stride = mask.width() as usize;
    for row in mask.data_mut().chunks_mut(stride).take(work.height()) {
        row[..work.width()].fill(0);
    }
    let mut builder = builder_slot.take().unwrap_or_default();
    builder.clear();
    let local = |p: glam::DVec2| {
        (
            (p.x - f64::from(work.x0)) as f32,
            (p.y - f64::from(work.y0)) as f32,
        )
    };
    let loop_orientation = rest_loop_orientation(patch);
    if loop_orientation == 0.0 {
        for (setup, tri) in setups.iter().zip(patch.triangles) {
            if setup.signed_area2 != 0.0 {
                let order = oriented(tri, setup.signed_area2 > 0.0);
                push_polygon(
                    &mut builder,
                    order.iter().map(|&v| local(patch.placed[v as usize])),
                );
            }
        }
    } else {
        for l in patch.loops {
            push_polygon(
                &mut builder,
                l.vertices.iter().map(|&v| local(patch.placed[v as usize])),
            );
        }
        for (setup, tri) in setups.iter().zip(patch.triangles) {
            if setup.signed_area2 < 0.0 {
                // Wind it like a non-inverted triangle relative to the loops' direction.
                let order = oriented(tri, loop_orientation < 0.0);
                for _ in 0..2 {
                    push_polygon(
                        &mut builder,
                        order.iter().map(|&v| local(patch.placed[v as usize])),
                    );
                }
            }
        }
    }
    match builder.finish() {
        Some(path) => {
            mask.fill_path(&path, FillRule::Winding, true, Transform::identity());
            *builder_slot = Some(path.clear());
        }
        None => *builder_slot = Some(PathBuilder::new()),
    }
    stride
}

/// `tri` as given (`keep`) or with its winding reversed.
fn oriented(tri: &[u32; 3], keep: bool) -> [u32; 3] {
    if keep {
        *tri
    } else {
        [tri[0], tri[2], tri[1]]
    }
}

fn push_polygon(builder: &mut PathBuilder, mut points: impl Iterator<Item = (f32, f32)>) {
    if let Some((x, y)) = points.next() {
        builder.move_to(x, y);
        for (x, y) in points {
            builder.line_to(x, y);
        }
        builder.close();
    }
}

/// Sign of the loops' total signed area at rest (+1: same direction as the triangles),
/// or 0 when there are no usable loops.
fn rest_loop_orientation(patch: &Patch) -> f64 {
    let mut area2 = 0.0;
    for l in patch.loops {
        let n = l.vertices.len();
        for k in 0..n {
            let p = patch.rest[l.vertices[k] as usize];
            let q = patch.rest[l.vertices[(k + 1) % n] as usize];
            area2 += p.perp_dot(q);
        }
    }
    if area2 > 0.0 {
        1.0
    } else if area2 < 0.0 {
        -1.0
    } else {
        0.0
    }
}

fn ensure_mask(slot: &mut Option<Mask>, work: PixelRect) -> &mut Mask {
    let (w, h) = (work.width() as u32, work.height() as u32);
    let fits = slot
        .as_ref()
        .is_some_and(|m| m.width() >= w && m.height() >= h);
    if !fits {
        let (old_w, old_h) = slot.as_ref().map_or((0, 0), |m| (m.width(), m.height()));
        let mask = Mask::new(w.max(old_w), h.max(old_h));
        *slot = Some(mask.expect("non-empty")); // invariant: the work rectangle is non-empty
    }
    slot.as_mut().expect("mask present") // invariant: set just above when missing.
}
