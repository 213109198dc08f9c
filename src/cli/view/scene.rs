//! The scene message a page draws its overlays and timeline from: takes the renderer (its
//! scene, placed meshes and pivots) and the session's playhead and revision, and gives JSON
//! — each patch's placement at the playhead, key times per track, handles, pins, the path
//! of a followed track and, for pages with the mesh overlay on, the placed meshes. Also where a canvas point falls: the
//! patch drawn on top there and the source (rest) point under it.

use glam::DVec2;
use lapclone::render::Renderer;
use lapclone::scene::{Follow, FollowTarget, Patch, PatchState, Track};
use serde_json::{json, Value};

/// The session facts a scene message carries besides the renderer's.
pub struct Playhead<'a> {
    pub time: f64,
    pub revision: u64,
    /// The loaded file's name (for the page's title and its save confirmation).
    pub file: Option<&'a str>,
}

/// The scene message, with the placed meshes when `mesh`.
pub fn scene_message(renderer: &Renderer, head: &Playhead, mesh: bool) -> String {
    let scene = renderer.scene();
    let canvas = &scene.canvas;
    let state = scene.evaluate(head.time);
    let pivots = renderer.pivots();
    let meshes = renderer.placed_meshes();
    let patches: Vec<Value> = scene
        .patches
        .iter()
        .zip(&state.patches)
        .zip(pivots.iter().zip(&meshes))
        .map(|((patch, s), (&pivot, placed))| patch_json(patch, s, pivot, placed.placed, head.time))
        .collect();
    let frame = (head.time * canvas.fps + 1e-9).floor() as u64 + 1;
    let mut message = json!({
        "type": "scene",
        "rev": head.revision,
        "t": head.time,
        "frame": frame,
        "frames": canvas.frame_count(),
        "fps": canvas.fps,
        "duration": canvas.duration,
        "width": canvas.width,
        "height": canvas.height,
        "file": head.file,
        "draw_order": state.draw_order,
        "patches": patches,
    });
    if mesh {
        let meshes: Vec<Value> = meshes
            .iter()
            .filter(|m| m.placed.len() == m.mesh.vertex_count())
            .map(|m| {
                let points: Vec<f64> = m.placed.iter().flat_map(|p| [r2(p.x), r2(p.y)]).collect();
                let triangles: Vec<u32> = m.mesh.triangles.iter().flatten().copied().collect();
                json!({ "name": m.name, "points": points, "triangles": triangles })
            })
            .collect();
        message["meshes"] = Value::from(meshes);
    }
    message.to_string()
}

fn patch_json(patch: &Patch, s: &PatchState, pivot: DVec2, placed: &[DVec2], t: f64) -> Value {
    let at = s.position.unwrap_or(pivot);
    let bbox = placed.iter().fold(None, |b: Option<[f64; 4]>, p| {
        Some(match b {
            None => [p.x, p.y, p.x, p.y],
            Some([a, b, c, d]) => [a.min(p.x), b.min(p.y), c.max(p.x), d.max(p.y)],
        })
    });
    let p = &patch.placement;
    let handles: Vec<Value> = patch
        .handles
        .iter()
        .zip(&s.handles)
        .enumerate()
        .map(|(i, (h, hs))| {
            json!({
                "from": xy(h.from),
                "to": xy(hs.to),
                "radius": h.radius,
                "keys": { "at": times(&h.to), "rotate": times(&h.rotation) },
                "follow": follow_json(patch, FollowTarget::Handle(i), t),
            })
        })
        .collect();
    let pins: Vec<Value> = patch
        .pins
        .iter()
        .map(|pin| json!({ "at": xy(pin.at), "start": pin.start, "end": pin.end }))
        .collect();
    json!({
        "name": patch.name,
        "at": xy(at),
        "scale": s.scale,
        "rotation": s.rotation,
        "depth": s.depth,
        "opacity": s.opacity,
        "pivot": xy(pivot),
        "bbox": bbox,
        "keys": {
            "at": times(&p.position),
            "scale": times(&p.scale),
            "rotate": times(&p.rotation),
            "depth": times(&p.depth),
            "opacity": times(&p.opacity),
        },
        "handles": handles,
        "pins": pins,
        "follow": follow_json(patch, FollowTarget::Patch, t),
    })
}

/// The path of the track `target` follows, if its keys are still in place: the file, the
/// followed positions (canvas points for a patch, source points for a handle's target, as
/// the handle's `to` is) and the index of the last one at or before the playhead `t`.
fn follow_json(patch: &Patch, target: FollowTarget, t: f64) -> Value {
    let Some(follow) = patch.intact_follows(target).last() else {
        return Value::Null;
    };
    let keys = follow.at.keys();
    let path: Vec<[f64; 2]> = keys
        .iter()
        .map(|k| [r2(k.value.x), r2(k.value.y)])
        .collect();
    let current = keys.iter().rposition(|k| k.time <= t + 1e-9).unwrap_or(0);
    json!({
        "file": Follow::file_name(follow),
        "keys": keys.len(),
        "path": path,
        "current": current,
    })
}

fn times<T: lapclone::scene::Interpolate>(track: &Track<T>) -> Vec<f64> {
    track.keys().iter().map(|k| k.time).collect()
}

fn xy(p: DVec2) -> [f64; 2] {
    [p.x, p.y]
}

fn r2(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

/// The patch drawn on top at canvas point `p` in the last frame and the source point that
/// landed there (through its placed mesh, so deformation is included).
pub fn locate(renderer: &Renderer, time: f64, p: DVec2) -> Option<(String, DVec2)> {
    let order = renderer.scene().evaluate(time).draw_order;
    let meshes = renderer.placed_meshes();
    order.iter().rev().find_map(|&i| {
        let m = meshes.get(i)?;
        if m.placed.len() != m.mesh.vertex_count() {
            return None;
        }
        m.mesh.triangles.iter().find_map(|t| {
            let [a, b, c] = t.map(|v| v as usize);
            let w = barycentric(p, m.placed[a], m.placed[b], m.placed[c])?;
            let rest = m.mesh.positions[a] * w[0]
                + m.mesh.positions[b] * w[1]
                + m.mesh.positions[c] * w[2];
            Some((m.name.to_string(), rest))
        })
    })
}

/// Barycentric weights of `p` in triangle `abc`, if it lies inside (edges included).
fn barycentric(p: DVec2, a: DVec2, b: DVec2, c: DVec2) -> Option<[f64; 3]> {
    let area = (b - a).perp_dot(c - a);
    if area.abs() < 1e-12 {
        return None;
    }
    let u = (c - b).perp_dot(p - b) / area;
    let v = (a - c).perp_dot(p - c) / area;
    let w = 1.0 - u - v;
    let eps = -1e-9;
    (u >= eps && v >= eps && w >= eps).then_some([u, v, w])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentric_weights_rebuild_the_point() {
        let (a, b, c) = (
            DVec2::new(0.0, 0.0),
            DVec2::new(4.0, 0.0),
            DVec2::new(0.0, 4.0),
        );
        let p = DVec2::new(1.0, 2.0);
        let w = barycentric(p, a, b, c).unwrap();
        assert!((a * w[0] + b * w[1] + c * w[2] - p).length() < 1e-12);
        assert!(barycentric(DVec2::new(3.0, 3.0), a, b, c).is_none());
    }
}
