//! Pixels shared by all stages: takes image files or `image::DynamicImage`s in and gives
//! [`FloatImage`]s (straight RGBA values in [0, 1], for sources and targets as loaded; 8-bit
//! images keep their levels, 8-bit PNGs decoded straight into them) and [`Canvas`]es (the
//! frame being composited, in the target's output bit depth), plus PNG output in the
//! target's original [`PixelFormat`], and [`footage`]: numbered image sequences and videos
//! read one frame at a time.
//!
//! Coordinates follow the mesh convention: x right, y down, pixel (i, j) covers
//! [i, i+1] × [j, j+1] and its centre is (i + 0.5, j + 0.5); bilinear sampling is exact at
//! pixel centres and clamps to the edge outside the image.
//!
//! 16-bit output: tiny-skia only holds 8-bit premultiplied pixmaps, so 16-bit canvases are
//! stored as `u16` here and encoded through `png_bands` like 8-bit ones; an 8-bit copy
//! ([`Canvas::to_rgba8_image`]) exists for overlays (a 16-bit canvas is rounded to 8 bits).

mod bilinear;
mod canvas;
mod error;
mod float_image;
pub mod footage;
mod format;
mod png_decode;
mod png_encode;
mod rect;

pub use bilinear::sample_bilinear_rgba;
pub(crate) use canvas::composite_over_straight as canvas_composite_over;
pub use canvas::{Canvas, CanvasPixels, Texel};
pub use error::PixelError;
pub use float_image::FloatImage;
pub(crate) use float_image::open_error;
pub(crate) use png_decode::decode_png_levels;
pub use footage::{Footage, FootageError, FootageReader, FootageSource};
pub use format::{ColorKind, Depth, PixelFormat};
pub use rect::PixelRect;
