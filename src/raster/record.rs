//! A recording draw in two halves: takes a patch whose membrane is still to be solved and
//! gives the same bytes as a fresh draw, plus the record that later whole-pixel moves replay
//! (see [`replay`](super::replay)).
//!
//! The record (pixel runs, source samples, coverage) does not depend on the membrane, so a
//! helper thread makes it — preparation, rasterising, source sampling, writing nothing —
//! while this thread solves. The canvas is then composited from the record with the
//! membrane, which is exactly what a replay by (0, 0) does. A patch's first draw is the
//! recording one, and its solve is the first, which factors the Laplacian
//! (`MembraneSolver::deferred`): the factor and the record overlap.

use super::draw::{draw_frame, replay, worker_threads, Frame, RasterOptions, RasterStats};
use super::helper;
use super::prepare::prepare;
use super::shade::StoreTexel;
use super::shade_simd::Kernel;
use super::{Patch, PixelRect, RasterError, RasterScratch};
use crate::pixels::{Canvas, Texel};

/// Records the draw of `patch` over `work` (inside the canvas, unclipped) on a helper thread
/// while `solve` runs on this one, then composites the record with the membrane.
pub(super) fn record_and_composite<'m, E: From<RasterError>>(
    canvas: &mut Canvas,
    patch: &Patch,
    options: &RasterOptions,
    work: PixelRect,
    scratch: &mut RasterScratch,
    solve: impl FnOnce(&Canvas) -> Result<&'m [[f32; 3]], E>,
) -> Result<RasterStats, E> {
    let mut zeros = std::mem::take(&mut scratch.zero_membrane);
    zeros.clear();
    zeros.resize(patch.placed.len(), [0.0; 3]);
    let (canvas_width, canvas_height) = (canvas.width() as usize, canvas.height() as usize);
    let mut record = || {
        let sizes = (canvas_width, canvas_height);
        record_only(patch, work, options, scratch, &zeros, sizes)
    };
    // Overlapping needs a second core, not a large patch: the solve may factor.
    let overlap = worker_threads(options.threads, usize::MAX, 2) >= 2;
    let (recorded, membrane) = if overlap {
        let shared: &Canvas = canvas;
        helper::join(record, || solve(shared))
    } else {
        let membrane = solve(canvas);
        let recorded = match membrane {
            Ok(_) => record(),
            Err(_) => Ok(()),
        };
        (recorded, membrane)
    };
    scratch.zero_membrane = zeros;
    let membrane = membrane?;
    recorded?;
    let stats = replay(canvas, patch, options, work, (0, 0), scratch, |_| {
        Ok::<_, E>(membrane)
    })?;
    Ok(RasterStats {
        replayed: false,
        ..stats
    })
}

/// Prepares and rasterises `patch` with a zero membrane on this thread, recording the runs,
/// samples and coverage into the scratch's record; writes no pixel.
fn record_only(
    patch: &Patch,
    work: PixelRect,
    options: &RasterOptions,
    scratch: &mut RasterScratch,
    zeros: &[[f32; 3]],
    (canvas_width, canvas_height): (usize, usize),
) -> Result<(), RasterError> {
    let membrane = prepare(patch, work, options.anti_alias, 1, scratch, || {
        Ok::<_, RasterError>(zeros)
    })?;
    let patch = &Patch { membrane, ..*patch };
    let frame = Frame {
        patch,
        work,
        target: work,
        anti_alias: options.anti_alias,
        threads: 1,
        use_depth: false,
        kernel: if options.simd {
            Kernel::detect()
        } else {
            Kernel::Scalar
        },
    };
    let mut replay = std::mem::take(&mut scratch.replay);
    let mut recording = replay.start(patch, options.anti_alias, work);
    // Zero-sized texels: a canvas-shaped slice that stores nothing and allocates nothing.
    let mut nowhere = vec![[Discard; 4]; canvas_width * canvas_height];
    draw_frame(
        &frame,
        options,
        scratch,
        &mut nowhere,
        canvas_width,
        &mut recording,
    );
    scratch.replay = replay;
    Ok(())
}

/// A canvas texel that keeps nothing: shading into it only samples the source (which the
/// recorder keeps).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Discard;

impl Texel for Discard {
    #[inline(always)]
    fn to_unit(self) -> f32 {
        0.0
    }

    #[inline(always)]
    fn from_unit(_: f32) -> Self {
        Discard
    }
}

impl StoreTexel for Discard {
    #[inline(always)]
    fn store_unit(_: glam::Vec4) -> [Self; 4] {
        [Discard; 4]
    }

    #[inline(always)]
    fn as_rgba8(_: &mut [[Self; 4]]) -> Option<&mut [[u8; 4]]> {
        None
    }
}
