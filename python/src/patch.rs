//! One patch, meshed and factored once: takes a source and a mask array, and for each clone a
//! target array, a placement and optional drags and pins; gives the composited array. The
//! target is read and the result written only over the pixels the clone can touch (the
//! placed patch's bounding box and a margin), so a frame costs its patch, not its size; the
//! mesh, factor and solve run with the GIL released.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

use lapclone::glam::DVec2;
use lapclone::{
    mesh_from_mask, BitMask, Canvas, CloneOptions, DeformRig, Deformed, Handle, MeshOptions,
    PatchCloner, PatchMesh, Pin, Placement,
};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use crate::arrays::{self, Layout, Picture, Rect};
use crate::errors::{clone_error, to_py};

/// The mask threshold of `lapclone clone` (`--threshold` default): inside where the mask's
/// luma (or alpha, if it has one) is at least half scale.
pub const MASK_THRESHOLD: f32 = 0.5;

/// How a clone is placed and deformed (source coordinates for drags and pins).
pub struct Pose {
    pub placement: Placement,
    pub handles: Vec<Handle>,
    pub pins: Vec<Pin>,
}

/// What stays between clones: the cloner (mesh and factor), the deformation rig once a
/// drag or pin asks for it, and the canvas frames are composited on.
pub struct PatchState {
    cloner: PatchCloner,
    laplacian: lapclone::LaplacianKind,
    rig: Option<DeformRig>,
    deformed: Deformed,
    /// Whether the prepared clone is deformed (and so depth-ordered).
    deformed_now: bool,
    canvas: Option<Canvas>,
}

/// A patch behind a lock: clones of one patch from several Python threads take turns, and
/// the lock is only ever waited for with the GIL released.
pub struct Patch {
    state: Mutex<PatchState>,
    /// The thread holding `state` ([`thread_number`]; 0: none).
    holder: AtomicU64,
    /// The patch mesh's bounding box of inside mask pixels and its default drag radius.
    pub bbox_min: DVec2,
    pub bbox_max: DVec2,
    pub drag_radius: f64,
    pub vertex_count: usize,
    pub triangle_count: usize,
}

impl Patch {
    /// Meshes the mask and factors the patch's Laplacian (GIL released), as `lapclone clone`
    /// does for the same images and options.
    pub fn new(
        py: Python<'_>,
        source: Picture,
        mask: Picture,
        mesh_options: &MeshOptions,
        options: &CloneOptions,
        threads: Option<usize>,
    ) -> PyResult<Patch> {
        let (state, patch) = py.allow_threads(|| -> PyResult<_> {
            let bits = BitMask::from_image(&mask.image, MASK_THRESHOLD);
            let size = (source.image.width(), source.image.height());
            let patch: PatchMesh =
                mesh_from_mask(&bits, None, size, mesh_options).map_err(clone_error)?;
            let source = lapclone::FloatImage::from_dynamic(&source.image).map_err(to_py)?;
            let bbox = (patch.bbox_min, patch.bbox_max, patch.default_drag_radius());
            let triangles = patch.result.mesh.triangles.len();
            let mut cloner =
                PatchCloner::new(source, patch.result.mesh, options).map_err(clone_error)?;
            // Unless told otherwise every core, as `lapclone clone` uses (the pixels are the same
            // for any count); looked up once per process, since the look-up reads cgroup files.
            cloner.set_raster_threads(threads.unwrap_or_else(lapclone::available_cores));
            let state = PatchState {
                cloner,
                laplacian: options.laplacian,
                rig: None,
                deformed: Deformed::default(),
                deformed_now: false,
                canvas: None,
            };
            Ok((state, (bbox, triangles)))
        })?;
        let ((bbox_min, bbox_max, drag_radius), triangle_count) = patch;
        let vertex_count = state.cloner.mesh().vertex_count();
        Ok(Patch {
            state: Mutex::new(state),
            holder: AtomicU64::new(0),
            bbox_min,
            bbox_max,
            drag_radius,
            vertex_count,
            triangle_count,
        })
    }

    /// Clones onto `target` (an image array of `layout`): into `out` when given (after
    /// copying the target there), else into a new array. Returns the result array.
    pub fn clone_onto<'py>(
        &self,
        target: &Bound<'py, PyAny>,
        layout: &Layout,
        bgr: bool,
        pose: &Pose,
        out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let py = target.py();
        let shared: Py<PyAny> = target.clone().unbind();
        let out: Option<Py<PyAny>> = out.map(|out| out.clone().unbind());
        let result = py.allow_threads(|| {
            // Waited for without the GIL, so a thread holding the lock can always take it.
            let mut state = self.lock()?;
            let rect = state.prepare(pose, layout)?;
            // Each time the GIL is taken back the arrays are checked again: other threads ran
            // meanwhile. No code but numpy's runs while the lock is held, so a clone called
            // from inside that code cannot wait for this one.
            Python::with_gil(|py| {
                let target = shared.bind(py);
                arrays::check_unchanged(target, layout, "target")?;
                state.load_target(target, layout, bgr, rect)
            })?;
            state.draw()?;
            // The result from the drawn canvas directly (no copy of the rectangle between).
            Python::with_gil(|py| {
                let target = shared.bind(py);
                arrays::check_unchanged(target, layout, "target")?;
                let result = match &out {
                    Some(out) => {
                        let out = out.bind(py);
                        arrays::check_out(out, layout)?;
                        arrays::copy_into(target, out, layout)?;
                        out.clone()
                    }
                    None => arrays::plain_copy(target)?,
                };
                // invariant: `load_target` left a canvas.
                let canvas = state.canvas.as_ref().expect("loaded before drawing");
                arrays::write_canvas_rect(&result, layout, bgr, canvas, rect)?;
                Ok::<_, PyErr>(result.unbind())
            })
        })?;
        Ok(result.into_bound(py))
    }
}

impl Patch {
    /// The state, also after a panic on another thread (every clone starts by resetting
    /// what it uses, so a half-done one leaves nothing wrong behind). A clone called on the
    /// thread already holding it is refused: Python code can run inside a clone (garbage
    /// collection calling a finaliser while numpy allocates the result), and waiting there
    /// would wait for itself.
    fn lock(&self) -> PyResult<StateGuard<'_>> {
        let me = thread_number();
        if self.holder.load(Ordering::Relaxed) == me {
            return Err(PyRuntimeError::new_err(
                "this Cloner is already cloning on this thread: a clone was called from inside \
                 another (a finaliser run by garbage collection?); give that code its own Cloner",
            ));
        }
        let state = self
            .state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        self.holder.store(me, Ordering::Relaxed);
        Ok(StateGuard {
            state,
            holder: &self.holder,
        })
    }
}

/// The locked state; clears the holder when dropped.
struct StateGuard<'a> {
    state: MutexGuard<'a, PatchState>,
    holder: &'a AtomicU64,
}

impl Drop for StateGuard<'_> {
    fn drop(&mut self) {
        self.holder.store(0, Ordering::Relaxed);
    }
}

impl std::ops::Deref for StateGuard<'_> {
    type Target = PatchState;
    fn deref(&self) -> &PatchState {
        &self.state
    }
}

impl std::ops::DerefMut for StateGuard<'_> {
    fn deref_mut(&mut self) -> &mut PatchState {
        &mut self.state
    }
}

/// This thread's number, from 1: the same for the thread's life, never another's.
fn thread_number() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    thread_local! {
        static NUMBER: u64 = NEXT.fetch_add(1, Ordering::Relaxed);
    }
    NUMBER.with(|n| *n)
}

impl PatchState {
    /// Places (and deforms) the patch and gives the target pixels the clone can read or
    /// write: the placed vertices' bounding box grown by two pixels (the raster's
    /// anti-aliasing band and the boundary's bilinear taps lie within one), clipped.
    fn prepare(&mut self, pose: &Pose, layout: &Layout) -> PyResult<Rect> {
        self.deformed_now = !(pose.handles.is_empty() && pose.pins.is_empty());
        if !self.deformed_now {
            self.cloner.prepare_rigid(&pose.placement).map_err(to_py)?;
        } else {
            let rig = match &mut self.rig {
                Some(rig) => rig,
                slot => {
                    slot.insert(DeformRig::new(self.cloner.mesh(), self.laplacian).map_err(to_py)?)
                }
            };
            rig.deform(&pose.handles, &pose.pins, &mut self.deformed)
                .map_err(to_py)?;
            let d = &self.deformed;
            self.cloner
                .prepare_deformed(&pose.placement, &d.positions, Some(&d.depth))
                .map_err(to_py)?;
        }
        Ok(touched_rect(self.cloner.placed(), layout))
    }

    /// Copies the target's `rect` into the canvas (a new canvas of the target's size and
    /// depth when the last one differs).
    fn load_target(
        &mut self,
        target: &Bound<'_, PyAny>,
        layout: &Layout,
        bgr: bool,
        rect: Rect,
    ) -> PyResult<()> {
        let depth = layout.format().depth;
        let fits = self.canvas.as_ref().is_some_and(|c| {
            (c.width() as usize, c.height() as usize, c.depth())
                == (layout.width, layout.height, depth)
        });
        let canvas = match &mut self.canvas {
            Some(canvas) if fits => canvas,
            slot => {
                let canvas = Canvas::new(layout.width as u32, layout.height as u32, depth);
                slot.insert(canvas.map_err(to_py)?)
            }
        };
        arrays::load_rect(target, layout, bgr, canvas, rect)
    }

    /// The membrane solve and the raster on the canvas.
    fn draw(&mut self) -> PyResult<()> {
        // invariant: the clone calls `load_target`, which leaves a canvas, before every `draw`.
        let canvas = self.canvas.as_mut().expect("loaded before drawing");
        let depth = self.deformed_now.then_some(&self.deformed.depth[..]);
        self.cloner.clone_prepared(canvas, depth).map_err(to_py)?;
        Ok(())
    }
}

fn touched_rect(placed: &[DVec2], layout: &Layout) -> Rect {
    let mut min = DVec2::splat(f64::INFINITY);
    let mut max = DVec2::splat(f64::NEG_INFINITY);
    for &p in placed {
        min = min.min(p);
        max = max.max(p);
    }
    let (w, h) = (layout.width as f64, layout.height as f64);
    if !(min.x <= max.x && min.y <= max.y) {
        return Rect {
            x0: 0,
            y0: 0,
            x1: 0,
            y1: 0,
        };
    }
    let clip = |v: f64, limit: f64| v.clamp(0.0, limit) as u32;
    let rect = Rect {
        x0: clip(min.x.floor() - 2.0, w),
        y0: clip(min.y.floor() - 2.0, h),
        x1: clip(max.x.ceil() + 2.0, w),
        y1: clip(max.y.ceil() + 2.0, h),
    };
    if rect.x0 >= rect.x1 || rect.y0 >= rect.y1 {
        return Rect {
            x0: 0,
            y0: 0,
            x1: 0,
            y1: 0,
        };
    }
    rect
}
