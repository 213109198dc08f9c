//! Sixel output for terminals without the kitty or iTerm2 protocols (xterm with sixel, foot,
//! mlterm, …): takes an RGBA frame and gives the DEC sixel escape sequence that draws it,
//! downscaled to a preview width. The encoding (palette, dithering, run lengths) is
//! `icy_sixel`'s.

use anyhow::Context as _;
use image::imageops::FilterType;
use image::RgbaImage;

/// Widest preview drawn, in pixels (sixel is slow to print for big frames).
pub const MAX_WIDTH: u32 = 480;

/// The sixel sequence for `picture` (straight alpha), at most [`MAX_WIDTH`] wide.
pub fn encode_sixel(picture: &RgbaImage) -> anyhow::Result<String> {
    let (width, height) = picture.dimensions();
    let scaled;
    let shown = if width > MAX_WIDTH {
        let h = ((u64::from(height) * u64::from(MAX_WIDTH)) / u64::from(width)).max(1) as u32;
        scaled = image::imageops::resize(picture, MAX_WIDTH, h, FilterType::Triangle);
        &scaled
    } else {
        picture
    };
    let options = icy_sixel::EncodeOptions::default();
    let (w, h) = (shown.width() as usize, shown.height() as usize);
    icy_sixel::sixel_encode(shown.as_raw(), w, h, &options).context("encoding the sixel preview")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(sixel: &str) -> icy_sixel::SixelImage {
        icy_sixel::SixelImage::decode(sixel.as_bytes()).expect("the sequence decodes")
    }

    #[test]
    fn a_small_frame_round_trips_in_size_and_colour() {
        // Left half red, right half blue, 10×7 (two sixel bands).
        let picture = RgbaImage::from_fn(10, 7, |x, _| {
            if x < 5 {
                image::Rgba([255, 0, 0, 255])
            } else {
                image::Rgba([0, 0, 255, 255])
            }
        });
        let sixel = encode_sixel(&picture).unwrap();
        assert!(
            sixel.starts_with("\x1bP") && sixel.ends_with("\x1b\\"),
            "{sixel:?}"
        );
        let back = decode(&sixel);
        // Sixel draws whole six-row bands: the decoded height is rounded up to 12.
        assert_eq!((back.width, back.height), (10, 12));
        let at = |x: usize, y: usize| &back.pixels[(y * 10 + x) * 4..(y * 10 + x) * 4 + 3];
        for y in 0..7 {
            // Two flat colours need no dithering: within a few levels of the input.
            let (red, blue) = (at(1, y), at(8, y));
            assert!(red[0] > 240 && red[1] < 16 && red[2] < 16, "{red:?}");
            assert!(blue[0] < 16 && blue[1] < 16 && blue[2] > 240, "{blue:?}");
        }
    }

    #[test]
    fn wide_frames_are_downscaled_to_the_preview_width() {
        let picture = RgbaImage::from_pixel(960, 12, image::Rgba([255, 255, 255, 255]));
        let back = decode(&encode_sixel(&picture).unwrap());
        assert_eq!((back.width, back.height), (MAX_WIDTH as usize, 6));
    }
}
