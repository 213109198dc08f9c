//! The scene language's editing calls, registered next to [`super::api`]: takes the shared
//! draft and gives `remove_patch(...)` and, on `Patch` and `Handle` values, `remove_key`,
//! `move_key`, `handle`, `remove_handle`, `remove_pin`, `rename`, `to_front` and `to_back`. Every
//! call is checked in full before it changes anything, so a refusal (a positioned runtime
//! error that says what exists) leaves the scene as it was.

use rhai::{Dynamic, Engine, NativeCallContext, TypeBuilder};

use super::refs::{fail, Fallible, HandleRef, PatchRef, Placed};
use super::draft::{Draft, SharedDraft};
use super::values;
use crate::scene::{Interpolate, Patch, Track};

/// What removing and moving keys needs of a track, whatever its value type.
trait KeyTimes {
    fn has_key_at(&self, t: f64) -> bool;
    fn remove(&mut self, t: f64);
    fn move_key(&mut self, from: f64, to: f64);
    fn key_times(&self) -> Vec<f64>;
}

impl<T: Interpolate> KeyTimes for Track<T> {
    fn has_key_at(&self, t: f64) -> bool {
        Track::has_key_at(self, t)
    }
    fn remove(&mut self, t: f64) {
        Track::remove(self, t);
    }
    fn move_key(&mut self, from: f64, to: f64) {
        Track::move_key(self, from, to);
    }
    fn key_times(&self) -> Vec<f64> {
        self.times().collect()
    }
}

/// The keyframed tracks of one patch or handle, by name, and how errors name their owner.
struct Tracks<'a> {
    owner: String,
    tracks: Vec<(&'static str, &'a mut dyn KeyTimes)>,
}

fn patch_tracks(patch: &mut Patch) -> Tracks<'_> {
    let owner = format!("patch {:?}", patch.name);
    let p = &mut patch.placement;
    // The same order and names as `Placed::ALL`.
    let tracks: Vec<(&'static str, &mut dyn KeyTimes)> = vec![
        (Placed::At.name(), &mut p.position),
        (Placed::Scale.name(), &mut p.scale),
        (Placed::Rotate.name(), &mut p.rotation),
        (Placed::Depth.name(), &mut p.depth),
        (Placed::Opacity.name(), &mut p.opacity),
    ];
    Tracks { owner, tracks }
}

impl<'a> Tracks<'a> {
    /// The tracks `name` selects (all of them for `None`), or an error naming the tracks.
    fn select(&mut self, name: Option<&str>) -> Result<Vec<&mut &'a mut dyn KeyTimes>, String> {
        let names: Vec<&str> = self.tracks.iter().map(|(n, _)| *n).collect();
        if let Some(name) = name {
            if !names.contains(&name) {
                return Err(format!(
                    "unknown track {name:?} on {}; tracks: {}",
                    self.owner,
                    names.join(", ")
                ));
            }
        }
        Ok(self
            .tracks
            .iter_mut()
            .filter(|(n, _)| name.is_none_or(|name| name == *n))
            .map(|(_, t)| t)
            .collect())
    }

    /// Checks that some selected track has a key at `t`; the error lists the keys there are.
    fn find(&mut self, t: f64, name: Option<&str>) -> Result<(), String> {
        let owner = self.owner.clone();
        let selected = self.select(name)?;
        if selected.iter().any(|track| track.has_key_at(t)) {
            return Ok(());
        }
        let mut times: Vec<f64> = selected.iter().flat_map(|t| t.key_times()).collect();
        times.sort_by(f64::total_cmp);
        times.dedup();
        let what = match name {
            Some(name) => format!("no {name:?} key"),
            None => "no key".to_string(),
        };
        let keys = listed(times.iter().map(f64::to_string), "it has no keys", "its keys are at ");
        Err(format!("{what} at t = {t} on {owner}; {keys}"))
    }

    fn remove_key(&mut self, t: f64, name: Option<&str>) -> Result<(), String> {
        self.find(t, name)?;
        for track in self.select(name)? {
            track.remove(t);
        }
        Ok(())
    }

    fn move_key(&mut self, from: f64, to: f64, name: Option<&str>) -> Result<(), String> {
        self.find(from, name)?;
        for track in self.select(name)? {
            if track.has_key_at(from) {
                track.move_key(from, to);
            }
        }
        Ok(())
    }
}

fn handle_tracks(handle: &mut crate::scene::Handle, owner: String) -> Tracks<'_> {
    let tracks: Vec<(&'static str, &mut dyn KeyTimes)> =
        vec![("at", &mut handle.to), ("rotate", &mut handle.rotation)];
    Tracks { owner, tracks }
}

/// Applies `edit` to a copy of the whole draft and commits it only if it succeeds.
fn edit_draft<R>(
    draft: &SharedDraft,
    ctx: &NativeCallContext,
    edit: impl FnOnce(&mut Draft) -> Result<R, String>,
) -> Fallible<R> {
    let mut d = draft.lock();
    let mut copy = d.clone();
    let result = edit(&mut copy).map_err(|m| fail(ctx, m))?;
    *d = copy;
    Ok(result)
}

/// The patch's current index, or the error for a patch removed since.
fn index_of(d: &Draft, patch: &PatchRef) -> Result<usize, String> {
    d.patch_index(patch.id)
        .ok_or_else(|| "this patch no longer exists in the scene".to_string())
}

pub fn register(engine: &mut Engine, draft: &SharedDraft) {
    let d = draft.clone();
    engine.register_fn(
        "remove_patch",
        move |ctx: NativeCallContext, name: &str| -> Fallible<()> {
            edit_draft(&d, &ctx, |draft| {
                let index = draft
                    .patches
                    .iter()
                    .position(|p| p.name == name)
                    .ok_or_else(|| draft.no_patch_message(name))?;
                draft.remove_patch(index);
                Ok(())
            })
        },
    );
    engine.register_fn(
        "remove_patch",
        move |ctx: NativeCallContext, patch: PatchRef| -> Fallible<()> {
            edit_draft(&patch.draft, &ctx, |draft| {
                let index = index_of(draft, &patch)?;
                draft.remove_patch(index);
                Ok(())
            })
        },
    );
}

impl PatchRef {
    /// The patch's handle at index `which`, as the value `drag` returned for it.
    fn handle_at(&mut self, ctx: NativeCallContext, which: Dynamic) -> Fallible<HandleRef> {
        let d = self.draft.lock();
        let found = index_of(&d, self).and_then(|p| {
            let h = index(&which, "handle", d.patches[p].handles.len())
                .map_err(|m| handles_listed(m, &d.patches[p]))?;
            Ok(d.ids.handles[p][h])
        });
        let handle = found.map_err(|m| fail(&ctx, m))?;
        Ok(HandleRef {
            draft: self.draft.clone(),
            patch: self.id,
            handle,
        })
    }

    fn remove_handle(&mut self, ctx: NativeCallContext, which: Dynamic) -> Fallible<Self> {
        let this = self.clone();
        edit_draft(&self.draft, &ctx, |d| {
            let p = index_of(d, &this)?;
            let h = match which.clone().try_cast::<HandleRef>() {
                Some(handle) => {
                    let (hp, h) = handle
                        .indices(d)
                        .ok_or("this handle no longer exists in the scene")?;
                    if hp != p {
                        return Err(format!(
                            "this handle belongs to patch {:?}, not {:?}",
                            d.patches[hp].name, d.patches[p].name
                        ));
                    }
                    h
                }
                None => index(&which, "handle", d.patches[p].handles.len())
                    .map_err(|m| handles_listed(m, &d.patches[p]))?,
            };
            d.patches[p].handles.remove(h);
            d.ids.handles[p].remove(h);
            Ok(())
        })?;
        Ok(self.clone())
    }

    pub(super) fn remove_pin(
        &mut self,
        ctx: NativeCallContext,
        which: Dynamic,
    ) -> Fallible<Self> {
        self.edit(&ctx, |p| {
            let i = if which.is_array() {
                let at = values::point(&which, "pin point")?;
                let found = p.pins.iter().position(|pin| pin.at == at);
                found.ok_or_else(|| pins_listed(format!("no pin at [{}, {}]", at.x, at.y), p))?
            } else {
                index(&which, "pin", p.pins.len()).map_err(|m| pins_listed(m, p))?
            };
            p.pins.remove(i);
            Ok(())
        })?;
        Ok(self.clone())
    }

    fn rename(&mut self, ctx: NativeCallContext, name: Dynamic) -> Fallible<Self> {
        let this = self.clone();
        edit_draft(&self.draft, &ctx, |d| {
            let p = index_of(d, &this)?;
            let name = values::patch_name(&name)?;
            if let Some(other) = d.patches.iter().position(|q| q.name == name) {
                if other != p {
                    let names: Vec<&str> = d.patches.iter().map(|q| q.name.as_str()).collect();
                    return Err(format!(
                        "a patch named {name:?} already exists; patches: {}",
                        names.join(", ")
                    ));
                }
            }
            d.patches[p].name = name;
            Ok(())
        })?;
        Ok(self.clone())
    }

    /// Moves the patch to the end (front) or start (back) of scene order.
    fn reorder(&mut self, ctx: NativeCallContext, front: bool) -> Fallible<Self> {
        let this = self.clone();
        edit_draft(&self.draft, &ctx, |d| {
            let p = index_of(d, &this)?;
            let to = if front { d.patches.len() - 1 } else { 0 };
            d.move_patch(p, to);
            Ok(())
        })?;
        Ok(self.clone())
    }
}

/// A whole-number index below `len`.
fn index(value: &Dynamic, what: &str, len: usize) -> Result<usize, String> {
    let Ok(i) = value.as_int() else {
        return Err(format!(
            "{what} must be given by its index (an integer) or its value, got {}",
            value.type_name()
        ));
    };
    usize::try_from(i)
        .ok()
        .filter(|&i| i < len)
        .ok_or_else(|| format!("no {what} {i}"))
}

/// `error` on patch `p`, followed by the handles it has.
fn handles_listed(error: String, p: &Patch) -> String {
    let each = p.handles.iter().enumerate();
    let each = each.map(|(i, h)| format!("{i} from [{}, {}]", h.from.x, h.from.y));
    let handles = listed(each, "it has no handles", "its handles: ");
    format!("{error} on patch {:?}; {handles}", p.name)
}

/// `error` on patch `p`, followed by the pins it has.
fn pins_listed(error: String, p: &Patch) -> String {
    let each = p.pins.iter().enumerate();
    let each = each.map(|(i, pin)| format!("{i} at [{}, {}]", pin.at.x, pin.at.y));
    let pins = listed(each, "it has no pins", "its pins: ");
    format!("{error} on patch {:?}; {pins}", p.name)
}

/// `none` for no items, else `some` followed by the items separated by commas.
fn listed(items: impl Iterator<Item = String>, none: &str, some: &str) -> String {
    let items: Vec<String> = items.collect();
    if items.is_empty() {
        return none.into();
    }
    format!("{some}{}", items.join(", "))
}

/// A patch or a handle: what owns keyframed tracks a script edits by name.
trait KeyOwner: Clone + Send + Sync + 'static {
    /// Applies `edit` to this owner's tracks, committing only if it succeeds.
    fn edit_tracks(
        &mut self,
        ctx: &NativeCallContext,
        edit: impl FnOnce(&mut Tracks) -> Result<(), String>,
    ) -> Fallible<Self>;
}

impl KeyOwner for PatchRef {
    fn edit_tracks(
        &mut self,
        ctx: &NativeCallContext,
        edit: impl FnOnce(&mut Tracks) -> Result<(), String>,
    ) -> Fallible<Self> {
        self.edit(ctx, |p| edit(&mut patch_tracks(p)))?;
        Ok(self.clone())
    }
}

impl KeyOwner for HandleRef {
    fn edit_tracks(
        &mut self,
        ctx: &NativeCallContext,
        edit: impl FnOnce(&mut Tracks) -> Result<(), String>,
    ) -> Fallible<Self> {
        let this = self.clone();
        edit_draft(&self.draft, ctx, |d| {
            let (p, h) = this
                .indices(d)
                .ok_or("this handle no longer exists in the scene")?;
            let owner = format!("handle {h} of patch {:?}", d.patches[p].name);
            edit(&mut handle_tracks(&mut d.patches[p].handles[h], owner))
        })?;
        Ok(self.clone())
    }
}

/// `remove_key(t [, track])` and `move_key(from, to [, track])`, on a patch or a handle.
fn build_key_edits<T: KeyOwner>(b: &mut TypeBuilder<T>) {
    let remove = |ctx: &NativeCallContext, o: &mut T, t: Dynamic, track: Option<&str>| {
        o.edit_tracks(ctx, |tracks| tracks.remove_key(values::time(&t)?, track))
    };
    let move_key = |ctx: &NativeCallContext, o: &mut T, from: Dynamic, to: Dynamic, track: Option<&str>| {
        o.edit_tracks(ctx, |tracks| {
            tracks.move_key(values::time(&from)?, values::time(&to)?, track)
        })
    };
    b.with_fn("remove_key", move |ctx: NativeCallContext, o: &mut T, t: Dynamic| {
        remove(&ctx, o, t, None)
    })
    .with_fn(
        "remove_key",
        move |ctx: NativeCallContext, o: &mut T, t: Dynamic, track: &str| {
            remove(&ctx, o, t, Some(track))
        },
    )
    .with_fn(
        "move_key",
        move |ctx: NativeCallContext, o: &mut T, from: Dynamic, to: Dynamic| {
            move_key(&ctx, o, from, to, None)
        },
    )
    .with_fn(
        "move_key",
        move |ctx: NativeCallContext, o: &mut T, from: Dynamic, to: Dynamic, track: &str| {
            move_key(&ctx, o, from, to, Some(track))
        },
    );
}

pub fn build_patch(b: &mut TypeBuilder<PatchRef>) {
    build_key_edits(b);
    b.with_fn(
        "remove_handle",
        |ctx: NativeCallContext, p: &mut PatchRef, h: Dynamic| p.remove_handle(ctx, h),
    )
    .with_fn(
        "handle",
        |ctx: NativeCallContext, p: &mut PatchRef, h: Dynamic| p.handle_at(ctx, h),
    )
    .with_fn(
        "remove_pin",
        |ctx: NativeCallContext, p: &mut PatchRef, pin: Dynamic| p.remove_pin(ctx, pin),
    )
    .with_fn(
        "rename",
        |ctx: NativeCallContext, p: &mut PatchRef, name: Dynamic| p.rename(ctx, name),
    )
    .with_fn("to_front", |ctx: NativeCallContext, p: &mut PatchRef| {
        p.reorder(ctx, true)
    })
    .with_fn("to_back", |ctx: NativeCallContext, p: &mut PatchRef| {
        p.reorder(ctx, false)
    });
}

pub fn build_handle(b: &mut TypeBuilder<HandleRef>) {
    build_key_edits(b);
}
