//! Footage through the library API alone (no scene file): a scene built in Rust with a
//! three-plate background sequence and a patch whose source alternates between two frames
//! renders frame i over plate i, the patch alternating with it, on one factorisation.

use std::path::Path;

use lapclone::animation::{
    Background, Footage, FootageSource, Patch, Pattern, Scene, SceneCanvas, Shape, Track,
};
use lapclone::glam::DVec2;
use lapclone::{Polygon, Renderer};

const W: u32 = 96;
const H: u32 = 64;

/// Plate `k`: every pixel differs from the other plates'.
fn plate(k: u32) -> image::RgbImage {
    image::RgbImage::from_fn(W, H, |x, y| {
        let v = x * 5 + y * 11 + k * 60;
        image::Rgb([
            (v % 241) as u8,
            ((v * 7 + k * 31) % 239) as u8,
            (k * 70 + 30) as u8,
        ])
    })
}

/// Source frame `k` (40×36): a ramp, inverted on odd frames.
fn source_frame(k: u32) -> image::RgbImage {
    image::RgbImage::from_fn(40, 36, |x, y| {
        let v = [(x * 6) as u8, (y * 7) as u8, ((x + y) * 3) as u8];
        image::Rgb(if k % 2 == 1 { v.map(|c| 255 - c) } else { v })
    })
}

fn write_inputs(dir: &Path) {
    for k in 0..3 {
        plate(k)
            .save(dir.join(format!("plate_{:03}.png", k + 5)))
            .unwrap();
        source_frame(k)
            .save(dir.join(format!("src_{}.png", k + 1)))
            .unwrap();
    }
}

/// The scene: plates from number 5 on (found, not given), a triangle of the animated
/// source placed with its bounding-box centre at (30, 24).
fn scene(dir: &Path) -> Scene {
    let plates = Footage::open(&dir.join("plate_%03d.png"), None, false, "plates_hold").unwrap();
    assert_eq!((plates.width, plates.height), (W, H));
    let FootageSource::Sequence { pattern, start } = &plates.source else {
        panic!("a pattern is a sequence: {:?}", plates.source);
    };
    assert_eq!(*start, 5);
    assert_eq!(pattern.path(6), dir.join("plate_006.png"));
    let parsed = Pattern::parse(&dir.join("plate_%03d.png")).unwrap();
    assert_eq!(parsed.as_ref(), Some(pattern));

    let triangle = Polygon {
        outer: vec![
            DVec2::new(4.0, 4.0),
            DVec2::new(36.0, 6.0),
            DVec2::new(14.0, 32.0),
        ],
        holes: Vec::new(),
    };
    let mut patch = Patch::new("p", dir.join("src_1.png"), Shape::Polygons(vec![triangle]));
    patch.footage = Some(Footage::open(&dir.join("src_%d.png"), Some(1), false, "hold").unwrap());
    patch.placement.position = Track::constant(DVec2::new(30.0, 24.0));
    let canvas = SceneCanvas {
        width: plates.width,
        height: plates.height,
        fps: 3.0,
        duration: 1.0,
        background: Background::Footage(plates),
    };
    Scene::new(canvas, vec![patch])
}

/// Whether (x, y) may be touched by the patch: its bounding box, about 32×28 around
/// (30, 24), with a margin.
fn near_patch(x: u32, y: u32) -> bool {
    (8..=52).contains(&x) && (4..=44).contains(&y)
}

#[test]
fn a_rust_scene_renders_each_frame_over_its_plate_with_an_alternating_source() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let mut renderer = Renderer::new(scene(dir.path())).unwrap();
    assert_eq!(renderer.frame_count(), 3);
    let frames: Vec<image::RgbaImage> = (0..3)
        .map(|i| renderer.render_frame(i).unwrap().to_rgba8_image())
        .collect();
    assert_eq!(renderer.factorisations(), 1);
    for (i, frame) in frames.iter().enumerate() {
        let expected = plate(i as u32);
        let mut compared = 0;
        for (x, y, px) in frame.enumerate_pixels() {
            if !near_patch(x, y) {
                let e = expected.get_pixel(x, y).0;
                assert_eq!(px.0, [e[0], e[1], e[2], 255], "frame {i} at ({x}, {y})");
                compared += 1;
            }
        }
        assert!(compared > 4000, "{compared}");
    }
    // The patch shows its own source frame: source frames 1 and 3 are the still source,
    // frame 2 its inversion. So frames 0 and 2 equal a render with the still source, and
    // frame 1 differs from it inside the patch only.
    let mut still = scene(dir.path());
    still.patches[0].footage = None;
    let mut still = Renderer::new(still).unwrap();
    let still: Vec<image::RgbaImage> = (0..3)
        .map(|i| still.render_frame(i).unwrap().to_rgba8_image())
        .collect();
    assert_eq!(frames[0], still[0]);
    assert_eq!(frames[2], still[2]);
    let differing: Vec<(u32, u32)> = frames[1]
        .enumerate_pixels()
        .filter(|&(x, y, px)| px != still[1].get_pixel(x, y))
        .map(|(x, y, _)| (x, y))
        .collect();
    assert!(differing.len() > 300, "{}", differing.len());
    assert!(differing.iter().all(|&(x, y)| near_patch(x, y)));
}

#[test]
fn footage_errors_are_typed_and_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let error = Footage::open(&dir.path().join("plate.png"), None, false, "hold").unwrap_err();
    assert!(
        matches!(error, lapclone::FootageError::NoNumber(_)),
        "{error}"
    );
    let error = Footage::open(&dir.path().join("shot_%03d.png"), None, false, "hold").unwrap_err();
    assert!(
        matches!(error, lapclone::FootageError::NoFiles { .. }),
        "{error}"
    );
    // Four frames of three plates: refused before drawing, naming the missing file.
    let mut scene = scene(dir.path());
    scene.canvas.duration = 4.0 / 3.0;
    let error = Renderer::new(scene).err().expect("too few plates");
    assert!(error.to_string().contains("plate_008.png"), "{error}");
}

#[test]
#[allow(deprecated)]
fn the_old_animation_names_still_name_the_scene_types() {
    use lapclone::animation::{Canvas, Placement, ScenePlacement};
    let placement: ScenePlacement = Placement::default();
    assert_eq!(placement, ScenePlacement::default());
    let canvas: SceneCanvas = Canvas {
        width: W,
        height: H,
        fps: 3.0,
        duration: 1.0,
        background: Background::Colour([0.0, 0.0, 0.0, 1.0]),
    };
    assert_eq!(canvas.frame_count(), 3);
}
