//! The per-frame work before the pixels: takes a placed patch with its membrane and the
//! work rectangle, and fills the raster scratch's per-triangle setups and (anti-aliased)
//! silhouette strips: two independent halves, which a threaded draw runs side by side.

use super::coverage::{rest_loop_orientation, Silhouette, SilhouetteInput};
use super::folds::FoldOutline;
use super::setup::{SnappedVertex, TriangleSetup};
use super::{Patch, PixelRect, RasterScratch};

/// Fills `scratch`'s setups and, with `anti_alias`, its silhouette strips for `patch` over
/// `work`. Each setup depends on its triangle alone, and the strips are laid out by
/// [`Silhouette::layout`](super::coverage::Silhouette::layout) from `work` alone.
pub(crate) fn prepare(
    patch: &Patch,
    work: PixelRect,
    anti_alias: bool,
    scratch: &mut RasterScratch,
) {
    prepare_setups(patch, &mut scratch.snapped, &mut scratch.setups);
    if anti_alias {
        prepare_silhouette(patch, work, &mut scratch.folds, &mut scratch.silhouette);
    }
}

/// Fills `setups` (one per triangle of `patch`), snapping the placed vertices into `snapped`.
pub(crate) fn prepare_setups(
    patch: &Patch,
    snapped: &mut Vec<SnappedVertex>,
    setups: &mut Vec<TriangleSetup>,
) {
    snapped.clear();
    snapped.extend(patch.placed.iter().map(|&p| SnappedVertex::new(p)));
    setups.clear();
    setups.extend(patch.triangles.iter().map(|tri| {
        let [a, b, c] = tri.map(|v| v as usize);
        TriangleSetup::from_snapped(
            [patch.placed[a], patch.placed[b], patch.placed[c]],
            [snapped[a], snapped[b], snapped[c]],
            [patch.rest[a], patch.rest[b], patch.rest[c]],
            [patch.membrane[a], patch.membrane[b], patch.membrane[c]],
            patch.depth.map_or([0.0; 3], |d| [d[a], d[b], d[c]]),
        )
    }));
}

/// Fills the anti-aliased silhouette's strips over `work` (and the fold outline they read).
pub(crate) fn prepare_silhouette(
    patch: &Patch,
    work: PixelRect,
    folds: &mut FoldOutline,
    silhouette: &mut Silhouette,
) {
    let loop_orientation = rest_loop_orientation(patch);
    match loop_orientation != 0.0 {
        true => folds.build(patch, loop_orientation),
        false => folds.clear(),
    }
    let input = SilhouetteInput {
        patch,
        loop_orientation,
        folds,
    };
    for strip in silhouette.layout(work) {
        strip.fill(input);
    }
}
