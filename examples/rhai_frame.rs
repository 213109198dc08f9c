//! A `.rhai` scene loaded and one frame rendered into an `image::RgbaImage`: the bundled
//! `scenes/cat_in_coffee.rhai` at t = 1 s (or the scene file and time given as arguments).
//! Prints the frame's size and a checksum of its pixels, which is the same on every run.
//! Run: `cargo run --release --example rhai_frame -- scenes/cat_in_coffee.rhai 1.0`.

use std::path::PathBuf;

use lapclone::{load_scene, Renderer};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let default = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cat_in_coffee.rhai");
    let file = PathBuf::from(args.next().unwrap_or(default.into()));
    let t: f64 = args.next().map_or(Ok(1.0), |text| text.parse())?;

    // Errors carry `file:line:col` and the offending source line.
    let loaded = load_scene(&file)?;
    let mut renderer = Renderer::new(loaded.scene)?;
    let frame: image::RgbaImage = renderer.render_time(t)?.to_rgba8_image();

    // FNV-1a over the pixels: a short, deterministic fingerprint of the frame.
    let checksum = frame
        .as_raw()
        .iter()
        .fold(0xcbf2_9ce4_8422_2325_u64, |hash, &byte| {
            (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3)
        });
    println!(
        "{}: frame at t = {t} s is {}x{}, checksum {checksum:016x}",
        file.display(),
        frame.width(),
        frame.height()
    );
    Ok(())
}
