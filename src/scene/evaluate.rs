//! Timeline evaluation: takes a [`Scene`] and a time (or a frame index) and gives the
//! [`FrameState`] of every patch at that time. Pure and deterministic; frame i is evaluated
//! at t = i / fps computed from the index, never by accumulating 1/fps.

use glam::DVec2;

use super::types::{Patch, Scene};

/// One patch's evaluated placement and deformation controls at a time.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct PatchState {
    /// Canvas position of the patch's bounding-box centre; `None` keeps the source position.
    pub position: Option<DVec2>,
    /// Uniform scale.
    pub scale: f64,
    /// Degrees, clockwise on screen.
    pub rotation: f64,
    /// Depth of the whole layer (nearer is larger).
    pub depth: f64,
    /// In [0, 1]; 1 draws the clone as is, 0 leaves the layers below untouched.
    pub opacity: f64,
    /// The drag handles active at this time.
    pub handles: Vec<HandleState>,
    /// Rest points of the pins active at this time.
    pub pins: Vec<DVec2>,
}

#[derive(Clone, Copy, Debug, PartialEq, Default)]
/// One drag handle's evaluated state.
pub struct HandleState {
    /// Rest point in the source's frame.
    pub from: DVec2,
    /// Where the rest point is dragged to, in the source's frame.
    pub to: DVec2,
    /// Radius of influence in pixels.
    pub radius: f64,
    /// Depth override of the dragged region.
    pub depth: Option<f64>,
    /// Pivot override of the rotation.
    pub pivot: Option<DVec2>,
    /// Rotation override in degrees.
    pub rotation: Option<f64>,
}

#[derive(Clone, Debug, PartialEq, Default)]
/// Every patch's evaluated state at one time ([`Scene::evaluate`]).
pub struct FrameState {
    /// Seconds.
    pub time: f64,
    /// One entry per scene patch, in scene order.
    pub patches: Vec<PatchState>,
    /// Indices into `patches`, back to front: by increasing depth, ties in scene order.
    pub draw_order: Vec<usize>,
}

/// The time of frame `index` at `fps`.
pub fn frame_time(index: u64, fps: f64) -> f64 {
    index as f64 / fps
}

impl Scene {
    /// The state of every patch at time `t` (seconds).
    pub fn evaluate(&self, t: f64) -> FrameState {
        let mut state = FrameState::default();
        self.evaluate_into(t, &mut state);
        state
    }

    /// The state of frame `index` (t = index / fps).
    pub fn evaluate_frame(&self, index: u64) -> FrameState {
        self.evaluate(frame_time(index, self.canvas.fps))
    }

    /// Like [`Scene::evaluate`], reusing `state`'s buffers: no allocation once they are
    /// large enough.
    pub fn evaluate_into(&self, t: f64, state: &mut FrameState) {
        state.time = t;
        state
            .patches
            .resize_with(self.patches.len(), PatchState::default);
        for (patch, out) in self.patches.iter().zip(&mut state.patches) {
            evaluate_patch(patch, t, out);
        }
        state.draw_order.clear();
        state.draw_order.extend(0..self.patches.len());
        let depths = &state.patches;
        // Stable sort: equal depths keep scene order.
        state
            .draw_order
            .sort_by(|&a, &b| depths[a].depth.total_cmp(&depths[b].depth));
    }
}

fn evaluate_patch(patch: &Patch, t: f64, out: &mut PatchState) {
    let p = &patch.placement;
    out.position = p.position.value_at(t);
    out.scale = p.scale.value_at(t).unwrap_or(1.0);
    out.rotation = p.rotation.value_at(t).unwrap_or(0.0);
    out.depth = p.depth.value_at(t).unwrap_or(0.0);
    out.opacity = p.opacity.value_at(t).unwrap_or(1.0);
    out.handles.clear();
    out.handles
        .extend(patch.handles.iter().map(|h| HandleState {
            from: h.from,
            to: h.to.value_at(t).unwrap_or(h.from),
            radius: h.radius,
            depth: h.depth,
            pivot: h.pivot,
            rotation: h.rotation.value_at(t),
        }));
    out.pins.clear();
    out.pins.extend(
        patch
            .pins
            .iter()
            .filter(|pin| pin.is_active(t))
            .map(|pin| pin.at),
    );
}
