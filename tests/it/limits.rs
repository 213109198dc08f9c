//! The size and frame limits: what passes, what is refused, and the header-only size read.

use lapclone::limits::*;
use std::path::Path;

#[test]
fn sizes_at_the_limits_pass_and_one_more_fails() {
    let side = u64::from(MAX_IMAGE_SIDE);
    assert!(check_image_size(8192, 8192).is_ok());
    assert!(check_image_size(side, MAX_IMAGE_PIXELS / side).is_ok());
    assert!(check_image_size(side + 1, 1).is_err());
    assert!(check_image_size(1, side + 1).is_err());
    assert!(check_image_size(side, MAX_IMAGE_PIXELS / side + 1).is_err());
    assert!(check_image_size(u64::MAX, u64::MAX).is_err());
    assert!(check_frame_count(MAX_FRAMES).is_ok());
    assert!(check_frame_count(MAX_FRAMES + 1).is_err());
}

#[test]
fn the_message_names_size_and_limit() {
    let message = check_image_size(20_000, 20_000).unwrap_err().to_string();
    assert!(
        message.contains("20000×20000") && message.contains("size limit"),
        "{message}"
    );
}

#[test]
fn a_big_header_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.png");
    write_blank_grey_png(&path, 20_000, 3);
    assert_eq!(image_dimensions(&path).unwrap(), (20_000, 3));
    assert!(open_image(&path).is_err());
    let small = dir.path().join("small.png");
    write_blank_grey_png(&small, 5, 4);
    let image = open_image(&small).unwrap();
    assert_eq!((image.width(), image.height()), (5, 4));
}

fn write_blank_grey_png(path: &Path, width: u32, height: u32) {
    let file = std::fs::File::create(path).unwrap();
    let mut encoder = png::Encoder::new(file, width, height);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().unwrap();
    writer
        .write_image_data(&vec![0; (width * height) as usize])
        .unwrap();
}
