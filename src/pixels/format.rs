//! Pixel formats: takes an `image::DynamicImage` and gives the [`PixelFormat`] (grey or RGB,
//! alpha or not, 8 or 16 bit) that output PNGs reproduce, and an 8-bit image's pixels as
//! RGBA levels.

/// Colour model of an image file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ColorKind {
    /// One grey channel.
    Grey,
    /// Red, green, blue.
    Rgb,
}

/// Bits per channel of an image file (32-bit float inputs count as 16-bit for output).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Depth {
    /// 8 bits per channel.
    Eight,
    /// 16 bits per channel.
    Sixteen,
}

/// The format an image was stored in, kept so the output matches the target's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PixelFormat {
    /// Grey or RGB.
    pub color: ColorKind,
    /// Whether there is an alpha channel.
    pub alpha: bool,
    /// Bits per channel.
    pub depth: Depth,
}

impl PixelFormat {
    /// 8-bit RGBA.
    pub const RGBA8: PixelFormat = PixelFormat {
        color: ColorKind::Rgb,
        alpha: true,
        depth: Depth::Eight,
    };
    /// 16-bit RGBA.
    pub const RGBA16: PixelFormat = PixelFormat {
        color: ColorKind::Rgb,
        alpha: true,
        depth: Depth::Sixteen,
    };

    /// Detects the format of a decoded image.
    pub fn of(image: &image::DynamicImage) -> PixelFormat {
        let color_type = image.color();
        let channels = u16::from(color_type.channel_count()).max(1);
        let bytes_per_channel = u16::from(color_type.bytes_per_pixel()) / channels;
        PixelFormat {
            color: if color_type.has_color() {
                ColorKind::Rgb
            } else {
                ColorKind::Grey
            },
            alpha: color_type.has_alpha(),
            depth: if bytes_per_channel <= 1 {
                Depth::Eight
            } else {
                Depth::Sixteen
            },
        }
    }

    /// Channels per pixel in a file of this format.
    pub fn channel_count(self) -> usize {
        let colour = match self.color {
            ColorKind::Grey => 1,
            ColorKind::Rgb => 3,
        };
        colour + usize::from(self.alpha)
    }
}

/// A decoded 8-bit image's pixels as straight RGBA levels, row-major (grey expanded to
/// R = G = B, a missing alpha 255): the levels `to_rgba8` gives, without its colour-space
/// path. `None` for other depths.
pub(crate) fn rgba8_levels(decoded: &image::DynamicImage) -> Option<Vec<[u8; 4]>> {
    let format = PixelFormat::of(decoded);
    if format.depth != Depth::Eight {
        return None;
    }
    let mut levels = Vec::with_capacity(decoded.width() as usize * decoded.height() as usize);
    extend_rgba8(decoded.as_bytes(), format, &mut levels);
    Some(levels)
}

/// Appends 8-bit samples laid out as `format` says (grey or RGB, alpha or not) to `out` as
/// RGBA levels: grey expanded to R = G = B, a missing alpha 255.
pub(crate) fn extend_rgba8(samples: &[u8], format: PixelFormat, out: &mut Vec<[u8; 4]>) {
    match (format.color, format.alpha) {
        (ColorKind::Rgb, false) => {
            let start = out.len();
            out.resize(start + samples.len() / 3, [0; 4]);
            crate::simd::rgb8_to_levels(samples, false, &mut out[start..]);
        }
        (ColorKind::Rgb, true) => out.extend_from_slice(bytemuck::cast_slice(samples)),
        (ColorKind::Grey, false) => out.extend(samples.iter().map(|&l| [l, l, l, 255])),
        (ColorKind::Grey, true) => {
            out.extend(samples.chunks_exact(2).map(|p| [p[0], p[0], p[0], p[1]]))
        }
    }
}
