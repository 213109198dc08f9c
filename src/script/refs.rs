//! The script-side handles on a scene and what the scene functions share: takes nothing and
//! gives the `PatchRef`, `HandleRef` and `PinRef` types scripts hold (stable ids into the shared
//! draft), the keyframable placement properties by name, and the positioned runtime error.

use rhai::{Dynamic, EvalAltResult, NativeCallContext};

use super::draft::SharedDraft;
use super::values;
use crate::scene::{Easing, Patch};

pub(super) type Fallible<T> = Result<T, Box<EvalAltResult>>;

/// A runtime error at the position of the current call.
pub(super) fn fail(ctx: &NativeCallContext, message: impl Into<String>) -> Box<EvalAltResult> {
    EvalAltResult::ErrorRuntime(message.into().into(), ctx.call_position()).into()
}

/// A patch of the scene, as seen from a script. Cloning it in Rhai shares the patch; it
/// names the patch by a stable id, so it survives renames, reordering and other removals.
#[derive(Clone, Debug)]
pub struct PatchRef {
    pub(super) draft: SharedDraft,
    pub(super) id: u64,
}

/// A handle (drag) of a patch, as seen from a script (stable ids, like [`PatchRef`]).
#[derive(Clone, Debug)]
pub struct HandleRef {
    pub(super) draft: SharedDraft,
    pub(super) patch: u64,
    pub(super) handle: u64,
}

/// A pin of a patch, as seen from a script: its patch's stable id and its rest point
/// (two pins at one point hold the same point, so the point names the pin).
#[derive(Clone, Debug)]
pub struct PinRef {
    pub(super) patch: PatchRef,
    pub(super) at: glam::DVec2,
}

/// The keyframable placement properties, by their scene-language names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Placed {
    At,
    Scale,
    Rotate,
    Depth,
    Opacity,
}

/// The [`Placed`] variants' names, in declaration order.
pub(super) const PLACEMENT_KEYS: [&str; 5] = ["at", "scale", "rotate", "depth", "opacity"];

impl Placed {
    pub(super) const ALL: [Placed; 5] = [
        Placed::At,
        Placed::Scale,
        Placed::Rotate,
        Placed::Depth,
        Placed::Opacity,
    ];

    pub(super) fn from_name(name: &str) -> Option<Placed> {
        Placed::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The track's scene-language name.
    pub(super) fn name(self) -> &'static str {
        PLACEMENT_KEYS[self as usize]
    }

    pub(super) fn push(
        self,
        patch: &mut Patch,
        t: f64,
        value: &Dynamic,
        easing: Easing,
    ) -> Result<(), String> {
        let p = &mut patch.placement;
        let result = match self {
            Placed::At => p.position.push(t, values::position(value, "`at`")?, easing),
            Placed::Scale => p.scale.push(t, values::scale(value, "`scale`")?, easing),
            Placed::Rotate => p.rotation.push(t, values::rotation_or_depth(value, "`rotate`")?, easing),
            Placed::Depth => p.depth.push(t, values::rotation_or_depth(value, "`depth`")?, easing),
            Placed::Opacity => p.opacity.push(t, values::unit(value, "`opacity`")?, easing),
        };
        result.map_err(|e| e.to_string())
    }
}
