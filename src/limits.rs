//! Resource limits: takes an image file (or a width and height, or a frame count) and gives
//! an error *before* anything large is allocated when the input exceeds what lapclone will
//! hold in memory. Images are checked from their header alone, so a 20000 × 20000 mask of a
//! few kilobytes is refused without decoding 400 M pixels.
//!
//! Why these numbers (docs/robustness.md has the table): a source or target becomes a
//! `FloatImage` of 16 bytes per pixel, so [`MAX_IMAGE_PIXELS`] (64 Mi px, e.g. 8192 × 8192)
//! caps one image at 1 GiB of floats; the 2-core, 24 GiB reference machine holds a source,
//! a target and the canvases of a render at that size. [`MAX_IMAGE_SIDE`] matches the scene
//! canvas limit. The mesh vertex budget is `MeshOptions::max_vertices`
//! ([`MAX_MESH_VERTICES`] by default).

use std::path::Path;

/// Largest width or height of any image lapclone reads or any canvas it renders.
pub const MAX_IMAGE_SIDE: u32 = 16_384;
/// Largest number of pixels (width × height) of any image read or canvas rendered.
pub const MAX_IMAGE_PIXELS: u64 = 64 * 1024 * 1024;
/// Most pixels the distinct still source images of one scene may hold in all: eight of the
/// largest (2 GiB as 8-bit texels). Patches sharing a file share its pixels and count it
/// once; 200 distinct 4096² sources would have held 13 GB.
pub const MAX_SCENE_SOURCE_PIXELS: u64 = 8 * MAX_IMAGE_PIXELS;
/// Default mesh vertex budget (`MeshOptions::max_vertices`): refinement stops there, and a
/// mask whose boundary alone needs more vertices is refused.
pub const MAX_MESH_VERTICES: usize = 2_000_000;
/// Most frames a scene may have (`check` evaluates every one of them).
pub const MAX_FRAMES: u64 = 1_000_000;
/// Largest file number a numbered sequence may start at (a scene's `…_start_number`,
/// `track --start`): plates past it, counted up to [`MAX_FRAMES`] on, stay far from
/// overflowing a frame number.
pub const MAX_START_NUMBER: u64 = 1_000_000_000_000_000;
/// Largest scene or module file, bytes: far beyond any hand-written or generated scene, and
/// small enough that its text, its errors and the REPL's copy of it stay cheap.
pub const MAX_SCENE_BYTES: u64 = 16 << 20;
/// Widest feather, px: four times the widest canvas, so any feather that can matter fits,
/// and the raster's integer margins around a patch cannot overflow.
pub const MAX_FEATHER: f64 = 65_536.0;
/// Most pixels the raster examines for one patch in one frame: the patch's box, cut to the
/// canvas grown by the feather (its ramp needs the silhouette that far outside). Every such
/// pixel holds about 17 bytes of ids, depth, coverage and distance, so this caps a draw near
/// 2 GiB; a whole largest canvas plus an ordinary feather fits twice over. A feather of
/// 65,536 px around a patch scaled past the canvas asked for 69 GB.
pub const MAX_RASTER_PIXELS: u64 = 2 * MAX_IMAGE_PIXELS;
/// Slowest frame rate, frames per second: a frame every 100 s. Every output states it
/// exactly or within a millisecond a frame (a GIF's delays end at 655.35 s).
pub const MIN_FPS: f64 = 0.01;
/// Fastest frame rate, frames per second: far past any display, and whole rates up to it
/// fit every output's fraction.
pub const MAX_FPS: f64 = 1000.0;

/// Why `fps` cannot be a scene's frame rate (positive, within [`MIN_FPS`] and
/// [`MAX_FPS`]), if it cannot.
pub fn fps_error(fps: f64) -> Option<String> {
    if !(fps.is_finite() && fps > 0.0) {
        return Some(format!("fps must be > 0, got {}", crate::util::number_text(fps)));
    }
    let text = crate::util::number_text(fps);
    (!(MIN_FPS..=MAX_FPS).contains(&fps))
        .then(|| format!("fps must be between {MIN_FPS} and {MAX_FPS}, got {text}"))
}

/// Largest |coordinate| of a place a scene puts something (a patch's `at`, a handle's rest
/// point and target, a pin, a pivot; from calls or track files), px: a thousand times past
/// the raster's reach, and far enough from overflow that placed vertices stay finite.
pub const MAX_POSITION: f64 = 1e9;
/// Largest scale a patch may take: the largest source at this scale spans 1.6·10¹⁰ px, far
/// past any canvas, while its placed vertices stay finite (1e308 overflowed to ∞).
pub const MAX_SCALE: f64 = 1e6;

/// Largest |value| of a rotation (degrees) or a depth a scene keys: far past any use, and
/// far from overflow, so an eased key between two of them stays finite (keys of 1e308 and
/// −1e308 interpolated to ∞).
pub const MAX_ROTATION_OR_DEPTH: f64 = 1e9;

/// Why `v` cannot be a rotation or a depth ([`MAX_ROTATION_OR_DEPTH`]), if it cannot.
pub fn rotation_or_depth_error(v: f64) -> Option<String> {
    (v.abs() > MAX_ROTATION_OR_DEPTH).then(|| {
        let v = crate::util::number_text(v);
        format!("{v} is past ±{MAX_ROTATION_OR_DEPTH:e}")
    })
}

/// Why `v` cannot be a coordinate of a position ([`MAX_POSITION`]), if it cannot.
pub fn position_error(v: f64) -> Option<String> {
    (v.abs() > MAX_POSITION)
        .then(|| format!("{} is past ±{MAX_POSITION:e} px", crate::util::number_text(v)))
}

/// Why `v` cannot be a scale (positive, at most [`MAX_SCALE`]), if it cannot.
pub fn scale_error(v: f64) -> Option<String> {
    if v > 0.0 && v <= MAX_SCALE {
        return None;
    }
    let v_text = crate::util::number_text(v);
    Some(format!("{v_text} must be > 0 and at most {MAX_SCALE:e}"))
}

/// Heap the image decoder may allocate for one image: an RGBA 16-bit image at the pixel
/// limit (8 bytes per pixel) plus slack for the decoder's own buffers.
pub(crate) const MAX_DECODER_ALLOC: u64 = MAX_IMAGE_PIXELS * 8 + (64 << 20);

/// An input larger than the documented limits.
// Each variant's `#[error]` text says what it is and names its fields.
#[allow(missing_docs)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum LimitError {
    #[error(
        "{width}×{height} image exceeds the size limit (at most {MAX_IMAGE_SIDE} px per side \
         and {MAX_IMAGE_PIXELS} pixels; see docs/robustness.md)"
    )]
    ImageTooLarge { width: u64, height: u64 },
    #[error("{frames} frames exceed the limit of {MAX_FRAMES} frames per scene")]
    TooManyFrames { frames: u64 },
    #[error(
        "the scene's source images hold {pixels} pixels in all, over the limit of \
         {MAX_SCENE_SOURCE_PIXELS} (patches sharing a file count it once)"
    )]
    SceneSourcesTooLarge { pixels: u64 },
}

/// Why [`open_image`] failed.
#[derive(Debug, thiserror::Error)]
pub enum ImageOpenError {
    #[error("{0}")]
    Read(#[from] std::io::Error),
    #[error("{0}")]
    Decode(#[from] image::ImageError),
    #[error(transparent)]
    TooLarge(#[from] LimitError),
}

/// Refuses images wider or taller than [`MAX_IMAGE_SIDE`] or with more than
/// [`MAX_IMAGE_PIXELS`] pixels.
pub fn check_image_size(width: u64, height: u64) -> Result<(), LimitError> {
    let side = u64::from(MAX_IMAGE_SIDE);
    if width > side || height > side || width.saturating_mul(height) > MAX_IMAGE_PIXELS {
        return Err(LimitError::ImageTooLarge { width, height });
    }
    Ok(())
}

/// Adds a `width`×`height` source image to a scene's `total` source pixels, refusing a total
/// past [`MAX_SCENE_SOURCE_PIXELS`]. Called once per distinct source file.
pub fn add_scene_source(total: &mut u64, width: u32, height: u32) -> Result<(), LimitError> {
    *total = total.saturating_add(u64::from(width) * u64::from(height));
    if *total > MAX_SCENE_SOURCE_PIXELS {
        return Err(LimitError::SceneSourcesTooLarge { pixels: *total });
    }
    Ok(())
}

/// Whether `feather` (px) is a width lapclone accepts: finite, at least 0 and at most
/// [`MAX_FEATHER`]. Every place that takes a feather asks this.
pub fn feather_in_range(feather: f64) -> bool {
    (0.0..=MAX_FEATHER).contains(&feather)
}

/// Refuses scenes with more than [`MAX_FRAMES`] frames.
pub fn check_frame_count(frames: u64) -> Result<(), LimitError> {
    if frames > MAX_FRAMES {
        return Err(LimitError::TooManyFrames { frames });
    }
    Ok(())
}

/// The width and height in an image file's header (format guessed from its content),
/// without decoding its pixels.
pub fn image_dimensions(path: &Path) -> Result<(u32, u32), ImageOpenError> {
    let mut reader = image_reader(path)?;
    // Only the header is read here; its size is judged by `check_image_size`, whose message
    // names the limit. The decoder's default allocation limit would refuse a huge header
    // first, as "Memory limit exceeded".
    reader.no_limits();
    Ok(reader.into_dimensions()?)
}

/// A reader of the image file `path` (a regular file: see
/// [`open_input_file`](crate::util::open_input_file)), its format guessed from its content,
/// else from its extension.
fn image_reader(
    path: &Path,
) -> Result<image::ImageReader<std::io::BufReader<std::fs::File>>, ImageOpenError> {
    let file = crate::util::open_input_file(path)?;
    let mut reader = image::ImageReader::new(std::io::BufReader::new(file));
    if let Ok(format) = image::ImageFormat::from_path(path) {
        reader.set_format(format);
    }
    Ok(reader.with_guessed_format()?)
}

/// Reads an image file whose header passes [`check_image_size`]; the decoder runs with
/// matching allocation limits, so a header that lies cannot make it allocate more. A JPEG
/// is read once: its bytes are checked to be whole, then decoded.
pub fn open_image(path: &Path) -> Result<image::DynamicImage, ImageOpenError> {
    let (width, height) = image_dimensions(path)?;
    check_image_size(u64::from(width), u64::from(height))?;
    let reader = image_reader(path)?;
    if reader.format() != Some(image::ImageFormat::Jpeg) {
        return decode_within_limits(reader);
    }
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(&mut reader.into_inner(), &mut bytes)?;
    // The JPEG decoder fills what a cut-short file lacks with grey and says nothing.
    if !jpeg_is_whole(&bytes) {
        let format = image::error::ImageFormatHint::Exact(image::ImageFormat::Jpeg);
        let cut = "the file is cut short: its data ends before the end-of-image marker";
        return Err(image::ImageError::Decoding(image::error::DecodingError::new(format, cut)).into());
    }
    let cursor = std::io::Cursor::new(bytes);
    decode_within_limits(image::ImageReader::with_format(cursor, image::ImageFormat::Jpeg))
}

/// Decodes with the size and allocation limits of [`open_image`].
fn decode_within_limits<R: std::io::BufRead + std::io::Seek>(
    mut reader: image::ImageReader<R>,
) -> Result<image::DynamicImage, ImageOpenError> {
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_IMAGE_SIDE);
    limits.max_image_height = Some(MAX_IMAGE_SIDE);
    limits.max_alloc = Some(MAX_DECODER_ALLOC);
    reader.limits(limits);
    Ok(reader.decode()?)
}

/// Whether the JPEG file's bytes hold an end-of-image marker (`FF D9`) after its start of
/// scan. The segments before the scan are skipped by their lengths (an EXIF thumbnail is a
/// JPEG of its own, markers and all); inside the scan data every `FF` byte is stuffed or
/// starts a marker, so the first `FF D9` there ends the image, and data after it (a motion
/// photo's video) is allowed. A file this walk does not understand is left to the decoder.
fn jpeg_is_whole(b: &[u8]) -> bool {
    if !b.starts_with(&[0xFF, 0xD8]) {
        return true;
    }
    let mut at = 2;
    loop {
        match b.get(at..at + 2) {
            None => return false,
            Some(&[0xFF, 0xFF]) => at += 1,
            Some(&[0xFF, 0xD9]) => return true,
            Some(&[0xFF, 0x01 | 0xD0..=0xD8]) => at += 2,
            Some(&[0xFF, marker]) => {
                let Some(&[high, low]) = b.get(at + 2..at + 4) else {
                    return false;
                };
                at += 2 + usize::from(u16::from_be_bytes([high, low]));
                if marker == 0xDA {
                    let scan = b.get(at..).unwrap_or_default();
                    return scan.windows(2).any(|w| w == [0xFF, 0xD9]);
                }
            }
            Some(_) => return true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_s_source_pixels_are_bounded_in_all() {
        let mut total = 0;
        for _ in 0..8 {
            add_scene_source(&mut total, 8192, 8192).unwrap();
        }
        assert_eq!(total, MAX_SCENE_SOURCE_PIXELS);
        assert!(add_scene_source(&mut total, 1, 1).is_err());
        let mut huge = u64::MAX - 1;
        assert!(add_scene_source(&mut huge, u32::MAX, u32::MAX).is_err());
    }

    #[test]
    fn a_jpeg_cut_short_is_refused_and_a_whole_one_read() {
        let dir = tempfile::tempdir().unwrap();
        let whole = dir.path().join("whole.jpg");
        let image = image::RgbImage::from_fn(64, 48, |x, y| image::Rgb([x as u8 * 3, y as u8 * 5, 90]));
        image.save(&whole).unwrap();
        // Read once and decoded from memory, the pixels the decoder gives from the file.
        let read = open_image(&whole).unwrap();
        assert!(read == image::open(&whole).unwrap());
        let bytes = std::fs::read(&whole).unwrap();
        // Something after the image (a motion photo's video) is allowed.
        let trailed = dir.path().join("trailed.jpg");
        std::fs::write(&trailed, [&bytes[..], b"ftypmp42 and more"].concat()).unwrap();
        assert!(open_image(&trailed).is_ok());
        let cut = dir.path().join("cut.jpg");
        std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
        let error = open_image(&cut).unwrap_err().to_string();
        assert!(error.contains("cut short"), "{error}");
        // A thumbnail in an APP1 segment, whole with markers of its own, does not hide the cut.
        let thumb = [0xFF, 0xD8, 0xFF, 0xDA, 0x00, 0x02, 0x11, 0xFF, 0xD9];
        let mut app1 = vec![0xFF, 0xE1, 0x00, (thumb.len() + 2) as u8];
        app1.extend_from_slice(&thumb);
        let cut_with_thumb = dir.path().join("thumb.jpg");
        let body = &bytes[2..bytes.len() * 2 / 3];
        std::fs::write(&cut_with_thumb, [&bytes[..2], &app1[..], body].concat()).unwrap();
        let error = open_image(&cut_with_thumb).unwrap_err().to_string();
        assert!(error.contains("cut short"), "{error}");
    }
}
