//! A scene built in Rust (no Rhai): a cat's face drifting and growing in the espresso of
//! `assets/coffee.png` for one second at 8 frames per second, rendered to PNG frames
//! `frame_0001.png …` in the folder named by the first argument (default `scene_frames`,
//! created if missing). Run: `cargo run --release --example scene_frames -- out/frames`.

use std::path::{Path, PathBuf};

use lapclone::animation::{Background, Easing, Patch, Scene, SceneCanvas, Shape, Track};
use lapclone::glam::DVec2;
use lapclone::Renderer;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let folder = PathBuf::from(std::env::args().nth(1).unwrap_or("scene_frames".into()));
    std::fs::create_dir_all(&folder)?;

    let mut face = Patch::new(
        "cat",
        assets.join("chelsea.png"),
        Shape::Mask(assets.join("masks/chelsea_face.png")),
    );
    // Keys: position slides right and scale grows, both easing in and out.
    face.placement.position = Track::new();
    face.placement
        .position
        .push(0.0, DVec2::new(262.0, 150.0), Easing::Linear)?;
    face.placement
        .position
        .push(1.0, DVec2::new(302.0, 140.0), Easing::Smooth)?;
    face.placement.scale = Track::new();
    face.placement.scale.push(0.0, 0.32, Easing::Linear)?;
    face.placement.scale.push(1.0, 0.42, Easing::Smooth)?;

    let coffee = image::image_dimensions(assets.join("coffee.png"))?;
    let canvas = SceneCanvas {
        width: coffee.0,
        height: coffee.1,
        fps: 8.0,
        duration: 1.0,
        background: Background::Image(assets.join("coffee.png")),
    };
    let scene = Scene::new(canvas, vec![face]);

    let mut renderer = Renderer::new(scene)?;
    let format = renderer.output_format();
    for index in 0..renderer.frame_count() {
        let path = folder.join(format!("frame_{:04}.png", index + 1));
        renderer.render_frame(index)?.save_png(&path, format)?;
    }
    println!(
        "wrote {} frames to {}",
        renderer.frame_count(),
        folder.display()
    );
    Ok(())
}
