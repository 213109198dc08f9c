//! Pictures of a comparison: takes the expected frame (if any), the actual frame and the
//! thresholds and gives 8-bit RGBA images — the difference image and the `expected |
//! difference | actual` triptych — and their PNG bytes.
//!
//! In the difference image, identical pixels are a dim grey copy of the actual frame (for
//! orientation), pixels that differ within the fail threshold are light grey brightening
//! with the difference (one level is already clearly visible), and failing pixels — or
//! pixels that only one frame has — are red.

use image::{Rgba, RgbaImage};

use super::{GoldenFrame, Thresholds};

const FAILING: [u8; 4] = [255, 0, 0, 255];
const SEPARATOR: [u8; 4] = [255, 0, 255, 255];
const SEPARATOR_WIDTH: u32 = 2;
const EMPTY: [u8; 4] = [40, 40, 40, 255];

/// The difference image, as large as the larger frame in each direction.
pub fn difference_image(
    expected: &GoldenFrame,
    actual: &GoldenFrame,
    thresholds: &Thresholds,
) -> RgbaImage {
    let (width, height) = (
        expected.width.max(actual.width),
        expected.height.max(actual.height),
    );
    let channels = if expected.alpha || actual.alpha { 4 } else { 3 };
    let unit = 255.0 / f64::from(expected.max_value().max(actual.max_value()));
    let same_depth = expected.depth == actual.depth;
    RgbaImage::from_fn(width, height, |x, y| {
        let (Some(e), Some(a)) = (sample(expected, x, y), sample(actual, x, y)) else {
            return Rgba(FAILING);
        };
        if !same_depth {
            return Rgba(FAILING);
        }
        let d = (0..channels)
            .map(|c| e[c].abs_diff(a[c]))
            .max()
            .unwrap_or(0);
        let error = f64::from(d) * unit;
        if d == 0 {
            Rgba(dim(actual.rgba8_at(x, y).unwrap_or(EMPTY)))
        } else if error > thresholds.fail {
            Rgba(FAILING)
        } else {
            let v = (96.0 + error * 48.0).min(255.0) as u8;
            Rgba([v, v, v, 255])
        }
    })
}

/// `expected | difference | actual` side by side, separated by magenta bars. Without an
/// expected frame (a new golden) the first two panels are empty.
pub fn triptych(
    expected: Option<&GoldenFrame>,
    actual: &GoldenFrame,
    thresholds: &Thresholds,
) -> RgbaImage {
    let panel_w = expected.map_or(actual.width, |e| e.width.max(actual.width));
    let panel_h = expected.map_or(actual.height, |e| e.height.max(actual.height));
    let difference = expected.map(|e| difference_image(e, actual, thresholds));
    let width = panel_w * 3 + SEPARATOR_WIDTH * 2;
    RgbaImage::from_fn(width, panel_h, |x, y| {
        let (panel, i) = (
            x / (panel_w + SEPARATOR_WIDTH),
            x % (panel_w + SEPARATOR_WIDTH),
        );
        if i >= panel_w {
            return Rgba(SEPARATOR);
        }
        let pixel = match panel {
            0 => expected.and_then(|e| e.rgba8_at(i, y)),
            1 => difference.as_ref().map(|d| d.get_pixel(i, y).0),
            _ => actual.rgba8_at(i, y),
        };
        Rgba(pixel.map_or(EMPTY, opaque))
    })
}

/// PNG bytes of an 8-bit RGBA image (the pictures `lapclone` writes or shows: triptychs,
/// mesh overlays, previews).
pub fn encode_rgba_png(image: &RgbaImage) -> Vec<u8> {
    let mut bytes = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut bytes);
    // invariant: encoding an RGBA8 image into a Vec cannot fail.
    image.write_with_encoder(encoder).expect("in-memory PNG");
    bytes
}

fn sample(frame: &GoldenFrame, x: u32, y: u32) -> Option<[u16; 4]> {
    (x < frame.width && y < frame.height)
        .then(|| frame.pixels[(y as usize) * (frame.width as usize) + x as usize])
}

fn dim(px: [u8; 4]) -> [u8; 4] {
    let luma = (u32::from(px[0]) * 2 + u32::from(px[1]) * 7 + u32::from(px[2])) / 10;
    let v = (luma / 4) as u8;
    [v, v, v, 255]
}

/// Shows transparent pixels over the empty colour so the panels stay readable.
fn opaque(px: [u8; 4]) -> [u8; 4] {
    let a = u32::from(px[3]);
    let mix = |c: u8, bg: u8| ((u32::from(c) * a + u32::from(bg) * (255 - a) + 127) / 255) as u8;
    [
        mix(px[0], EMPTY[0]),
        mix(px[1], EMPTY[1]),
        mix(px[2], EMPTY[2]),
        255,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixels::Depth;

    fn frame(width: u32, height: u32, value: u16) -> GoldenFrame {
        GoldenFrame {
            width,
            height,
            depth: Depth::Eight,
            alpha: false,
            pixels: vec![[value, value, value, 255]; (width * height) as usize],
        }
    }

    #[test]
    fn the_difference_image_marks_failing_pixels_red_and_small_ones_grey() {
        let expected = frame(4, 2, 100);
        let mut actual = expected.clone();
        actual.pixels[1][0] = 101; // one level: within fail = 1
        actual.pixels[6][2] = 150; // fails
        let d = difference_image(&expected, &actual, &Thresholds::default());
        assert_eq!(d.get_pixel(2, 1).0, FAILING);
        let small = d.get_pixel(1, 0).0;
        assert!(small[0] == small[1] && small[0] >= 96, "{small:?}");
        let same = d.get_pixel(0, 0).0;
        assert!(same[0] < 64, "identical pixels are dim: {same:?}");
    }

    #[test]
    fn the_triptych_puts_expected_difference_and_actual_side_by_side() {
        let expected = frame(4, 2, 10);
        let actual = frame(5, 3, 200);
        let t = triptych(Some(&expected), &actual, &Thresholds::default());
        assert_eq!((t.width(), t.height()), (5 * 3 + 2 * SEPARATOR_WIDTH, 3));
        assert_eq!(t.get_pixel(0, 0).0, [10, 10, 10, 255]);
        assert_eq!(t.get_pixel(4, 2).0, EMPTY, "outside the smaller golden");
        assert_eq!(t.get_pixel(5, 0).0, SEPARATOR);
        assert_eq!(t.get_pixel(7 + 4, 2).0, FAILING, "only one frame has it");
        assert_eq!(t.get_pixel(14 + 4, 2).0, [200, 200, 200, 255]);
        let png = encode_rgba_png(&t);
        let back = image::load_from_memory(&png).unwrap().to_rgba8();
        assert_eq!(back, t);
    }
}
