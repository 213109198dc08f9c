//! Direct PNG decoding: takes an image file and, when it is a non-interlaced PNG whose
//! samples are 8-bit (after expanding palettes, low bit depths and `tRNS` transparency, as the
//! `image` crate does), gives its pixels as straight RGBA levels decoded row by row into their
//! final buffer, with the [`PixelFormat`] the `image` crate would report. Other files give
//! `None`, for the `image` crate to decode. Sizes are checked against `limits` from the
//! header first, and the decoder runs under the same allocation limit.

use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use crate::limits::{check_image_size, image_dimensions, ImageOpenError, MAX_DECODER_ALLOC};

use super::format::extend_rgba8;
use super::{ColorKind, Depth, PixelFormat};

/// The first eight bytes of every PNG file.
const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

/// An 8-bit image's pixels as RGBA levels, row-major.
pub(crate) struct Levels {
    pub width: u32,
    pub height: u32,
    pub format: PixelFormat,
    pub levels: Vec<[u8; 4]>,
}

/// Decodes `path` as [`Levels`] if it is an 8-bit, non-interlaced PNG; `Ok(None)` if it is
/// another kind of image (or not one at all: the caller's decoder says so).
pub(crate) fn decode_png_levels(path: &Path) -> Result<Option<Levels>, ImageOpenError> {
    let (width, height) = image_dimensions(path)?;
    check_image_size(u64::from(width), u64::from(height))?;
    let mut file = BufReader::new(crate::util::open_input_file(path)?);
    let mut signature = [0; 8];
    if file.read_exact(&mut signature).is_err() || signature != SIGNATURE {
        return Ok(None);
    }
    file.seek(SeekFrom::Start(0))?;
    let limits = png::Limits {
        bytes: usize::try_from(MAX_DECODER_ALLOC).unwrap_or(usize::MAX),
    };
    let mut decoder = png::Decoder::new_with_limits(file, limits);
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(decode_error)?;
    let (colour, depth) = reader.output_color_type();
    if depth != png::BitDepth::Eight || reader.info().interlaced {
        return Ok(None);
    }
    let Some(format) = layout(colour) else {
        return Ok(None);
    };
    let info = reader.info();
    let (width, height) = (info.width, info.height);
    let mut levels = Vec::with_capacity(width as usize * height as usize);
    while let Some(row) = reader.next_row().map_err(decode_error)? {
        extend_rgba8(row.data(), format, &mut levels);
    }
    Ok(Some(Levels {
        width,
        height,
        format,
        levels,
    }))
}

/// Appends one row's samples to the levels as RGBA.
/// The format of an 8-bit colour type after expansion (`None`: still indexed).
fn layout(colour: png::ColorType) -> Option<PixelFormat> {
    let (color, alpha) = match colour {
        png::ColorType::Rgb => (ColorKind::Rgb, false),
        png::ColorType::Rgba => (ColorKind::Rgb, true),
        png::ColorType::Grayscale => (ColorKind::Grey, false),
        png::ColorType::GrayscaleAlpha => (ColorKind::Grey, true),
        png::ColorType::Indexed => return None,
    };
    Some(PixelFormat {
        color,
        alpha,
        depth: Depth::Eight,
    })
}

fn decode_error(error: png::DecodingError) -> ImageOpenError {
    use image::error::{DecodingError, ImageFormatHint};
    ImageOpenError::Decode(match error {
        png::DecodingError::IoError(io) => image::ImageError::IoError(io),
        other => image::ImageError::Decoding(DecodingError::new(
            ImageFormatHint::Exact(image::ImageFormat::Png),
            other,
        )),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use png::{BitDepth, ColorType};

    /// An 11×3 PNG of `colour` and `depth` (samples from a ramp; a 4-entry palette for
    /// indexed images), with `trns` when asked. (The png crate writes no interlaced files.)
    fn png_bytes(colour: ColorType, depth: BitDepth, trns: Option<&[u8]>) -> Vec<u8> {
        let (width, height) = (11u32, 3u32);
        let row_bytes = (width as usize * colour.samples() * depth as usize).div_ceil(8);
        let mut data: Vec<u8> = (0..row_bytes * 3).map(|i| (i * 37 % 251) as u8).collect();
        if colour == ColorType::Indexed {
            // Every index below 4, whatever the bit depth.
            data.iter_mut().for_each(|b| *b &= 0x55);
        }
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(colour);
        encoder.set_depth(depth);
        if colour == ColorType::Indexed {
            encoder.set_palette(vec![10, 20, 30, 40, 50, 60, 70, 80, 90, 200, 210, 220]);
        }
        if let Some(trns) = trns {
            encoder.set_trns(trns.to_vec());
        }
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(&data).unwrap();
        writer.finish().unwrap();
        bytes
    }

    /// Every 8-bit-after-expansion PNG kind decodes to the levels and format the `image`
    /// crate gives; 16-bit PNGs and other files are left to it.
    #[test]
    fn levels_and_format_are_the_image_crates() {
        use {BitDepth::*, ColorType::*};
        let cases: [(ColorType, BitDepth, Option<&[u8]>, bool); 11] = [
            (Rgb, Eight, None, true),
            (Rgba, Eight, None, true),
            (Grayscale, Eight, None, true),
            (GrayscaleAlpha, Eight, None, true),
            (Grayscale, One, None, true),
            (Grayscale, Four, Some(&[0, 3]), true),
            (Rgb, Eight, Some(&[0, 37, 0, 74, 0, 111]), true),
            (Indexed, Two, None, true),
            (Indexed, Eight, Some(&[0, 128]), true),
            (Rgb, Sixteen, None, false),
            (Grayscale, Sixteen, None, false),
        ];
        let dir = tempfile::tempdir().unwrap();
        for (k, (colour, depth, trns, direct)) in cases.into_iter().enumerate() {
            let path = dir.path().join(format!("{k}.png"));
            std::fs::write(&path, png_bytes(colour, depth, trns)).unwrap();
            let case = format!("{colour:?} {depth:?} {trns:?}");
            let reference = image::open(&path).unwrap();
            let decoded = decode_png_levels(&path).unwrap();
            assert_eq!(decoded.is_some(), direct, "{case}");
            if let Some(png) = decoded {
                let levels: Vec<[u8; 4]> = reference.to_rgba8().pixels().map(|p| p.0).collect();
                assert!(png.levels == levels, "{case}");
                assert_eq!((png.width, png.height), (11, 3), "{case}");
                assert_eq!(png.format, PixelFormat::of(&reference), "{case}");
            }
            let loaded = crate::pixels::FloatImage::load(&path).unwrap();
            let expected = crate::pixels::FloatImage::from_dynamic(&reference).unwrap();
            assert!(loaded == expected, "{case}");
            assert_eq!(loaded.format(), expected.format(), "{case}");
        }
        let jpeg = dir.path().join("picture.jpg");
        image::RgbImage::from_pixel(4, 4, image::Rgb([9, 99, 199]))
            .save(&jpeg)
            .unwrap();
        assert!(decode_png_levels(&jpeg).unwrap().is_none());
    }

    #[test]
    fn truncated_and_missing_files_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let bytes = png_bytes(ColorType::Rgb, BitDepth::Eight, None);
        let path = dir.path().join("cut.png");
        std::fs::write(&path, &bytes[..bytes.len() - 30]).unwrap();
        assert!(matches!(decode_png_levels(&path), Err(ImageOpenError::Decode(_))));
        let missing = dir.path().join("missing.png");
        assert!(matches!(decode_png_levels(&missing), Err(ImageOpenError::Read(_))));
    }
}
