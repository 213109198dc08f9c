//! GIF output: shared palette, frame differencing and threads. Every GIF written here is
//! decoded back (the `image` crate composites the records) and compared with the frames.

use std::path::Path;

use image::AnimationDecoder;
use lapclone::output::{
    gif_delays_cs, Frame, FrameData, GifOptions, GifWriter, OutputError, Palette, PaletteMap,
};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

const W: u32 = 160;
const H: u32 = 120;

/// A crop of a bundled photograph (opaque RGBA8).
fn photo() -> Vec<u8> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/chelsea.png");
    let image = image::open(path).unwrap().to_rgba8();
    let crop = image::imageops::crop_imm(&image, 60, 20, W, H).to_image();
    crop.into_raw()
}

fn frame(data: Vec<u8>) -> Frame {
    Frame {
        width: W,
        height: H,
        data: FrameData::Rgba8(data),
    }
}

/// The photo with a 24×24 block of it pasted at a position moving with `k`.
fn moving_block(base: &[u8], k: u32) -> Vec<u8> {
    let mut out = base.to_vec();
    let (sx, sy) = (10, 10);
    let (dx, dy) = (30 + 9 * k, 40 + 3 * k);
    for y in 0..24 {
        for x in 0..24 {
            let from = (((sy + y) * W + sx + x) * 4) as usize;
            let to = (((dy + y) * W + dx + x) * 4) as usize;
            out.copy_within(from..from + 4, to);
        }
    }
    out
}

fn write_gif(path: &Path, frames: &[Frame], options: GifOptions) -> Result<(), OutputError> {
    let mut writer = GifWriter::create_with(path, 24.0, options)?;
    for f in frames {
        writer.add(&f.as_ref()?)?;
    }
    writer.finish().map(|_| ())
}

/// Composited RGBA frames and their delays in centiseconds.
fn decode(path: &Path) -> Vec<(Vec<u8>, u64)> {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let decoder = image::codecs::gif::GifDecoder::new(file).unwrap();
    decoder
        .into_frames()
        .collect_frames()
        .unwrap()
        .into_iter()
        .map(|f| {
            let (n, d) = f.delay().numer_denom_ms();
            (f.into_buffer().into_raw(), (n / d / 10) as u64)
        })
        .collect()
}

/// Raw record rectangles (left, top, width, height) as stored in the file.
fn records(path: &Path) -> Vec<(u16, u16, u16, u16)> {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::Indexed);
    let file = std::fs::File::open(path).unwrap();
    let mut decoder = options.read_info(file).unwrap();
    let mut out = Vec::new();
    while let Some(f) = decoder.read_next_frame().unwrap() {
        out.push((f.left, f.top, f.width, f.height));
    }
    out
}

/// Mean absolute error per channel in 0..=255 units, over opaque input pixels (RGB), and
/// whether the transparency (input alpha < 128 ⇔ decoded alpha 0) matches everywhere.
fn compare(input: &[u8], decoded: &[u8]) -> (f64, bool) {
    let mut sum = 0u64;
    let mut count = 0u64;
    let mut alpha_ok = true;
    for (a, b) in input.chunks_exact(4).zip(decoded.chunks_exact(4)) {
        if a[3] < 128 {
            alpha_ok &= b[3] == 0;
            continue;
        }
        alpha_ok &= b[3] == 255;
        for k in 0..3 {
            sum += (a[k] as i32 - b[k] as i32).unsigned_abs() as u64;
            count += 1;
        }
    }
    (sum as f64 / count.max(1) as f64, alpha_ok)
}

fn rgba(f: &Frame) -> &[u8] {
    match &f.data {
        FrameData::Rgba8(d) => d,
        FrameData::Rgba16(_) => unreachable!("8-bit test frames"),
    }
}

#[test]
fn photographic_frames_decode_within_palette_error() {
    let base = photo();
    let frames: Vec<Frame> = (0..8).map(|k| frame(moving_block(&base, k))).collect();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("photo.gif");
    write_gif(&path, &frames, GifOptions::default()).unwrap();
    let decoded = decode(&path);
    assert_eq!(decoded.len(), frames.len());
    let delays: Vec<u64> = decoded.iter().map(|d| d.1).collect();
    assert_eq!(delays, gif_delays_cs(frames.len(), 24.0));
    for (i, (f, (pixels, _))) in frames.iter().zip(&decoded).enumerate() {
        let (mean, alpha_ok) = compare(rgba(f), pixels);
        assert!(alpha_ok, "frame {i}: transparency differs");
        assert!(
            mean <= 3.0,
            "frame {i}: mean abs error {mean:.2}/255 > 3/255"
        );
    }
}

#[test]
fn dithered_frames_stay_close_and_deterministic() {
    let base = photo();
    let frames: Vec<Frame> = (0..4).map(|k| frame(moving_block(&base, k))).collect();
    let dir = tempfile::tempdir().unwrap();
    let one = dir.path().join("d1.gif");
    let two = dir.path().join("d2.gif");
    let dithered = |jobs| GifOptions { jobs, dither: true };
    write_gif(&one, &frames, dithered(1)).unwrap();
    write_gif(&two, &frames, dithered(2)).unwrap();
    assert_eq!(std::fs::read(&one).unwrap(), std::fs::read(&two).unwrap());
    for (i, (f, (pixels, _))) in frames.iter().zip(decode(&one)).enumerate() {
        let (mean, alpha_ok) = compare(rgba(f), &pixels);
        assert!(alpha_ok);
        // Dithering trades a little mean error for smoother gradients.
        assert!(
            mean <= 6.0,
            "frame {i}: mean abs error {mean:.2}/255 > 6/255"
        );
    }
}

/// Frames of at most 255 colours: a palette-indexed pattern with moving parts.
fn few_colours(k: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity((W * H * 4) as usize);
    for y in 0..H {
        for x in 0..W {
            let moving = (x + 5 * k) / 7 % 4 == 0 && y > 30 + 2 * k && y < 70 + 2 * k;
            let c = if moving {
                250
            } else {
                (x / 10 * 16 + y / 8) % 200
            };
            out.extend_from_slice(&[(c * 37 % 256) as u8, (c * 11) as u8, c as u8, 255]);
        }
    }
    out
}

#[test]
fn frames_with_few_colours_decode_exactly() {
    let frames: Vec<Frame> = (0..6).map(|k| frame(few_colours(k))).collect();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("few.gif");
    write_gif(&path, &frames, GifOptions::default()).unwrap();
    let decoded = decode(&path);
    assert_eq!(decoded.len(), frames.len());
    for (i, (f, (pixels, _))) in frames.iter().zip(&decoded).enumerate() {
        assert!(rgba(f) == pixels.as_slice(), "frame {i} differs");
    }
}

#[test]
fn static_frames_give_tiny_records_and_moving_ones_their_box() {
    let base = photo();
    let mut frames: Vec<Frame> = (0..4).map(|_| frame(base.clone())).collect();
    frames.push(frame(moving_block(&base, 0)));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("static.gif");
    write_gif(&path, &frames, GifOptions::default()).unwrap();
    let rects = records(&path);
    assert_eq!(rects.len(), 5);
    assert_eq!(rects[0], (0, 0, W as u16, H as u16), "first frame whole");
    for r in &rects[1..4] {
        assert_eq!((r.2, r.3), (1, 1), "unchanged frame stored as 1×1: {r:?}");
    }
    // The block lands at (30, 40), 24×24: the record lies inside that box.
    let (left, top, width, height) = rects[4];
    assert!(left >= 30 && top >= 40, "{:?}", rects[4]);
    assert!(left + width <= 54 && top + height <= 64, "{:?}", rects[4]);
    let one_frame = dir.path().join("one.gif");
    write_gif(&one_frame, &frames[..1], GifOptions::default()).unwrap();
    let extra = std::fs::metadata(&path).unwrap().len() as i64
        - std::fs::metadata(&one_frame).unwrap().len() as i64;
    assert!(
        extra < 3 * 40 + 24 * 24 * 2,
        "{extra} bytes for 4 more frames"
    );
    for (f, (pixels, _)) in frames.iter().zip(decode(&path)) {
        assert!(compare(rgba(f), &pixels).0 <= 3.0);
    }
}

/// An opaque disc moving over a transparent background (pixels turn transparent again),
/// and a strip at the left edge in every other frame; at most 24 colours.
fn disc(k: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity((W * H * 4) as usize);
    let (cx, cy) = (40.0 + 12.0 * k as f64, 60.0);
    for y in 0..H {
        for x in 0..W {
            let d = ((x as f64 - cx).powi(2) + (y as f64 - cy).powi(2)).sqrt();
            let shade = (y / 10 * 20) as u8;
            let pixel = if d < 20.0 {
                [shade, 200, 40, 255]
            } else if k % 2 == 0 && x < 8 {
                [shade, 90, 200, 200]
            } else {
                [shade, 0, 0, 0]
            };
            out.extend_from_slice(&pixel);
        }
    }
    out
}

#[test]
fn pixels_turning_transparent_are_cleared_for_any_job_count() {
    let frames: Vec<Frame> = (0..7).map(|k| frame(disc(k))).collect();
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = Vec::new();
    for jobs in [1, 2, 3] {
        let path = dir.path().join(format!("disc{jobs}.gif"));
        write_gif(
            &path,
            &frames,
            GifOptions {
                jobs,
                dither: false,
            },
        )
        .unwrap();
        let decoded = decode(&path);
        assert_eq!(decoded.len(), frames.len());
        for (i, (f, (pixels, _))) in frames.iter().zip(&decoded).enumerate() {
            let (mean, alpha_ok) = compare(rgba(f), pixels);
            assert!(alpha_ok, "jobs {jobs}, frame {i}: transparency differs");
            assert_eq!(mean, 0.0, "jobs {jobs}, frame {i}: colours differ");
        }
        bytes.push(std::fs::read(&path).unwrap());
    }
    assert!(
        bytes.windows(2).all(|w| w[0] == w[1]),
        "bytes differ by jobs"
    );
}

#[test]
fn identical_bytes_for_one_and_many_threads() {
    let base = photo();
    let frames: Vec<Frame> = (0..9).map(|k| frame(moving_block(&base, k % 5))).collect();
    let dir = tempfile::tempdir().unwrap();
    let outputs: Vec<Vec<u8>> = [1, 2, 4]
        .iter()
        .map(|&jobs| {
            let path = dir.path().join(format!("t{jobs}.gif"));
            write_gif(
                &path,
                &frames,
                GifOptions {
                    jobs,
                    dither: false,
                },
            )
            .unwrap();
            std::fs::read(path).unwrap()
        })
        .collect();
    assert_eq!(outputs[0], outputs[1]);
    assert_eq!(outputs[0], outputs[2]);
}

#[test]
fn short_animations_and_dropped_writers() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("single.gif");
    write_gif(
        &path,
        &[frame(photo())],
        GifOptions {
            jobs: 2,
            dither: false,
        },
    )
    .unwrap();
    assert_eq!(decode(&path).len(), 1);
    // Dropped mid-way (e.g. Ctrl-C), with workers running: nothing is left behind.
    let dropped = dir.path().join("dropped.gif");
    let mut writer = GifWriter::create_with(
        &dropped,
        24.0,
        GifOptions {
            jobs: 2,
            dither: false,
        },
    )
    .unwrap();
    for k in 0..6 {
        writer
            .add(&frame(moving_block(&photo(), k)).as_ref().unwrap())
            .unwrap();
    }
    drop(writer);
    let empty = GifWriter::create(&dir.path().join("empty.gif"), 24.0).unwrap();
    assert!(empty.finish().is_err());
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["single.gif".to_string()]);
}

#[test]
fn palette_is_exact_for_few_colours() {
    let pixels = few_colours(0);
    let palette = Palette::from_samples(&[&pixels]);
    palette.sanity_check().unwrap();
    let mut distinct: Vec<[u8; 3]> = pixels.chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect();
    distinct.sort();
    distinct.dedup();
    assert_eq!(palette.colours(), distinct.as_slice());
}

proptest! {
    #![proptest_config(Config {
        rng_seed: RngSeed::Fixed(0x6d1f),
        cases: 64,
        ..Config::default()
    })]

    /// The cached mapping gives a nearest palette colour (brute force), also when a colour
    /// is looked up again.
    #[test]
    fn mapping_finds_a_nearest_colour(pixels in proptest::collection::vec(any::<[u8; 3]>(), 1..40)) {
        static PALETTE: std::sync::OnceLock<Palette> = std::sync::OnceLock::new();
        let palette = PALETTE.get_or_init(|| Palette::from_samples(&[&photo()])).clone();
        let mut map = PaletteMap::new(palette.clone(), false);
        for _ in 0..2 {
            for p in &pixels {
                let index = map.index(&[p[0], p[1], p[2], 255], 0, 0) as usize;
                let distance = |c: &[u8; 3]| (0..3).map(|k| (p[k] as i32 - c[k] as i32).pow(2)).sum::<i32>();
                let best = palette.colours().iter().map(distance).min().unwrap();
                prop_assert_eq!(distance(&palette.colours()[index]), best);
            }
        }
        prop_assert_eq!(map.index(&[1, 2, 3, 0], 0, 0), palette.transparent_index());
    }
}
