//! The scene language's functions and types, registered on a Rhai engine: takes a
//! [`SharedDraft`] and gives `canvas(...)`, `patch(...)`, `get_patch(...)` and the `Patch` and
//! `Handle` types (with `CustomType`/`TypeBuilder`). Every value is validated when it is set;
//! a refusal is a runtime error at the position of the offending call. See
//! docs/scene-language.md for the language itself.

use crate::util::ShowPath;
use std::path::{Path, PathBuf};

use glam::DVec2;
use rhai::{CustomType, Dynamic, Engine, Map, NativeCallContext, TypeBuilder};

use super::draft::{Origin, SharedDraft};
use super::refs::{fail, Fallible, HandleRef, PatchRef, PinRef, Placed, PLACEMENT_KEYS};
use super::footage_options::{footage_keys, footage_option};
use super::values::{self, number};
use crate::scene::{
    get_patch_call, Background, Canvas, CloneMode, Easing, Handle, LaplacianKind, Patch, Pin, Polygon,
    Shape, Track,
};


/// `options` with renamed keys under their new names; each old one found is noted as a
/// warning at the call.
fn renamed(ctx: &NativeCallContext, draft: &SharedDraft, options: &Map) -> Fallible<Map> {
    let mut options = options.clone();
    let old = values::rename_keys(&mut options).map_err(|m| fail(ctx, m))?;
    let mut d = draft.lock();
    let at = origin(ctx, &d.base_dir);
    for old in old {
        // invariant: rename_keys gives only names from RENAMED_KEYS.
        let new = values::RENAMED_KEYS.iter().find(|(o, _)| *o == old).expect("renamed").1;
        d.origins.warnings.push(format!(
            "{}: `{old}` is now `{new}` (the old name still works)",
            super::error::location(&at.file, at.position)
        ));
    }
    Ok(options)
}

fn origin(ctx: &NativeCallContext, base_dir: &Path) -> Origin {
    Origin {
        file: ctx
            .call_source()
            .map(PathBuf::from)
            .unwrap_or_else(|| base_dir.to_path_buf()),
        position: ctx.call_position(),
    }
}

/// Resolves `text` against the scene folder and insists it is a regular file.
fn existing_file(base_dir: &Path, text: &str, what: &str) -> Result<PathBuf, String> {
    let path = base_dir.join(text);
    match crate::util::not_a_file(&path) {
        None => Ok(path),
        Some("does not exist") => Err(format!(
            "{what} file `{text}` not found (looked for {})",
            path.shown()
        )),
        Some(problem) => Err(format!("{what} `{text}` {problem} ({})", path.shown())),
    }
}

pub fn register(engine: &mut Engine, draft: &SharedDraft) {
    engine
        .build_type::<PatchRef>()
        .build_type::<HandleRef>()
        .build_type::<PinRef>();
    let d = draft.clone();
    engine.register_fn(
        "canvas",
        move |ctx: NativeCallContext, w: Dynamic, h: Dynamic| {
            set_canvas(&ctx, &d, Some((&w, &h)), &Map::new())
        },
    );
    let d = draft.clone();
    // The size comes from the background footage's plates.
    engine.register_fn("canvas", move |ctx: NativeCallContext, options: Map| {
        set_canvas(&ctx, &d, None, &options)
    });
    let d = draft.clone();
    engine.register_fn(
        "canvas",
        move |ctx: NativeCallContext, w: Dynamic, h: Dynamic, options: Map| {
            set_canvas(&ctx, &d, Some((&w, &h)), &options)
        },
    );
    let d = draft.clone();
    engine.register_fn(
        "patch",
        move |ctx: NativeCallContext, name: Dynamic, options: Dynamic| {
            new_patch(&ctx, &d, &name, &options)
        },
    );
    let d = draft.clone();
    engine.register_fn("get_patch", move |ctx: NativeCallContext, name: &str| {
        let guard = d.lock();
        let index = guard.patches.iter().position(|p| p.name == name);
        index
            .map(|index| PatchRef {
                draft: d.clone(),
                id: guard.ids.patches[index],
            })
            .ok_or_else(|| fail(&ctx, guard.no_patch_message(name)))
    });
    super::edit_api::register(engine, draft);
    super::follow_api::register(engine, draft);
    engine.register_fn("easings", || -> rhai::Array {
        Easing::ALL
            .iter()
            .map(|e| Dynamic::from(e.name().to_string()))
            .collect()
    });
}

fn set_canvas(
    ctx: &NativeCallContext,
    draft: &SharedDraft,
    size: Option<(&Dynamic, &Dynamic)>,
    options: &Map,
) -> Fallible<()> {
    let options = renamed(ctx, draft, options)?;
    let mut d = draft.lock();
    let canvas = parse_canvas(&d.base_dir, size, &options).map_err(|m| fail(ctx, m))?;
    let at = origin(ctx, &d.base_dir);
    // A scene has one canvas: a second call (an imported module's, or one left in by
    // mistake) replaces the first, which a reader of the first call would not expect.
    if let Some(first) = d.origins.canvas.replace(at.clone()) {
        let location = super::error::location;
        d.origins.warnings.push(format!(
            "{}: `canvas` again: this canvas replaces the one of {} (a scene has one)",
            location(&at.file, at.position),
            location(&first.file, first.position)
        ));
    }
    d.canvas = Some(canvas);
    Ok(())
}

fn parse_canvas(
    base_dir: &Path,
    size: Option<(&Dynamic, &Dynamic)>,
    options: &Map,
) -> Result<Canvas, String> {
    let [start_key, hold_key] = footage_keys("background");
    let keys = [
        "fps",
        "duration",
        "background",
        start_key.as_str(),
        hold_key.as_str(),
    ];
    values::check_keys(options, &keys, "canvas")?;
    let fps = match options.get("fps") {
        Some(v) => values::positive(v, "fps")?,
        None => 24.0,
    };
    if let Some(error) = crate::limits::fps_error(fps) {
        return Err(error);
    }
    let duration = match options.get("duration") {
        Some(v) => values::positive(v, "duration")?,
        None => 1.0,
    };
    let background = match options.get("background") {
        None => Background::Colour([0.0, 0.0, 0.0, 1.0]),
        Some(v) => match v.read_lock::<rhai::ImmutableString>() {
            Some(text) if !text.starts_with('#') => {
                match footage_option(base_dir, &text, options, "background")? {
                    Some(footage) => Background::Footage(footage),
                    None => Background::Image(existing_file(base_dir, &text, "background")?),
                }
            }
            _ => Background::Colour(values::colour(v)?),
        },
    };
    let (width, height) = match (size, &background) {
        (Some((w, h)), _) => (
            values::size(w, "canvas width")?,
            values::size(h, "canvas height")?,
        ),
        (None, Background::Footage(f)) => (f.width, f.height),
        (None, _) => {
            return Err("canvas needs a width and a height unless its background is footage".into())
        }
    };
    let canvas = Canvas {
        width,
        height,
        fps,
        duration,
        background,
    };
    // Pixel-count and frame limits, positioned at this call rather than at the end.
    canvas.sanity_check().map_err(|e| e.to_string())?;
    Ok(canvas)
}

/// The option keys of `canvas`, polygons, `drag`, `pin` and key maps in their current
/// spelling (the REPL completes them; `PATCH_OPTIONS` has the rest).
pub const OTHER_OPTION_KEYS: [&str; 15] = [
    "fps", "duration", "background", "background_start_number", "background_hold", "outer",
    "holes", "pivot", "start", "end", "t", "scale", "depth", "opacity", "ease",
];

pub const PATCH_OPTIONS: [&str; 11] = [
    "source",
    "source_start_number",
    "source_hold",
    "mask",
    "polygons",
    "density",
    "laplacian",
    "mode",
    "feather",
    "boundary_sampling",
    "mesh_boundary",
];

fn new_patch(
    ctx: &NativeCallContext,
    draft: &SharedDraft,
    name: &Dynamic,
    options: &Dynamic,
) -> Fallible<PatchRef> {
    let options = values::map(options, "patch options").map_err(|m| fail(ctx, m))?;
    let options = renamed(ctx, draft, &options)?;
    let mut d = draft.lock();
    let patch = parse_patch(&d.base_dir, name, &options).map_err(|m| fail(ctx, m))?;
    if d.patches.iter().any(|p| p.name == patch.name) {
        return Err(fail(
            ctx,
            format!("a patch named `{}` already exists", patch.name),
        ));
    }
    let o = origin(ctx, &d.base_dir);
    let id = d.push_patch(patch, o);
    Ok(PatchRef {
        draft: draft.clone(),
        id,
    })
}

fn parse_patch(base_dir: &Path, name: &Dynamic, options: &Map) -> Result<Patch, String> {
    let name = values::patch_name(name)?;
    values::check_keys(options, &PATCH_OPTIONS, "patch")?;
    let source = options
        .get("source")
        .ok_or("patch needs a `source` image")
        .and_then(|v| values::string(v, "source").map_err(|_| "`source` must be a string path"))?;
    let footage = footage_option(base_dir, &source, options, "source")?;
    let source = match &footage {
        Some(footage) => footage.first_path(),
        None => existing_file(base_dir, &source, "source")?,
    };
    let shape = match (options.get("mask"), options.get("polygons")) {
        (Some(mask), None) => {
            let mask = values::string(mask, "mask")?;
            Shape::Mask(existing_file(base_dir, &mask, "mask")?)
        }
        (None, Some(polygons)) => Shape::Polygons(parse_polygons(polygons)?),
        (Some(_), Some(_)) => return Err("give either `mask` or `polygons`, not both".into()),
        (None, None) => return Err("patch needs a `mask` image or `polygons`".into()),
    };
    let mut patch = Patch::new(name, source, shape);
    patch.footage = footage;
    if let Some(v) = options.get("density") {
        patch.density = Some(values::positive(v, "density")?);
    }
    if let Some(v) = options.get("laplacian") {
        let text = values::string(v, "laplacian")?;
        patch.laplacian = LaplacianKind::from_name(&text).ok_or_else(|| {
            format!("unknown laplacian `{text}` (expected combinatorial or cotangent)")
        })?;
    }
    if let Some(v) = options.get("mode") {
        let text = values::string(v, "mode")?;
        patch.mode = CloneMode::from_name(&text)
            .ok_or_else(|| format!("unknown mode `{text}` (expected normal or monochrome)"))?;
    }
    if let Some(v) = options.get("feather") {
        patch.feather = values::feather(v)?;
    }
    if let Some(v) = options.get("boundary_sampling") {
        patch.boundary_data = values::string(v, "boundary_sampling")?.parse()?;
    }
    if let Some(v) = options.get("mesh_boundary") {
        patch.boundary = values::string(v, "mesh_boundary")?.parse()?;
    }
    Ok(patch)
}

/// `[[x, y], ...]` (outer ring only) or `#{ outer: [...], holes: [[...], ...] }`, in an array.
fn parse_polygons(value: &Dynamic) -> Result<Vec<Polygon>, String> {
    let items = values::array(value, "polygons")?;
    let mut polygons = Vec::with_capacity(items.len());
    for item in &items {
        let polygon = if let Some(m) = item.read_lock::<Map>() {
            values::check_keys(&m, &["outer", "holes"], "polygon")?;
            let outer = m.get("outer").ok_or("polygon map needs `outer`")?;
            let holes = match m.get("holes") {
                Some(h) => values::array(h, "holes")?
                    .iter()
                    .map(ring)
                    .collect::<Result<_, _>>()?,
                None => Vec::new(),
            };
            Polygon {
                outer: ring(outer)?,
                holes,
            }
        } else {
            Polygon {
                outer: ring(item)?,
                holes: Vec::new(),
            }
        };
        polygons.push(polygon);
    }
    crate::scene::check_polygons(&polygons)?;
    Ok(polygons)
}

fn ring(value: &Dynamic) -> Result<Vec<DVec2>, String> {
    values::array(value, "polygon ring")?
        .iter()
        .map(|p| values::point(p, "polygon point"))
        .collect()
}

impl PatchRef {
    /// Applies `edit` to a copy of the patch and commits it only if it succeeds, so a failed
    /// call leaves the scene unchanged.
    pub(super) fn edit<R>(
        &self,
        ctx: &NativeCallContext,
        edit: impl FnOnce(&mut Patch) -> Result<R, String>,
    ) -> Fallible<R> {
        self.edit_in_place(ctx, |patch| {
            let mut copy = patch.clone();
            let result = edit(&mut copy)?;
            *patch = copy;
            Ok(result)
        })
    }

    /// Applies `edit` to the patch itself, for edits that change it only once every check
    /// has passed (one key, one drag, one pin): no copy, so a scene adding keys one call at
    /// a time stays linear in its keys.
    fn edit_in_place<R>(
        &self,
        ctx: &NativeCallContext,
        edit: impl FnOnce(&mut Patch) -> Result<R, String>,
    ) -> Fallible<R> {
        let mut d = self.draft.lock();
        let Some(index) = d.patch_index(self.id) else {
            return Err(fail(ctx, "this patch no longer exists in the scene"));
        };
        edit(&mut d.patches[index]).map_err(|m| fail(ctx, m))
    }

    /// The patch as the REPL shows it: the call that gives it back, `get_patch("cat")`.
    fn describe(&self) -> String {
        let d = self.draft.lock();
        match d.patch_index(self.id) {
            Some(i) => get_patch_call(&d.patches[i].name),
            None => "a patch removed from the scene".to_string(),
        }
    }

    pub(super) fn name(&mut self) -> String {
        let d = self.draft.lock();
        d.patch_index(self.id)
            .map(|i| d.patches[i].name.clone())
            .unwrap_or_default()
    }

    /// `key(t, #{ at, …, ease })` or `key(t, #{ at, … }, ease)`: the easing once, either way.
    fn key_map(
        &mut self,
        ctx: NativeCallContext,
        t: Dynamic,
        mut values: Map,
        easing: Option<&str>,
    ) -> Fallible<Self> {
        self.edit_in_place(&ctx, |p| {
            let t = values::time(&t)?;
            let easing = match (values.contains_key("ease"), easing) {
                (true, Some(_)) => return Err("give the easing once: `ease` or a last argument".into()),
                (false, Some(name)) => values::easing(name)?,
                (_, None) => take_easing(&mut values)?,
            };
            // A key refused for one property must leave the others unkeyed too: try them
            // on empty tracks first (a key's checks never depend on the keys already there).
            let mut trial = Patch::new(String::new(), PathBuf::new(), Shape::Polygons(Vec::new()));
            add_placement_keys(&mut trial, t, &values, easing)?;
            add_placement_keys(p, t, &values, easing)
        })?;
        Ok(self.clone())
    }

    /// `keys([#{ t, at, scale, rotate, depth, ease }, ...])`.
    fn keys(&mut self, ctx: NativeCallContext, list: rhai::Array) -> Fallible<Self> {
        self.edit(&ctx, |p| {
            for item in &list {
                let mut m = values::map(item, "key")?;
                let t = values::time(m.get("t").ok_or("each key needs a time `t`")?)?;
                let easing = take_easing(&mut m)?;
                m.remove("t");
                add_placement_keys(p, t, &m, easing)?;
            }
            Ok(())
        })?;
        Ok(self.clone())
    }

    fn track_key(
        &mut self,
        ctx: NativeCallContext,
        which: Placed,
        t: Dynamic,
        value: Dynamic,
        easing: &str,
    ) -> Fallible<Self> {
        self.edit_in_place(&ctx, |p| {
            let t = values::time(&t)?;
            let easing = values::easing(easing)?;
            which.push(p, t, &value, easing)
        })?;
        Ok(self.clone())
    }

    fn drag(
        &mut self,
        ctx: NativeCallContext,
        from: Dynamic,
        radius: Dynamic,
        options: Map,
    ) -> Fallible<HandleRef> {
        self.edit_in_place(&ctx, |p| {
            values::check_keys(&options, &["depth", "pivot"], "drag")?;
            let handle = Handle {
                from: values::position(&from, "drag rest point")?,
                to: Track::new(),
                radius: values::positive(&radius, "drag radius")?,
                depth: options
                    .get("depth")
                    .map(|v| values::rotation_or_depth(v, "depth"))
                    .transpose()?,
                pivot: options
                    .get("pivot")
                    .map(|v| values::position(v, "pivot"))
                    .transpose()?,
                rotation: Track::new(),
            };
            p.handles.push(handle);
            Ok(())
        })?;
        let mut d = self.draft.lock();
        // invariant: the edit above found the patch, and nothing ran in between.
        let index = d.patch_index(self.id).expect("patch edited just now");
        let handle = d.register_handle(index);
        Ok(HandleRef {
            draft: self.draft.clone(),
            patch: self.id,
            handle,
        })
    }

    fn pin(&mut self, ctx: NativeCallContext, at: Dynamic, options: Map) -> Fallible<PinRef> {
        let at = self.edit_in_place(&ctx, |p| {
            values::check_keys(&options, &["start", "end"], "pin")?;
            let start = match options.get("start") {
                Some(v) => values::time(v)?,
                None => 0.0,
            };
            let end = options.get("end").map(values::time).transpose()?;
            if end.is_some_and(|e| e <= start) {
                return Err(format!("pin `end` must be after `start` ({start})"));
            }
            let at = values::position(&at, "pin point")?;
            p.pins.push(Pin { at, start, end });
            Ok(at)
        })?;
        Ok(PinRef {
            patch: self.clone(),
            at,
        })
    }
}


fn add_placement_keys(patch: &mut Patch, t: f64, keys: &Map, easing: Easing) -> Result<(), String> {
    values::check_keys(keys, &PLACEMENT_KEYS, "key")?;
    if keys.is_empty() {
        return Err("a key needs at least one of: at, scale, rotate, depth, opacity".into());
    }
    for (name, value) in keys {
        let which = Placed::from_name(name).expect("checked key name"); // invariant: check_keys admitted only placement names.
        which.push(patch, t, value, easing)?;
    }
    Ok(())
}

/// Removes and parses an optional `ease` entry of a key map (default linear).
fn take_easing(m: &mut Map) -> Result<Easing, String> {
    match m.remove("ease") {
        Some(v) => values::easing(&values::string(&v, "ease")?),
        None => Ok(Easing::Linear),
    }
}

impl HandleRef {
    /// The (patch, handle) indices this handle has now, if it still exists.
    pub(super) fn indices(&self, d: &super::draft::Draft) -> Option<(usize, usize)> {
        let p = d.patch_index(self.patch)?;
        Some((p, d.handle_index(p, self.handle)?))
    }

    /// The handle as the REPL shows it: `handle 0 of get_patch("cat")`, its index as it is
    /// now.
    fn describe(&self) -> String {
        let d = self.draft.lock();
        match self.indices(&d) {
            Some((p, h)) => format!("handle {h} of {}", get_patch_call(&d.patches[p].name)),
            None => "a handle removed from the scene".to_string(),
        }
    }

    /// Applies `edit` to a copy of the handle and commits it only if it succeeds.
    pub(super) fn edit(
        &self,
        ctx: &NativeCallContext,
        edit: impl FnOnce(&mut Handle) -> Result<(), String>,
    ) -> Fallible<Self> {
        self.edit_in_place(ctx, |handle| {
            let mut copy = handle.clone();
            edit(&mut copy)?;
            *handle = copy;
            Ok(())
        })
    }

    /// Applies `edit` to the handle itself, for edits that change it only once every check
    /// has passed (one key): no copy per call.
    fn edit_in_place(
        &self,
        ctx: &NativeCallContext,
        edit: impl FnOnce(&mut Handle) -> Result<(), String>,
    ) -> Fallible<Self> {
        let mut d = self.draft.lock();
        let Some((p, h)) = self.indices(&d) else {
            return Err(fail(ctx, "this handle no longer exists in the scene"));
        };
        edit(&mut d.patches[p].handles[h]).map_err(|m| fail(ctx, m))?;
        Ok(self.clone())
    }

    fn key(
        &mut self,
        ctx: NativeCallContext,
        t: Dynamic,
        to: Dynamic,
        easing: &str,
    ) -> Fallible<Self> {
        self.edit_in_place(&ctx, |h| {
            let t = values::time(&t)?;
            let easing = values::easing(easing)?;
            h.to.push(t, values::position(&to, "handle target")?, easing)
                .map_err(|e| e.to_string())
        })
    }

    /// `radius(r)`: the radius of influence, > 0, for the whole shot (it is not keyed).
    fn set_radius(&mut self, ctx: NativeCallContext, radius: Dynamic) -> Fallible<Self> {
        self.edit_in_place(&ctx, |h| {
            h.radius = values::positive(&radius, "drag radius")?;
            Ok(())
        })
    }

    /// `keys([#{ t, at, rotate, ease }, ...])`.
    fn keys(&mut self, ctx: NativeCallContext, list: rhai::Array) -> Fallible<Self> {
        self.edit(&ctx, |h| {
            for item in &list {
                let mut m = values::map(item, "key")?;
                let easing = take_easing(&mut m)?;
                values::check_keys(&m, &["t", "at", "rotate"], "handle key")?;
                let t = values::time(m.get("t").ok_or("each key needs a time `t`")?)?;
                if let Some(at) = m.get("at") {
                    let at = values::position(at, "handle target")?;
                    h.to.push(t, at, easing).map_err(|e| e.to_string())?;
                }
                if let Some(r) = m.get("rotate") {
                    let r = number(r, "handle rotation")?;
                    h.rotation.push(t, r, easing).map_err(|e| e.to_string())?;
                }
            }
            Ok(())
        })
    }

    fn rotate(
        &mut self,
        ctx: NativeCallContext,
        t: Dynamic,
        degrees: Dynamic,
        easing: &str,
    ) -> Fallible<Self> {
        self.edit_in_place(&ctx, |h| {
            let t = values::time(&t)?;
            let easing = values::easing(easing)?;
            let r = values::rotation_or_depth(&degrees, "handle rotation")?;
            h.rotation.push(t, r, easing).map_err(|e| e.to_string())
        })
    }
}

impl CustomType for PatchRef {
    fn build(mut b: TypeBuilder<Self>) {
        b.with_name("Patch")
            .with_get("name", PatchRef::name)
            .with_fn("to_string", |p: &mut PatchRef| p.describe())
            .with_fn("to_debug", |p: &mut PatchRef| p.describe())
            .with_fn(
                "key",
                |ctx: NativeCallContext, p: &mut PatchRef, t: Dynamic, m: Map| {
                    p.key_map(ctx, t, m, None)
                },
            )
            .with_fn(
                "key",
                |ctx: NativeCallContext, p: &mut PatchRef, t: Dynamic, m: Map, e: &str| {
                    p.key_map(ctx, t, m, Some(e))
                },
            )
            .with_fn(
                "keys",
                |ctx: NativeCallContext, p: &mut PatchRef, l: rhai::Array| p.keys(ctx, l),
            )
            .with_fn(
                "drag",
                |ctx: NativeCallContext, p: &mut PatchRef, from: Dynamic, r: Dynamic| {
                    p.drag(ctx, from, r, Map::new())
                },
            )
            .with_fn(
                "drag",
                |ctx: NativeCallContext, p: &mut PatchRef, from: Dynamic, r: Dynamic, o: Map| {
                    p.drag(ctx, from, r, o)
                },
            )
            .with_fn(
                "pin",
                |ctx: NativeCallContext, p: &mut PatchRef, at: Dynamic| p.pin(ctx, at, Map::new()),
            )
            .with_fn(
                "pin",
                |ctx: NativeCallContext, p: &mut PatchRef, at: Dynamic, o: Map| p.pin(ctx, at, o),
            );
        super::edit_api::build_patch(&mut b);
        build_tracks(&mut b);
    }
}

/// `p.at(t, v [, easing])` and the other placement tracks, one function each.
fn build_tracks(b: &mut TypeBuilder<PatchRef>) {
    for which in Placed::ALL {
        let name = which.name();
        b.with_fn(
            name,
            move |ctx: NativeCallContext, p: &mut PatchRef, t: Dynamic, v: Dynamic| {
                p.track_key(ctx, which, t, v, "linear")
            },
        )
        .with_fn(
            name,
            move |ctx: NativeCallContext, p: &mut PatchRef, t: Dynamic, v: Dynamic, e: &str| {
                p.track_key(ctx, which, t, v, e)
            },
        );
    }
}

impl CustomType for PinRef {
    fn build(mut b: TypeBuilder<Self>) {
        b.with_name("Pin")
            .with_fn("to_string", |q: &mut PinRef| format!("pin([{}, {}])", q.at.x, q.at.y))
            .with_fn("remove", |ctx: NativeCallContext, q: &mut PinRef| {
                let at = Dynamic::from_array(vec![q.at.x.into(), q.at.y.into()]);
                q.patch.remove_pin(ctx, at).map(|_| ())
            })
            // A pin's `pin` pins its patch again, so `p.pin(a).pin(b)` still pins both.
            .with_fn(
                "pin",
                |ctx: NativeCallContext, q: &mut PinRef, at: Dynamic| {
                    q.patch.pin(ctx, at, Map::new())
                },
            )
            .with_fn(
                "pin",
                |ctx: NativeCallContext, q: &mut PinRef, at: Dynamic, o: Map| {
                    q.patch.pin(ctx, at, o)
                },
            );
    }
}

/// A handle call taking a time, a value and an easing.
type HandleKey = fn(&mut HandleRef, NativeCallContext, Dynamic, Dynamic, &str) -> Fallible<HandleRef>;

impl CustomType for HandleRef {
    fn build(mut b: TypeBuilder<Self>) {
        b.with_name("Handle")
            .with_fn("to_string", |h: &mut HandleRef| h.describe())
            .with_fn("to_debug", |h: &mut HandleRef| h.describe())
            .with_fn(
                "keys",
                |ctx: NativeCallContext, h: &mut HandleRef, l: rhai::Array| h.keys(ctx, l),
            );
        // `h.key(t, to [, easing])` and `h.rotate(t, degrees [, easing])`.
        for (name, call) in [("key", HandleRef::key as HandleKey), ("rotate", HandleRef::rotate)] {
            b.with_fn(
                name,
                move |ctx: NativeCallContext, h: &mut HandleRef, t: Dynamic, v: Dynamic| {
                    call(h, ctx, t, v, "linear")
                },
            )
            .with_fn(
                name,
                move |ctx: NativeCallContext, h: &mut HandleRef, t: Dynamic, v: Dynamic, e: &str| {
                    call(h, ctx, t, v, e)
                },
            );
        }
        b.with_fn(
            "radius",
            |ctx: NativeCallContext, h: &mut HandleRef, r: Dynamic| h.set_radius(ctx, r),
        );
        super::edit_api::build_handle(&mut b);
    }
}
