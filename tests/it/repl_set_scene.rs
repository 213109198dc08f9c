//! `Renderer::set_scene`, the REPL's re-solve after an edit: kept layers (no re-mesh, no
//! refactor) must render frame-identically to a fresh `Renderer::new` of the edited scene;
//! changed mesh settings rebuild, removed patches drop, a first handle builds a rig.

use std::path::Path;

use glam::DVec2;
use lapclone::render::{Renderer, SceneUpdate};
use lapclone::scene::{
    Background, BoundaryData, BoundaryPlacement, Canvas, Easing, Handle, Patch, Polygon, Scene,
    Shape, Track,
};

fn patch(name: &str, corner: DVec2) -> Patch {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/chelsea.png");
    let ring = [[0.0, 0.0], [30.0, 0.0], [34.0, 28.0], [4.0, 30.0]]
        .map(|[x, y]| corner + DVec2::new(x, y))
        .to_vec();
    let mut p = Patch::new(
        name,
        source,
        Shape::Polygons(vec![Polygon {
            outer: ring,
            holes: vec![],
        }]),
    );
    p.placement
        .position
        .push(0.0, DVec2::new(30.0, 24.0), Easing::Linear)
        .unwrap();
    p
}

fn scene() -> Scene {
    Scene {
        canvas: Canvas {
            width: 64,
            height: 48,
            fps: 6.0,
            duration: 1.0,
            background: Background::Colour([0.1, 0.2, 0.3, 1.0]),
        },
        patches: vec![
            patch("a", DVec2::new(150.0, 60.0)),
            patch("b", DVec2::new(60.0, 100.0)),
        ],
        golden: None,
    }
}

/// Renders `frame` of `edited` with a renderer that first showed `frame` of `original`,
/// then switched, and with a fresh renderer; gives the update and whether pixels match.
fn switch_and_compare(original: Scene, edited: Scene, frame: u64) -> (SceneUpdate, bool) {
    let mut live = Renderer::new(original).unwrap();
    live.render_frame(frame).unwrap();
    let update = live.set_scene(edited.clone()).unwrap();
    let live_frame = live.render_frame(frame).unwrap().to_rgba8_image();
    let mut fresh = Renderer::new(edited).unwrap();
    let fresh_frame = fresh.render_frame(frame).unwrap().to_rgba8_image();
    (update, live_frame == fresh_frame)
}

#[test]
fn a_keyframe_edit_keeps_every_layer_and_matches_a_fresh_renderer() {
    let mut edited = scene();
    edited.patches[0]
        .placement
        .position
        .push(0.5, DVec2::new(40.0, 20.0), Easing::EaseInOut)
        .unwrap();
    edited.patches[1].placement.rotation = Track::constant(12.0);
    let (update, same) = switch_and_compare(scene(), edited, 2);
    assert_eq!(update.reused, 2);
    assert_eq!(update.rebuilt, 0);
    assert_eq!(update.dropped, 0);
    assert!(!update.background_changed);
    assert!(same, "kept layers must render like fresh ones");
}

#[test]
fn changed_mesh_settings_rebuild_only_that_patch() {
    let mut edited = scene();
    edited.patches[1].feather = 2.0;
    edited.canvas.background = Background::Colour([0.5, 0.5, 0.5, 1.0]);
    let (update, same) = switch_and_compare(scene(), edited, 1);
    assert_eq!((update.reused, update.rebuilt, update.dropped), (1, 1, 1));
    assert!(update.background_changed);
    assert!(same);
}

#[test]
fn a_changed_boundary_data_rebuilds_that_patch() {
    let mut edited = scene();
    edited.patches[0].boundary_data = BoundaryData::Vertex;
    let (update, same) = switch_and_compare(scene(), edited, 1);
    assert_eq!((update.reused, update.rebuilt, update.dropped), (1, 1, 1));
    assert!(same, "the rebuilt layer must render like a fresh one");
}

#[test]
fn a_changed_boundary_rebuilds_that_patch() {
    let mut edited = scene();
    edited.patches[0].boundary = BoundaryPlacement::Cracks;
    let (update, same) = switch_and_compare(scene(), edited, 1);
    assert_eq!((update.reused, update.rebuilt, update.dropped), (1, 1, 1));
    assert!(same, "the rebuilt layer must render like a fresh one");
}

#[test]
fn removed_patches_drop_and_renamed_ones_keep_their_layer() {
    let mut edited = scene();
    edited.patches.remove(0);
    edited.patches[0].name = "renamed".into();
    let (update, same) = switch_and_compare(scene(), edited.clone(), 0);
    assert_eq!((update.reused, update.rebuilt, update.dropped), (1, 0, 1));
    assert!(same);
    // A new patch with the settings of a kept one still gets its own layer.
    edited.patches.push(patch("b", DVec2::new(60.0, 100.0)));
    let (update, same) = switch_and_compare(scene(), edited, 0);
    assert_eq!((update.reused, update.rebuilt, update.dropped), (1, 1, 1));
    assert!(same);
}

#[test]
fn a_first_handle_builds_a_rig_lazily() {
    let mut edited = scene();
    let mut to = Track::new();
    to.push(0.0, DVec2::new(165.0, 75.0), Easing::Linear)
        .unwrap();
    to.push(0.5, DVec2::new(170.0, 70.0), Easing::Smooth)
        .unwrap();
    edited.patches[0].handles.push(Handle {
        from: DVec2::new(165.0, 75.0),
        to,
        radius: 8.0,
        depth: None,
        pivot: None,
        rotation: Track::new(),
    });
    let mut live = Renderer::new(scene()).unwrap();
    assert_eq!(live.rigs_built(), [false, false]);
    live.render_frame(0).unwrap();
    let update = live.set_scene(edited.clone()).unwrap();
    assert_eq!((update.reused, update.rigs_built), (2, 1));
    assert_eq!(live.rigs_built(), [true, false]);
    let live_frame = live.render_frame(2).unwrap().to_rgba8_image();
    let fresh_frame = Renderer::new(edited)
        .unwrap()
        .render_frame(2)
        .unwrap()
        .to_rgba8_image();
    assert!(live_frame == fresh_frame);
}

#[test]
fn a_failed_switch_leaves_the_renderer_as_it_was() {
    let mut live = Renderer::new(scene()).unwrap();
    let before = live.render_frame(1).unwrap().to_rgba8_image();
    let mut broken = scene();
    broken.patches[1].source = "/nonexistent/picture.png".into();
    assert!(live.set_scene(broken).is_err());
    assert_eq!(live.scene(), &scene());
    assert!(live.render_frame(1).unwrap().to_rgba8_image() == before);
}

#[test]
fn placed_meshes_follow_the_last_frame() {
    let mut live = Renderer::new(scene()).unwrap();
    live.render_frame(0).unwrap();
    let placed = live.placed_meshes();
    assert_eq!(placed.len(), 2);
    for p in &placed {
        assert_eq!(p.placed.len(), p.mesh.vertex_count());
        let centre = p.placed.iter().sum::<DVec2>() / p.placed.len() as f64;
        assert!(
            (centre - DVec2::new(30.0, 24.0)).length() < 6.0,
            "{}: {centre}",
            p.name
        );
    }
}

/// `Renderer::drawn_region`, what the live view compares: every frame of the demo scenes
/// (deformation with folds, several layers, translucent layers) equals the background outside
/// its drawn rectangle, and the background's number holds while the background does — across
/// frames and an edit that keeps it — and changes with it.
#[test]
fn drawn_region_bounds_where_a_frame_differs_from_its_background() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for name in ["horse_gallop", "two_layers", "ring_slide"] {
        let (loaded, mut renderer) =
            lapclone::open_scene(&scenes.join(format!("{name}.rhai"))).unwrap();
        let mut bare = loaded.scene.clone();
        bare.patches.clear();
        let background = Renderer::new(bare)
            .unwrap()
            .render_frame(0)
            .unwrap()
            .clone();
        let mut numbers = Vec::new();
        for frame in (0..renderer.frame_count()).step_by(5) {
            let canvas = renderer.render_frame(frame).unwrap().clone();
            let region = renderer.drawn_region().unwrap();
            assert!(
                !region.rect.is_empty(),
                "{name} frame {frame}: nothing drawn"
            );
            let outside = differing_pixels(&canvas, &background)
                .into_iter()
                .filter(|&(x, y)| {
                    let r = region.rect;
                    !(r.x0 <= x && x < r.x1 && r.y0 <= y && y < r.y1)
                })
                .count();
            assert_eq!(
                outside, 0,
                "{name} frame {frame}: pixels changed outside {region:?}"
            );
            numbers.push(region.background);
        }
        numbers.dedup();
        assert_eq!(numbers.len(), 1, "{name}: the background's number changed");
        // An edit that keeps the background keeps its number; a new background gets another.
        let mut edited = loaded.scene.clone();
        edited.patches.truncate(1);
        renderer.set_scene(edited.clone()).unwrap();
        renderer.render_frame(0).unwrap();
        assert_eq!(
            renderer.drawn_region().unwrap().background,
            numbers[0],
            "{name}"
        );
        edited.canvas.background = Background::Colour([0.5, 0.1, 0.1, 1.0]);
        renderer.set_scene(edited).unwrap();
        renderer.render_frame(0).unwrap();
        assert_ne!(
            renderer.drawn_region().unwrap().background,
            numbers[0],
            "{name}"
        );
    }
}

/// The (x, y) of every pixel where two canvases of one size differ.
fn differing_pixels(a: &lapclone::Canvas, b: &lapclone::Canvas) -> Vec<(i32, i32)> {
    let (a, b) = (a.to_rgba8_image(), b.to_rgba8_image());
    a.enumerate_pixels()
        .zip(b.pixels())
        .filter(|((_, _, p), q)| p != q)
        .map(|((x, y, _), _)| (x as i32, y as i32))
        .collect()
}

/// `Renderer::set_raster_threads`, which the REPL's session turns up to every core: the demo
/// scenes (a leg folding over the body, several layers, translucent ones) render the same
/// bytes on one, two and three shading threads, frame after frame.
#[test]
fn raster_threads_render_the_same_frames() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for name in ["horse_gallop", "two_layers", "ring_slide"] {
        let path = scenes.join(format!("{name}.rhai"));
        let renderers = [1, 2, 3].map(|threads| {
            let (_, mut renderer) = lapclone::open_scene(&path).unwrap();
            renderer.set_raster_threads(threads);
            renderer
        });
        let [mut one, mut two, mut three] = renderers;
        let frames = one.frame_count();
        let mut compared = 0;
        for index in (0..frames).step_by(((frames / 6) as usize).max(1)) {
            let single = one.render_frame(index).unwrap();
            for other in [&mut two, &mut three] {
                let frame = other.render_frame(index).unwrap();
                assert!(
                    differing_pixels(single, frame).is_empty(),
                    "{name} frame {index}"
                );
            }
            compared += 1;
        }
        assert!(compared >= 6, "{name}: {compared} frames compared");
    }
}
