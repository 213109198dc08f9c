//! One meaning of a mask everywhere: takes masks in grey, RGB, grey+alpha and RGBA at 8 and
//! 16 bits whose colour and alpha disagree, and gives what `lapclone clone`, `check` and
//! `render` make of each, which must agree (alpha decides when there is alpha, else luma).

use std::path::{Path, PathBuf};
use std::process::Command;

use image::{DynamicImage, ImageBuffer, Luma, LumaA, Rgb, Rgba};

const SIZE: u32 = 48;

/// Inside by alpha (or by luma without alpha): the square [12, 36)².
fn in_square(x: u32, y: u32) -> bool {
    (12..36).contains(&x) && (12..36).contains(&y)
}

fn masks() -> Vec<(&'static str, DynamicImage)> {
    let luma8 = |x, y| if in_square(x, y) { 255u8 } else { 0 };
    let luma16 = |x, y| if in_square(x, y) { 65535u16 } else { 0 };
    // With alpha the colour disagrees: black (no inside by luma) at 8 bits, white on the
    // left half at 16.
    let colour8 = |_: u32| 0u8;
    let colour16 = |x: u32| if x < SIZE / 2 { 65535u16 } else { 0 };
    vec![
        (
            "grey8",
            DynamicImage::ImageLuma8(ImageBuffer::from_fn(SIZE, SIZE, |x, y| Luma([luma8(x, y)]))),
        ),
        (
            "rgb8",
            DynamicImage::ImageRgb8(ImageBuffer::from_fn(SIZE, SIZE, |x, y| {
                Rgb([luma8(x, y); 3])
            })),
        ),
        (
            "grey_alpha8",
            DynamicImage::ImageLumaA8(ImageBuffer::from_fn(SIZE, SIZE, |x, y| {
                LumaA([colour8(x), luma8(x, y)])
            })),
        ),
        (
            "rgba8",
            DynamicImage::ImageRgba8(ImageBuffer::from_fn(SIZE, SIZE, |x, y| {
                let c = colour8(x);
                Rgba([c, c, c, luma8(x, y)])
            })),
        ),
        (
            "grey16",
            DynamicImage::ImageLuma16(ImageBuffer::from_fn(SIZE, SIZE, |x, y| {
                Luma([luma16(x, y)])
            })),
        ),
        (
            "rgb16",
            DynamicImage::ImageRgb16(ImageBuffer::from_fn(SIZE, SIZE, |x, y| {
                Rgb([luma16(x, y); 3])
            })),
        ),
        (
            "grey_alpha16",
            DynamicImage::ImageLumaA16(ImageBuffer::from_fn(SIZE, SIZE, |x, y| {
                LumaA([colour16(x), luma16(x, y)])
            })),
        ),
        (
            "rgba16",
            DynamicImage::ImageRgba16(ImageBuffer::from_fn(SIZE, SIZE, |x, y| {
                let c = colour16(x);
                Rgba([c, c, c, luma16(x, y)])
            })),
        ),
    ]
}

fn lapclone(args: &[&std::ffi::OsStr]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(args)
        .output()
        .unwrap();
    let text = |b: Vec<u8>| String::from_utf8(b).unwrap();
    (
        out.status.code().unwrap(),
        text(out.stdout),
        text(out.stderr),
    )
}

/// The source and target: smooth, different gradients so the clone changes pixels.
fn write_images(dir: &Path) -> (PathBuf, PathBuf) {
    let source = dir.join("source.png");
    let target = dir.join("target.png");
    image::RgbImage::from_fn(SIZE, SIZE, |x, y| Rgb([(4 * x) as u8, (4 * y) as u8, 200]))
        .save(&source)
        .unwrap();
    image::RgbImage::from_fn(SIZE, SIZE, |x, y| Rgb([90, (5 * x) as u8, (3 * y) as u8]))
        .save(&target)
        .unwrap();
    (source, target)
}

/// The pixels where `picture` differs from `target`.
fn changed(picture: &Path, target: &Path) -> Vec<(u32, u32)> {
    let (a, b) = (image::open(picture).unwrap(), image::open(target).unwrap());
    let (a, b) = (a.to_rgb8(), b.to_rgb8());
    a.enumerate_pixels()
        .filter(|(x, y, p)| *p != b.get_pixel(*x, *y))
        .map(|(x, y, _)| (x, y))
        .collect()
}

fn mesh_vertices(check_stdout: &str) -> u64 {
    let (before, _) = check_stdout
        .split_once(" mesh vertices")
        .expect(check_stdout);
    before.rsplit('(').next().unwrap().parse().unwrap()
}

#[test]
fn clone_check_and_render_agree_on_every_kind_of_mask() {
    let dir = tempfile::tempdir().unwrap();
    let (source, target) = write_images(dir.path());
    let mut cases = 0;
    for (name, mask) in masks() {
        let mask_path = dir.path().join(format!("{name}.png"));
        mask.save(&mask_path).unwrap();
        let cloned = dir.path().join(format!("{name}_clone.png"));
        let (code, stats, stderr) = lapclone(&[
            "clone".as_ref(),
            "--source".as_ref(),
            source.as_os_str(),
            "--mask".as_ref(),
            mask_path.as_os_str(),
            "--target".as_ref(),
            target.as_os_str(),
            "--at".as_ref(),
            "24,24".as_ref(),
            "--stats".as_ref(),
            "-o".as_ref(),
            cloned.as_os_str(),
        ]);
        assert_eq!(code, 0, "{name}: {stderr}");
        let stats: serde_json::Value = serde_json::from_str(&stats).unwrap();

        let scene = dir.path().join(format!("{name}.rhai"));
        let text = format!(
            "canvas({SIZE}, {SIZE}, #{{ fps: 1, duration: 1, background: {target:?} }});\n\
             let c = patch(\"c\", #{{ source: {source:?}, mask: {mask_path:?} }});\n\
             c.at(0, [24, 24]);\n"
        );
        std::fs::write(&scene, text).unwrap();
        let loaded = lapclone::load_scene(&scene).unwrap();
        let summary = lapclone::script::validate_scene(&loaded).unwrap();
        assert_eq!(summary.inside_pixels, [24 * 24], "{name}");
        let (code, checked, stderr) = lapclone(&["check".as_ref(), scene.as_os_str()]);
        assert_eq!(code, 0, "{name}: {stderr}");
        assert_eq!(
            mesh_vertices(&checked),
            stats["vertices"].as_u64().unwrap(),
            "{name}: the scene's mesh is the clone's"
        );

        let frames = dir.path().join(format!("{name}_frames"));
        let (code, _, stderr) = lapclone(&[
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            frames.as_os_str(),
            "--format".as_ref(),
            "png".as_ref(),
        ]);
        assert_eq!(code, 0, "{name}: {stderr}");
        let frame = std::fs::read_dir(&frames).unwrap().next().unwrap().unwrap();
        let by_clone = changed(&cloned, &target);
        let by_render = changed(&frame.path(), &target);
        assert!(!by_clone.is_empty(), "{name}: the clone changed nothing");
        assert!(
            by_clone
                .iter()
                .all(|&(x, y)| (11..37).contains(&x) && (11..37).contains(&y)),
            "{name}: the clone reaches outside the square"
        );
        assert_eq!(
            by_render, by_clone,
            "{name}: render and clone cover the same pixels"
        );
        cases += 1;
    }
    assert_eq!(cases, 8);
}
