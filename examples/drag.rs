//! A drag-deformed clone: the galaxy-textured horse of `assets/horse_texture.png` cloned into
//! `assets/rocket.jpg` with its hind hoof dragged forward and its head and tail pinned (the
//! paper's Fig. 8 pose), written to the PNG named by the first argument (default
//! `drag.png`). The deformation rig and the cloner each factor their Laplacian once; a new
//! drag only switches constraints. Run: `cargo run --release --example drag -- out.png`.

use std::path::{Path, PathBuf};

use lapclone::glam::DVec2;
use lapclone::{mesh_from_mask, BitMask, Canvas, CloneOptions, DeformRig, Deformed, FloatImage};
use lapclone::{Handle, LaplacianKind, MeshOptions, PatchCloner, Pin, Placement};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or("drag.png".into()));

    let source = FloatImage::load(&assets.join("horse_texture.png"))?;
    let target = FloatImage::load(&assets.join("rocket.jpg"))?;
    let mask = BitMask::load(&assets.join("horse_mask.png"), 0.5)?;
    let size = (source.width(), source.height());
    let patch = mesh_from_mask(&mask, None, size, &MeshOptions::default())?;
    let centre = (patch.bbox_min + patch.bbox_max) / 2.0;
    let mesh = patch.result.mesh;

    // Deform in rest (source) coordinates: one drag with a 70 px falloff, two pins.
    let mut rig = DeformRig::new(&mesh, LaplacianKind::Combinatorial)?;
    let hoof = Handle::drag(DVec2::new(118.0, 298.0), DVec2::new(215.0, 175.0), 70.0);
    let pins = [Pin(DVec2::new(360.0, 70.0)), Pin(DVec2::new(30.0, 150.0))];
    let mut deformed = Deformed::default();
    let stats = rig.deform(&[hoof], &pins, &mut deformed)?;

    // Clone the deformed patch; `depth` lets the leg pass in front of the belly.
    let mut cloner = PatchCloner::new(source, mesh, &CloneOptions::default())?;
    let placement = Placement {
        scale: 0.9,
        ..Placement::translate(centre, DVec2::new(320.0, 250.0))
    };
    let mut canvas = Canvas::from_image(&target);
    cloner.clone_deformed(
        &mut canvas,
        &placement,
        &deformed.positions,
        Some(&deformed.depth),
    )?;
    canvas.save_png(&out, target.format())?;
    let moved = deformed.positions.iter().zip(&cloner.mesh().positions);
    let furthest = moved.map(|(d, r)| d.distance(*r)).fold(0.0, f64::max);
    println!(
        "deformed {} vertices ({} constrained, furthest moved {furthest:.1} px) into {}",
        deformed.positions.len(),
        stats.constrained,
        out.display()
    );
    Ok(())
}
