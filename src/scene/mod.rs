//! The scene: a canvas and layered, keyframed patches as plain Rust values ([`Scene`]), their
//! evaluation at a time ([`Scene::evaluate`] → [`FrameState`]) and their writing back as a
//! Rhai scene file ([`Scene::to_rhai`]), and warnings about what no frame shows
//! ([`Scene::warnings`]). Parsing scene files lives in the script stage.

mod evaluate;
mod follow;
mod to_rhai;
mod track;
mod types;
mod warnings;

pub use evaluate::{frame_time, FrameState, HandleState, PatchState};
pub(crate) use to_rhai::get_patch_call;
pub use to_rhai::rhai_string_literal;
pub use track::{Easing, Interpolate, Key, KeyError, Track};
pub use types::{
    Follow, FollowTarget,
    check_polygons, Background, BoundaryData, BoundaryPlacement, Canvas, CloneMode, Footage,
    FootageSource, Handle, LaplacianKind, ModelError, Patch, Pin, Placement, Polygon, Scene, Shape,
    MAX_CANVAS_SIDE,
};
