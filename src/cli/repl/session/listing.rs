//! What the session shows about its scene: the `:list` text (canvas, patches with their
//! keys, handles and pins, layer order, variables), the `:keys NAME` table and `:stats`.

use lapclone::util::ShowPath;
use std::path::Path;

use lapclone::scene::{Background, Canvas as SceneCanvas, Patch, Scene, Shape};
use lapclone::script::Draft;

use super::Session;
use crate::cli::repl::keys::key_table;

impl Session {
    /// The `:keys NAME` table.
    pub(super) fn keys(&self, name: &str) -> anyhow::Result<String> {
        let draft = self.engine.draft();
        let patch = draft
            .patches
            .iter()
            .find(|p| p.name == name)
            .ok_or_else(|| anyhow::anyhow!(draft.no_patch_message(name)))?;
        Ok(key_table(patch))
    }

    pub(super) fn stats(&self) -> anyhow::Result<String> {
        let renderer = self.renderer()?;
        let s = renderer.last_stats();
        let mut out = format!(
            "t = {} s: {:.2} ms total (deform {:.2}, solve {:.2}, raster {:.2}); \
             switches: {} deform, {} clone; boundary hidden {}, outside {}, glued {}\n",
            lapclone::util::number_text(s.time),
            s.total_ms,
            s.deform_ms,
            s.solve_ms,
            s.raster_ms,
            s.deform_switches,
            s.clone_switches,
            s.hidden,
            s.outside,
            s.glued
        );
        let vertices = renderer.vertex_counts();
        out.push_str(&format!("mesh vertices per patch: {vertices:?}\n"));
        if let Some(u) = self.last_update {
            out.push_str(&format!(
                "last edit: {} layer(s) kept, {} rebuilt, {} dropped, {} rig(s) built\n",
                u.reused, u.rebuilt, u.dropped, u.rigs_built
            ));
        }
        Ok(out)
    }

    /// The `:list` text: canvas, patches with their keys, handles and pins, and variables.
    pub fn listing(&self) -> String {
        let draft = self.engine.draft();
        let mut out = String::new();
        match &draft.canvas {
            Some(c) => out.push_str(&canvas_line(c)),
            None => out.push_str("no canvas yet\n"),
        }
        for patch in &draft.patches {
            out.push_str(&patch_lines(patch));
        }
        out.push_str(&layer_order(&draft, self.time));
        let variables = self.visible_variables();
        let names: Vec<&str> = variables.iter().map(|(name, _)| *name).collect();
        if !names.is_empty() {
            out.push_str(&format!("variables: {}\n", names.join(", ")));
        }
        out
    }
}

/// `canvas 600×400, 24 fps, 3 s (72 frames), background coffee.png`.
fn canvas_line(c: &SceneCanvas) -> String {
    let background = match &c.background {
        Background::Image(path) => short(path),
        Background::Colour(rgba) => format!("colour {rgba:?}"),
        Background::Footage(f) => format!("footage {}", f.describe()),
    };
    format!(
        "canvas {}×{}, {} fps, {} s ({} frames), background {background}\n",
        c.width,
        c.height,
        c.fps,
        c.duration,
        c.frame_count()
    )
}

/// A patch's `:list` lines: its settings, its key counts, its handles and pins.
fn patch_lines(patch: &Patch) -> String {
    let shape = match &patch.shape {
        Shape::Mask(path) => format!("mask {}", short(path)),
        Shape::Polygons(p) => format!("{} polygon(s)", p.len()),
    };
    let mut out = format!(
        "patch \"{}\": source {}, {shape}, {:?}, {:?}, feather {}, boundary data {}, \
         boundary {}\n",
        patch.name,
        short(&patch.source),
        patch.laplacian,
        patch.mode,
        patch.feather,
        patch.boundary_data.name(),
        patch.boundary.name()
    );
    let p = &patch.placement;
    out.push_str(&format!(
        "  keys: position {}, scale {}, rotation {}, depth {}, opacity {}\n",
        p.position.keys().len(),
        p.scale.keys().len(),
        p.rotation.keys().len(),
        p.depth.keys().len(),
        p.opacity.keys().len()
    ));
    for (i, h) in patch.handles.iter().enumerate() {
        out.push_str(&format!(
            "  handle {i}: from [{}, {}], radius {}, {} key(s)\n",
            h.from.x,
            h.from.y,
            h.radius,
            h.to.keys().len()
        ));
    }
    for (i, pin) in patch.pins.iter().enumerate() {
        let end = pin.end.map_or("end".to_string(), |e| format!("{e} s"));
        out.push_str(&format!(
            "  pin {i}: at [{}, {}], {} s to {end}\n",
            pin.at.x, pin.at.y, pin.start
        ));
    }
    out
}

/// `layers at t = 1.5 s, back to front: horse, cat (opacity 0.5)`.
fn layer_order(draft: &Draft, t: f64) -> String {
    let Some(canvas) = draft.canvas.clone() else {
        return String::new();
    };
    if draft.patches.is_empty() {
        return String::new();
    }
    let scene = Scene {
        canvas,
        patches: draft.patches.clone(),
        golden: None,
    };
    let state = scene.evaluate(t);
    let layers: Vec<String> = state
        .draw_order
        .iter()
        .map(|&i| {
            let (patch, s) = (&scene.patches[i], &state.patches[i]);
            let mut text = format!("{:?} (depth {}", patch.name, s.depth);
            if s.opacity < 1.0 {
                text.push_str(&format!(", opacity {}", s.opacity));
            }
            text + ")"
        })
        .collect();
    format!(
        "layers at t = {} s, back to front: {}\n",
        lapclone::util::number_text(t),
        layers.join(", ")
    )
}

fn short(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.shown().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}
