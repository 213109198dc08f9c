//! The smallest seamless clone: the cat's face from `assets/chelsea.png` into the espresso
//! of `assets/coffee.png`, written to the PNG named by the first argument (default
//! `minimal.png`). Run: `cargo run --release --example minimal -- out.png`.

use std::path::{Path, PathBuf};

use lapclone::glam::DVec2;
use lapclone::{mesh_from_mask, BitMask, Canvas, CloneOptions, FloatImage, MeshOptions};
use lapclone::{PatchCloner, Placement};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or("minimal.png".into()));

    let source = FloatImage::load(&assets.join("chelsea.png"))?;
    let target = FloatImage::load(&assets.join("coffee.png"))?;
    let mask = BitMask::load(&assets.join("masks/chelsea_face.png"), 0.5)?;

    // Mesh the mask once; the cloner factors the mesh's Laplacian once.
    let size = (source.width(), source.height());
    let patch = mesh_from_mask(&mask, None, size, &MeshOptions::default())?;
    let centre = (patch.bbox_min + patch.bbox_max) / 2.0;
    let mut cloner = PatchCloner::new(source, patch.result.mesh, &CloneOptions::default())?;

    // Put the face's centre at (288, 143) in the target, at 42 % of its size.
    let placement = Placement {
        scale: 0.42,
        ..Placement::translate(centre, DVec2::new(288.0, 143.0))
    };
    let mut canvas = Canvas::from_image(&target);
    cloner.clone_onto(&mut canvas, &placement)?;
    canvas.save_png(&out, target.format())?;
    println!(
        "cloned a {}-vertex patch into {}",
        cloner.mesh().vertex_count(),
        out.display()
    );
    Ok(())
}
