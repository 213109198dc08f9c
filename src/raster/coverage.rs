//! Anti-aliased silhouette coverage: takes the placed patch and gives tiny-skia masks over
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
//!
//! Large work rectangles are covered by up to four horizontal strips, one mask each. Each
//! strip's path is clipped ([`clip`](super::clip)) to one pixel beyond the strip, so it lies
//! inside the strip's mask and tiny-skia's own clipping (whose rounding would depend on the
//! grow-only mask's size, so on earlier frames) never runs.

use glam::DVec2;
use tiny_skia::{FillRule, Mask, PathBuilder, Transform};

use super::clip::{clip_polygon, ClipRect};
use super::folds::{wound, FoldOutline};
use super::{Patch, PixelRect};

/// Work rectangles are covered by one horizontal strip per this many pixels (at most
/// [`MAX_STRIPS`]). Where a strip is cut can move coverage in the last bits near the cut,
/// so the rule depends on the rectangle alone and never changes with anything else.
pub(crate) const SPLIT_AREA: usize = 64 * 1024;

/// Strips of the largest work rectangles.
const MAX_STRIPS: usize = 4;

/// Pixels of mask around a strip: its path is clipped one pixel outside the strip, and
/// tiny-skia's conservative path bounds add about half a pixel more.
const BORDER: i32 = 2;

/// The silhouette coverage of one draw, as one to [`MAX_STRIPS`] horizontal strips of the
/// work rectangle, each with its own mask. Grow-only storage, kept in the raster scratch.
#[derive(Default)]
pub(crate) struct Silhouette {
    strips: Vec<Strip>,
    count: usize,
}

/// One strip: canvas pixels `rect`, the mask holding them `BORDER` px in from its corner.
#[derive(Default)]
pub(crate) struct Strip {
    rect: PixelRect,
    mask: Option<Mask>,
    builder: Option<PathBuilder>,
    clipped: Vec<DVec2>,
    spare: Vec<DVec2>,
}

/// What every strip's fill reads.
#[derive(Clone, Copy)]
pub(crate) struct SilhouetteInput<'a> {
    pub patch: &'a Patch<'a>,
    /// Sign of the loops' rest area (see [`rest_loop_orientation`]).
    pub loop_orientation: f64,
    /// The outline of the inverted triangles, built for this `loop_orientation` (unread
    /// when it is 0).
    pub folds: &'a FoldOutline,
}

impl Silhouette {
    /// Lays out the strips of `work` (one per [`SPLIT_AREA`] pixels, 1 to [`MAX_STRIPS`]).
    /// The strips are filled by [`Strip::fill`].
    pub fn layout(&mut self, work: PixelRect) -> &mut [Strip] {
        let height = work.height();
        self.count = (work.area() / SPLIT_AREA)
            .clamp(1, MAX_STRIPS)
            .min(height.max(1));
        if self.strips.len() < self.count {
            self.strips.resize_with(self.count, Strip::default);
        }
        for (k, strip) in self.strips[..self.count].iter_mut().enumerate() {
            let row = |k: usize| work.y0 + (height * k / self.count) as i32;
            strip.rect = PixelRect {
                y0: row(k),
                y1: row(k + 1),
                ..work
            };
        }
        &mut self.strips[..self.count]
    }

    /// The strips of the last layout, top first.
    pub fn strips(&self) -> &[Strip] {
        &self.strips[..self.count]
    }

    /// The coverage row of canvas row `y` over columns `[x0, x1)` (inside the work
    /// rectangle of the last layout).
    pub fn row(&self, y: i32, x0: i32, x1: i32) -> &[u8] {
        let strip = self
            .strips()
            .iter()
            .find(|s| y < s.rect.y1)
            .unwrap_or(&self.strips[self.count - 1]);
        let (data, stride, origin) = strip.coverage();
        let start = (y - origin.1) as usize * stride + (x0 - origin.0) as usize;
        &data[start..start + (x1 - x0) as usize]
    }
}

impl Strip {
    /// The canvas pixels this strip covers.
    pub fn rect(&self) -> PixelRect {
        self.rect
    }

    /// The mask's bytes, row stride and the canvas pixel of byte 0.
    pub fn coverage(&self) -> (&[u8], usize, (i32, i32)) {
        // invariant: a strip is filled (which creates its mask) before anyone reads it.
        let mask = self.mask.as_ref().expect("strip filled before use");
        let origin = (self.rect.x0 - BORDER, self.rect.y0 - BORDER);
        (mask.data(), mask.width() as usize, origin)
    }

    /// Fills the strip's mask with the coverage of the patch's silhouette over its rows.
    pub fn fill(&mut self, input: SilhouetteInput) {
        let (patch, loop_orientation) = (input.patch, input.loop_orientation);
        let rect = self.rect;
        let mask = ensure_mask(
            &mut self.mask,
            rect.width() as u32 + 2 * BORDER as u32,
            rect.height() as u32 + 2 * BORDER as u32,
        );
        let stride = mask.width() as usize;
        let rows = rect.height() + 2 * BORDER as usize;
        for row in mask.data_mut().chunks_mut(stride).take(rows) {
            row[..rect.width() + 2 * BORDER as usize].fill(0);
        }
        let mut path = PolygonSink {
            builder: self.builder.take().unwrap_or_default(),
            clip: ClipRect {
                x0: f64::from(rect.x0) - 1.0,
                y0: f64::from(rect.y0) - 1.0,
                x1: f64::from(rect.x1) + 1.0,
                y1: f64::from(rect.y1) + 1.0,
            },
            origin: DVec2::new(f64::from(rect.x0 - BORDER), f64::from(rect.y0 - BORDER)),
            clipped: &mut self.clipped,
            spare: &mut self.spare,
        };
        path.builder.clear();
        let placed = |v: &u32| patch.placed[*v as usize];
        if loop_orientation == 0.0 {
            for tri in patch.triangles {
                let area2 = signed_area2(patch, tri);
                if area2 != 0.0 {
                    path.push(wound(tri, area2 > 0.0).iter().map(placed));
                }
            }
        } else {
            for l in patch.loops {
                path.push(l.vertices.iter().map(placed));
            }
            for contour in input.folds.contours() {
                for _ in 0..2 {
                    path.push(contour.iter().map(placed));
                }
            }
        }
        self.builder = Some(match path.builder.finish() {
            Some(path) => {
                mask.fill_path(&path, FillRule::Winding, true, Transform::identity());
                path.clear()
            }
            None => PathBuilder::new(),
        });
    }
}

/// Placed polygons into a path, clipped to the strip and moved to mask coordinates.
struct PolygonSink<'a> {
    builder: PathBuilder,
    clip: ClipRect,
    origin: DVec2,
    clipped: &'a mut Vec<DVec2>,
    spare: &'a mut Vec<DVec2>,
}

impl PolygonSink<'_> {
    fn push(&mut self, points: impl Iterator<Item = DVec2>) {
        clip_polygon(points, &self.clip, self.clipped, self.spare);
        let origin = self.origin;
        let local = |p: &DVec2| ((p.x - origin.x) as f32, (p.y - origin.y) as f32);
        push_polygon(&mut self.builder, self.clipped.iter().map(local));
    }
}

/// The placed triangle's signed area ×2 (negative: inverted), as the triangle setup has it.
fn signed_area2(patch: &Patch, tri: &[u32; 3]) -> f64 {
    let [a, b, c] = tri.map(|v| patch.placed[v as usize]);
    (b - a).perp_dot(c - a)
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
pub(crate) fn rest_loop_orientation(patch: &Patch) -> f64 {
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

fn ensure_mask(slot: &mut Option<Mask>, width: u32, height: u32) -> &mut Mask {
    let fits = slot
        .as_ref()
        .is_some_and(|m| m.width() >= width && m.height() >= height);
    if !fits {
        let (old_w, old_h) = slot.as_ref().map_or((0, 0), |m| (m.width(), m.height()));
        let mask = Mask::new(width.max(old_w), height.max(old_h));
        // invariant: both sizes include the border
        *slot = Some(mask.expect("non-empty"));
    }
    // invariant: set just above when missing.
    slot.as_mut().expect("mask present")
}
