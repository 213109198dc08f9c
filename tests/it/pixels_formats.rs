//! Pixel formats: 8/16-bit grey, grey+alpha, RGB and RGBA PNGs survive encode → decode
//! exactly, with their format detected; loading errors name the file.

use lapclone::pixels::{Canvas, ColorKind, Depth, FloatImage, PixelFormat};

fn formats() -> Vec<PixelFormat> {
    let mut all = Vec::new();
    for color in [ColorKind::Grey, ColorKind::Rgb] {
        for alpha in [false, true] {
            for depth in [Depth::Eight, Depth::Sixteen] {
                all.push(PixelFormat {
                    color,
                    alpha,
                    depth,
                });
            }
        }
    }
    all
}

/// Distinct, exactly representable values in the given format.
fn test_image(format: PixelFormat) -> FloatImage {
    test_image_of_size(format, 7, 5)
}

/// [`test_image`] of any size.
fn test_image_of_size(format: PixelFormat, width: u32, height: u32) -> FloatImage {
    let max = match format.depth {
        Depth::Eight => 255.0,
        Depth::Sixteen => 65535.0,
    };
    let q = |v: u32| (v % (max as u32 + 1)) as f32 / max;
    FloatImage::from_fn(width, height, format, |i, j| {
        let grey = q(i * 9973 + j * 31 + 5);
        let (r, g, b) = match format.color {
            ColorKind::Grey => (grey, grey, grey),
            ColorKind::Rgb => (grey, q(i * 131 + j * 7919), q(i * j * 17 + 3)),
        };
        let a = if format.alpha {
            q(i * 40503 + j * 977 + 1)
        } else {
            1.0
        };
        [r, g, b, a]
    })
    .unwrap()
}

#[test]
fn png_round_trips_every_format() {
    for format in formats() {
        let image = test_image(format);
        let canvas = Canvas::from_image(&image);
        assert_eq!(canvas.depth(), format.depth);
        let bytes = canvas.encode_png(format).unwrap();
        let decoded = image::load_from_memory(&bytes).unwrap();
        assert_eq!(PixelFormat::of(&decoded), format);
        let back = FloatImage::from_dynamic(&decoded).unwrap();
        assert_eq!(back.format(), format);
        assert_eq!(Canvas::from_image(&back), canvas, "{format:?}");
    }
}

#[test]
fn save_and_load_through_files() {
    let dir = tempfile::tempdir().unwrap();
    for format in formats() {
        let image = test_image(format);
        let path = dir
            .path()
            .join(format!("{format:?}.png").replace([' ', '{', '}', ':', ','], ""));
        Canvas::from_image(&image).save_png(&path, format).unwrap();
        let loaded = FloatImage::load(&path).unwrap();
        assert_eq!(loaded.format(), format);
        assert_eq!(Canvas::from_image(&loaded), Canvas::from_image(&image));
    }
}

/// Images taller than one band of streamed rows, with a width whose rows end mid-band, in
/// every format and through both the in-memory and the file path: the decoded samples are
/// the canvas's values quantised in the format (Rec. 709 luma for grey), band seams included.
#[test]
fn images_of_many_row_bands_write_every_sample() {
    let dir = tempfile::tempdir().unwrap();
    for format in formats() {
        for depth in [Depth::Eight, Depth::Sixteen] {
            let canvas =
                Canvas::from_image(&test_image_of_size(PixelFormat { depth, ..format }, 13, 71));
            let path = dir.path().join("tall.png");
            canvas.save_png(&path, format).unwrap();
            let bytes = canvas.encode_png(format).unwrap();
            for decoded in [
                image::open(&path).unwrap(),
                image::load_from_memory(&bytes).unwrap(),
            ] {
                assert_eq!(PixelFormat::of(&decoded), format);
                let samples = decoded.to_rgba16();
                for j in 0..canvas.height() {
                    for i in 0..canvas.width() {
                        let expected = expected_samples(canvas.pixel_f32(i, j).unwrap(), format);
                        let actual = samples.get_pixel(i, j).0;
                        assert_eq!(actual, expected, "{format:?} from {depth:?} at ({i}, {j})");
                    }
                }
            }
        }
    }
}

/// A canvas value as a PNG of `format` stores it, widened to 16 bits as `to_rgba16` does.
fn expected_samples(value: [f32; 4], format: PixelFormat) -> [u16; 4] {
    let quantise = |v: f32| match format.depth {
        Depth::Eight => u16::from((v * 255.0 + 0.5) as u8) * 257,
        Depth::Sixteen => (v * 65535.0 + 0.5) as u16,
    };
    let [r, g, b, a] = value;
    let colour = match format.color {
        ColorKind::Grey => [0.2126 * r + 0.7152 * g + 0.0722 * b; 3],
        ColorKind::Rgb => [r, g, b],
    }
    .map(quantise);
    let alpha = if format.alpha { quantise(a) } else { u16::MAX };
    [colour[0], colour[1], colour[2], alpha]
}

#[test]
fn eight_bit_canvas_written_as_sixteen_bit_scales_exactly() {
    let format8 = PixelFormat {
        color: ColorKind::Rgb,
        alpha: false,
        depth: Depth::Eight,
    };
    let image = test_image(format8);
    let canvas = Canvas::from_image(&image);
    let format16 = PixelFormat {
        depth: Depth::Sixteen,
        ..format8
    };
    let decoded = image::load_from_memory(&canvas.encode_png(format16).unwrap()).unwrap();
    let wide = decoded.to_rgb16();
    let narrow = image::load_from_memory(&canvas.encode_png(format8).unwrap())
        .unwrap()
        .to_rgb8();
    for (w, n) in wide.pixels().zip(narrow.pixels()) {
        for c in 0..3 {
            assert_eq!(w.0[c], u16::from(n.0[c]) * 257);
        }
    }
}

#[test]
fn load_errors_name_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.png");
    let message = FloatImage::load(&missing).unwrap_err().to_string();
    assert!(message.contains("missing.png"), "{message}");
    let garbage = dir.path().join("garbage.png");
    std::fs::write(&garbage, b"not an image").unwrap();
    let message = FloatImage::load(&garbage).unwrap_err().to_string();
    assert!(message.contains("garbage.png"), "{message}");
}

#[test]
fn saving_into_a_missing_folder_fails_without_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nope").join("out.png");
    let canvas = Canvas::from_image(&test_image(PixelFormat::RGBA8));
    assert!(canvas.save_png(&path, PixelFormat::RGBA8).is_err());
    assert!(!path.exists());
}
