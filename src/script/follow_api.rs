//! The scene language's tracks: takes `p.follow(file, #{ … })`, `h.follow(file, #{ … })` and
//! `track_keys(file, #{ … })` calls and gives keys read from a track file (the CSV `lapclone
//! track` writes, a CSV naming its columns, or After Effects keyframe text): `follow` replaces
//! the patch's `at` (and `rotate` / `scale` from a two-point track) or the handle's target
//! with them and records the call, `track_keys` returns them as a key list for `keys(...)`.


use glam::DVec2;
use rhai::{Array, Dynamic, Engine, Map, NativeCallContext};

use super::draft::SharedDraft;
use super::refs::{fail, Fallible, HandleRef, PatchRef};
use super::values::{self, number};
use crate::scene::{Easing, Follow, FollowTarget, Track};
use crate::track::{FollowKey, FollowSettings, TrackFile};

const FOLLOW_OPTIONS: [&str; 5] = ["point", "offset", "rotate", "scale", "from_frame"];

pub fn register(engine: &mut Engine, draft: &SharedDraft) {
    engine.register_fn(
        "follow",
        |ctx: NativeCallContext, p: &mut PatchRef, file: &str| follow_patch(&ctx, p, file, &Map::new()),
    );
    engine.register_fn(
        "follow",
        |ctx: NativeCallContext, p: &mut PatchRef, file: &str, o: Map| follow_patch(&ctx, p, file, &o),
    );
    engine.register_fn(
        "follow",
        |ctx: NativeCallContext, h: &mut HandleRef, file: &str| follow_handle(&ctx, h, file, &Map::new()),
    );
    engine.register_fn(
        "follow",
        |ctx: NativeCallContext, h: &mut HandleRef, file: &str, o: Map| follow_handle(&ctx, h, file, &o),
    );
    let d = draft.clone();
    engine.register_fn("track_keys", move |ctx: NativeCallContext, file: &str| {
        track_keys(&ctx, &d, file, &Map::new())
    });
    let d = draft.clone();
    engine.register_fn("track_keys", move |ctx: NativeCallContext, file: &str, o: Map| {
        track_keys(&ctx, &d, file, &o)
    });
}

/// The settings a call's option map gives.
fn settings(options: &Map) -> Result<FollowSettings, String> {
    values::check_keys(options, &FOLLOW_OPTIONS, "follow")?;
    let mut s = FollowSettings::default();
    if let Some(v) = options.get("point") {
        s.point = whole(v, "point")? as usize;
    }
    if let Some(v) = options.get("offset") {
        s.offset = values::position(v, "offset")?;
    }
    let flag = |name: &str| -> Result<Option<bool>, String> {
        options
            .get(name)
            .map(|v| v.as_bool().map_err(|_| format!("`{name}` must be true or false")))
            .transpose()
    };
    s.rotate = flag("rotate")?;
    s.scale = flag("scale")?;
    if let Some(v) = options.get("from_frame") {
        s.from_frame = Some(whole(v, "from_frame")?);
    }
    Ok(s)
}

fn whole(value: &Dynamic, what: &str) -> Result<u64, String> {
    let v = number(value, what)?;
    if v.fract() != 0.0 || !(1.0..=1e9).contains(&v) {
        return Err(format!(
            "`{what}` must be a whole number ≥ 1, got {}",
            crate::util::number_text(v)
        ));
    }
    Ok(v as u64)
}

/// Reads `file` (against the scene's folder) into keys at the canvas's frame rate, and notes
/// it among the files the script read: an input of every render of the scene, even when a
/// later `follow` replaces what it keyed.
fn load_keys(
    draft: &SharedDraft,
    file: &str,
    options: &Map,
) -> Result<(std::path::PathBuf, FollowSettings, Vec<FollowKey>), String> {
    let (base_dir, fps) = context(draft);
    let settings = settings(options)?;
    let fps = fps.ok_or("call canvas(...) before reading a track: its frames become times at the canvas's fps")?;
    let path = base_dir.join(file);
    let read = &mut draft.lock().origins.read;
    if !read.contains(&path) {
        read.push(path.clone());
    }
    let track = TrackFile::load(&path).map_err(|e| e.to_string())?;
    let keys = track.follow_keys(&settings, fps)?;
    Ok((path, settings, keys))
}

/// The keys' tracks: position, and rotation and scale when they are followed.
struct Keyed {
    at: Track<DVec2>,
    rotation: Option<Track<f64>>,
    scale: Option<Track<f64>>,
}

fn keyed(keys: &[FollowKey]) -> Result<Keyed, String> {
    let mut out = Keyed {
        at: Track::new(),
        rotation: keys[0].rotate.map(|_| Track::new()),
        scale: keys[0].scale.map(|_| Track::new()),
    };
    for k in keys {
        let bad = |e: crate::scene::KeyError| e.to_string();
        out.at.push(k.t, k.at, Easing::Linear).map_err(bad)?;
        if let (Some(track), Some(r)) = (out.rotation.as_mut(), k.rotate) {
            track.push(k.t, r, Easing::Linear).map_err(bad)?;
        }
        if let (Some(track), Some(s)) = (out.scale.as_mut(), k.scale) {
            track.push(k.t, s, Easing::Linear).map_err(bad)?;
        }
    }
    Ok(out)
}

fn record(path: std::path::PathBuf, target: FollowTarget, s: &FollowSettings, k: &Keyed) -> Follow {
    Follow {
        file: path,
        target,
        point: s.point,
        offset: s.offset,
        rotate: s.rotate,
        scale: s.scale,
        from_frame: s.from_frame,
        at: k.at.clone(),
        rotation: k.rotation.clone(),
        scale_keys: k.scale.clone(),
    }
}

fn context(draft: &SharedDraft) -> (std::path::PathBuf, Option<f64>) {
    let d = draft.lock();
    (d.base_dir.clone(), d.canvas.as_ref().map(|c| c.fps))
}

fn follow_patch(ctx: &NativeCallContext, p: &mut PatchRef, file: &str, options: &Map) -> Fallible<PatchRef> {
    let (path, settings, keys) = load_keys(&p.draft, file, options).map_err(|m| fail(ctx, m))?;
    let k = keyed(&keys).map_err(|m| fail(ctx, m))?;
    p.edit(ctx, |patch| {
        patch.placement.position = k.at.clone();
        if let Some(r) = &k.rotation {
            patch.placement.rotation = r.clone();
        }
        if let Some(s) = &k.scale {
            patch.placement.scale = s.clone();
        }
        patch.follows.retain(|f| f.target != FollowTarget::Patch);
        patch.follows.push(record(path, FollowTarget::Patch, &settings, &k));
        Ok(())
    })?;
    Ok(p.clone())
}

fn follow_handle(ctx: &NativeCallContext, h: &mut HandleRef, file: &str, options: &Map) -> Fallible<HandleRef> {
    let (path, settings, keys) = load_keys(&h.draft, file, options).map_err(|m| fail(ctx, m))?;
    if settings.scale == Some(true) {
        return Err(fail(ctx, "a handle has no scale to follow: leave out `scale: true`"));
    }
    let mut k = keyed(&keys).map_err(|m| fail(ctx, m))?;
    k.scale = None;
    let mut d = h.draft.lock();
    let Some((pi, hi)) = h.indices(&d) else {
        return Err(fail(ctx, "this handle no longer exists in the scene"));
    };
    let patch = &mut d.patches[pi];
    patch.handles[hi].to = k.at.clone();
    if let Some(r) = &k.rotation {
        patch.handles[hi].rotation = r.clone();
    }
    let target = FollowTarget::Handle(hi);
    patch.follows.retain(|f| f.target != target);
    patch.follows.push(record(path, target, &settings, &k));
    Ok(h.clone())
}

/// `[#{ t, at, rotate?, scale? }, …]` for `keys(...)`.
fn track_keys(ctx: &NativeCallContext, draft: &SharedDraft, file: &str, options: &Map) -> Fallible<Array> {
    let (_, _, keys) = load_keys(draft, file, options).map_err(|m| fail(ctx, m))?;
    Ok(keys
        .iter()
        .map(|k| {
            let mut m = Map::new();
            m.insert("t".into(), Dynamic::from_float(k.t));
            let at: Array = vec![Dynamic::from_float(k.at.x), Dynamic::from_float(k.at.y)];
            m.insert("at".into(), Dynamic::from_array(at));
            if let Some(r) = k.rotate {
                m.insert("rotate".into(), Dynamic::from_float(r));
            }
            if let Some(s) = k.scale {
                m.insert("scale".into(), Dynamic::from_float(s));
            }
            Dynamic::from_map(m)
        })
        .collect())
}
