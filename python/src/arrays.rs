//! numpy arrays in and out: takes an H×W or H×W×C (C = 1, 3, 4) `uint8`/`uint16` array,
//! contiguous or not, in RGB or BGR order, and gives the `image::DynamicImage` lapclone reads
//! (the same one a PNG of those pixels decodes to); takes a canvas's samples and gives an
//! array of the input's dtype, shape and channel order back. Anything else is a `ValueError`
//! (`TypeError` for what is not an array), never a crash.

use lapclone::image::{DynamicImage, ImageBuffer, Luma, Rgb, Rgba};
use lapclone::{Canvas, CanvasPixels, ColorKind, Depth, PixelFormat};
use numpy::ndarray::{ArrayViewD, ArrayViewMut3, Axis, Ix3};
use numpy::{
    Element, PyArray2, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

/// The sample type of an array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dtype {
    U8,
    U16,
}

impl Dtype {
    /// numpy's name of the dtype, as messages give it.
    pub fn name(self) -> &'static str {
        match self {
            Dtype::U8 => "uint8",
            Dtype::U16 => "uint16",
        }
    }
}

/// A shape (or strides) as numpy writes it: `(64, 96, 3)`, `(5,)`, `()`.
fn tuple_text<T: std::fmt::Display>(items: &[T]) -> String {
    match items {
        [one] => format!("({one},)"),
        _ => {
            let items: Vec<String> = items.iter().map(T::to_string).collect();
            format!("({})", items.join(", "))
        }
    }
}

/// An input array's layout, given back to outputs: rows, columns, channels (`None` for a
/// 2-D grey array) and sample type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub height: usize,
    pub width: usize,
    pub channels: Option<usize>,
    pub dtype: Dtype,
}

impl Layout {
    /// Channels per pixel (1 for a 2-D array).
    pub fn channel_count(&self) -> usize {
        self.channels.unwrap_or(1)
    }

    /// The PNG format an image of this layout has: what outputs are written in.
    pub fn format(&self) -> PixelFormat {
        let c = self.channel_count();
        PixelFormat {
            color: if c >= 3 {
                ColorKind::Rgb
            } else {
                ColorKind::Grey
            },
            alpha: c == 4,
            depth: match self.dtype {
                Dtype::U8 => Depth::Eight,
                Dtype::U16 => Depth::Sixteen,
            },
        }
    }

    /// The array's shape as numpy writes it: `(height, width)` or `(height, width, channels)`.
    fn shape_text(&self) -> String {
        match self.channels {
            None => tuple_text(&[self.height, self.width]),
            Some(c) => tuple_text(&[self.height, self.width, c]),
        }
    }
}

/// An input image: the decoded image lapclone reads and the layout it came in.
pub struct Picture {
    pub image: DynamicImage,
    pub layout: Layout,
}

/// The array behind `object`, or a `TypeError` naming `what`.
fn untyped<'py>(object: &Bound<'py, PyAny>, what: &str) -> PyResult<Bound<'py, PyUntypedArray>> {
    object.downcast::<PyUntypedArray>().cloned().map_err(|_| {
        let kind = object
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_default();
        PyTypeError::new_err(format!("{what} must be a numpy array, not {kind}"))
    })
}

/// The layout of an image array: dtype uint8/uint16 (and bool when `allow_bool`), 2 or 3
/// dimensions, 1, 3 or 4 channels, no empty side.
pub fn layout_of(object: &Bound<'_, PyAny>, what: &str, allow_bool: bool) -> PyResult<Layout> {
    let array = untyped(object, what)?;
    let py = object.py();
    let dtype = array.dtype();
    let dtype = if dtype.is_equiv_to(&numpy::dtype::<u8>(py))
        || (allow_bool && dtype.is_equiv_to(&numpy::dtype::<bool>(py)))
    {
        Dtype::U8
    } else if dtype.is_equiv_to(&numpy::dtype::<u16>(py)) {
        Dtype::U16
    } else {
        let allowed = if allow_bool {
            "uint8, uint16 or bool"
        } else {
            "uint8 or uint16"
        };
        return Err(PyValueError::new_err(format!(
            "{what} must have dtype {allowed}, not {dtype}"
        )));
    };
    let shape = array.shape();
    let (height, width, channels) = match *shape {
        [h, w] => (h, w, None),
        [h, w, c] if matches!(c, 1 | 3 | 4) => (h, w, Some(c)),
        _ => {
            return Err(PyValueError::new_err(format!(
                "{what} must have shape (H, W) (grey) or (H, W, C) with C = 1, 3 or 4, not {}",
                tuple_text(shape)
            )))
        }
    };
    if height == 0 || width == 0 {
        return Err(PyValueError::new_err(format!(
            "{what} is empty: shape {}",
            tuple_text(shape)
        )));
    }
    // The limits of every image lapclone reads, before anything of that size is allocated.
    if lapclone::check_image_size(width as u64, height as u64).is_err() {
        return Err(PyValueError::new_err(format!(
            "{what} of shape {} exceeds the image size limit (at most {} px per side and {} \
             pixels)",
            tuple_text(shape),
            lapclone::MAX_IMAGE_SIDE,
            lapclone::MAX_IMAGE_PIXELS
        )));
    }
    // A view into packed records (a uint16 field after a byte) steps by part of a sample;
    // numpy's strides in bytes would be read as whole samples.
    let itemsize = array.dtype().itemsize() as isize;
    if array.strides().iter().any(|s| s % itemsize != 0) {
        return Err(PyValueError::new_err(format!(
            "{what} steps by fractions of a sample (strides {} bytes for {itemsize}-byte \
             samples); pass numpy.ascontiguousarray({what})",
            tuple_text(array.strides())
        )));
    }
    Ok(Layout {
        height,
        width,
        channels,
        dtype,
    })
}

/// The samples of an array of element type `T`, row-major and interleaved, in RGB order
/// (BGR arrays' first and third channels swapped).
fn samples<T: Element + Copy>(
    object: &Bound<'_, PyAny>,
    layout: &Layout,
    bgr: bool,
) -> PyResult<Vec<T>> {
    let array = object.downcast::<PyArrayDyn<T>>()?;
    let readonly = array
        .try_readonly()
        .map_err(|e| PyValueError::new_err(format!("the array cannot be read now: {e}")))?;
    let view: ArrayViewD<'_, T> = readonly.as_array();
    let mut out: Vec<T> = match view.as_slice() {
        Some(slice) => slice.to_vec(),
        None => view.iter().copied().collect(),
    };
    if bgr && layout.channel_count() >= 3 {
        for pixel in out.chunks_exact_mut(layout.channel_count()) {
            pixel.swap(0, 2);
        }
    }
    Ok(out)
}

/// Reads an image array (see [`layout_of`]) as the decoded image a PNG of it gives.
pub fn read_picture(object: &Bound<'_, PyAny>, what: &str, bgr: bool) -> PyResult<Picture> {
    read_with(object, what, bgr, false)
}

/// Reads a mask: as [`read_picture`], bool arrays too (`True` = 255).
pub fn read_mask(object: &Bound<'_, PyAny>, what: &str, bgr: bool) -> PyResult<Picture> {
    read_with(object, what, bgr, true)
}

fn read_with(
    object: &Bound<'_, PyAny>,
    what: &str,
    bgr: bool,
    allow_bool: bool,
) -> PyResult<Picture> {
    let layout = layout_of(object, what, allow_bool)?;
    let py = object.py();
    let (w, h) = (layout.width as u32, layout.height as u32);
    let untyped = untyped(object, what)?;
    let image = if untyped.dtype().is_equiv_to(&numpy::dtype::<bool>(py)) {
        // Read as the bytes they are: numpy takes any nonzero byte as True (a 0/255 mask
        // viewed as bool), which a Rust `bool` may not hold.
        let bytes = object.call_method1("view", ("uint8",))?;
        let bytes: Vec<u8> = samples(&bytes, &layout, false)?;
        let bytes = bytes
            .iter()
            .map(|&b| if b != 0 { 255 } else { 0 })
            .collect();
        eight_bit(w, h, layout.channel_count(), bytes)
    } else if layout.dtype == Dtype::U8 {
        eight_bit(w, h, layout.channel_count(), samples(object, &layout, bgr)?)
    } else {
        sixteen_bit(w, h, layout.channel_count(), samples(object, &layout, bgr)?)
    };
    let image = image.ok_or_else(|| PyValueError::new_err(format!("{what}: bad buffer size")))?;
    Ok(Picture { image, layout })
}

fn eight_bit(w: u32, h: u32, channels: usize, bytes: Vec<u8>) -> Option<DynamicImage> {
    Some(match channels {
        1 => DynamicImage::ImageLuma8(ImageBuffer::<Luma<u8>, _>::from_raw(w, h, bytes)?),
        3 => DynamicImage::ImageRgb8(ImageBuffer::<Rgb<u8>, _>::from_raw(w, h, bytes)?),
        _ => DynamicImage::ImageRgba8(ImageBuffer::<Rgba<u8>, _>::from_raw(w, h, bytes)?),
    })
}

fn sixteen_bit(w: u32, h: u32, channels: usize, words: Vec<u16>) -> Option<DynamicImage> {
    Some(match channels {
        1 => DynamicImage::ImageLuma16(ImageBuffer::<Luma<u16>, _>::from_raw(w, h, words)?),
        3 => DynamicImage::ImageRgb16(ImageBuffer::<Rgb<u16>, _>::from_raw(w, h, words)?),
        _ => DynamicImage::ImageRgba16(ImageBuffer::<Rgba<u16>, _>::from_raw(w, h, words)?),
    })
}

/// The rectangle of pixels `x0..x1` × `y0..y1` a clone read or changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

/// Copies the pixels of `rect` from a target array into `canvas` (same size and depth), as
/// [`Canvas::from_dynamic`] would make them: grey spread to R = G = B, a missing alpha
/// opaque, BGR reordered.
pub fn load_rect(
    object: &Bound<'_, PyAny>,
    layout: &Layout,
    bgr: bool,
    canvas: &mut Canvas,
    rect: Rect,
) -> PyResult<()> {
    match layout.dtype {
        Dtype::U8 => load_rect_typed::<u8>(object, layout, bgr, canvas, rect, u8::MAX),
        Dtype::U16 => load_rect_typed::<u16>(object, layout, bgr, canvas, rect, u16::MAX),
    }
}

fn load_rect_typed<T: Element + Copy + CanvasTexel>(
    object: &Bound<'_, PyAny>,
    layout: &Layout,
    bgr: bool,
    canvas: &mut Canvas,
    rect: Rect,
    opaque: T,
) -> PyResult<()> {
    let array = object.downcast::<PyArrayDyn<T>>()?;
    let readonly = array
        .try_readonly()
        .map_err(|e| PyValueError::new_err(format!("the target cannot be read now: {e}")))?;
    let view = readonly.as_array();
    let view = match view.ndim() {
        2 => view.insert_axis(Axis(2)),
        _ => view,
    };
    let view = view
        .into_dimensionality::<Ix3>()
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let width = layout.width;
    let pixels = T::texels_mut(canvas).ok_or_else(|| {
        PyValueError::new_err("the target's depth changed between frames".to_string())
    })?;
    let channels = layout.channel_count();
    let (red, blue) = if bgr && channels >= 3 { (2, 0) } else { (0, 2) };
    let texel = |px: &[T]| gather(px, channels, (red, blue), opaque);
    let (x0, x1) = (rect.x0 as usize, rect.x1 as usize);
    for y in rect.y0 as usize..rect.y1 as usize {
        let row = view.index_axis(Axis(0), y);
        let out = &mut pixels[y * width + x0..y * width + x1];
        match row.as_slice() {
            // A contiguous row (the usual case): its samples in place.
            Some(samples) => {
                let samples = &samples[x0 * channels..x1 * channels];
                match channels {
                    1 => load_row::<T, 1>(out, samples, (red, blue), opaque),
                    3 => T::load_rgb_row(out, samples, (red, blue), opaque),
                    _ => load_row::<T, 4>(out, samples, (red, blue), opaque),
                }
            }
            None => {
                for (t, x) in out.iter_mut().zip(x0..) {
                    let mut px = [opaque; 4];
                    for (k, &v) in row.index_axis(Axis(0), x).iter().enumerate() {
                        px[k] = v;
                    }
                    *t = texel(&px);
                }
            }
        }
    }
    Ok(())
}

/// Canvas storage of one sample type.
pub trait CanvasTexel: Copy + Sized {
    fn texels_mut(canvas: &mut Canvas) -> Option<&mut Vec<[Self; 4]>>;

    /// One contiguous row of three-sample pixels into texels, red and blue read from the
    /// indices `red_blue`, alpha `opaque`.
    fn load_rgb_row(
        out: &mut [[Self; 4]],
        samples: &[Self],
        red_blue: (usize, usize),
        opaque: Self,
    ) {
        load_row::<Self, 3>(out, samples, red_blue, opaque);
    }

    /// Texels into one contiguous row of three-sample pixels, red and blue swapped for `bgr`.
    fn write_rgb_row(dst: &mut [Self], row: &[[Self; 4]], bgr: bool) {
        let order = if bgr { [2, 1, 0, 3] } else { [0, 1, 2, 3] };
        texels_into_row::<Self, 3>(dst, row, order);
    }
}

impl CanvasTexel for u8 {
    fn texels_mut(canvas: &mut Canvas) -> Option<&mut Vec<[u8; 4]>> {
        match canvas.pixels_mut() {
            lapclone::CanvasPixels::Eight(p) => Some(p),
            _ => None,
        }
    }

    // 8-bit rows go through lapclone's converters, compiled for this CPU's vector unit (the
    // plain loop has no byte shuffle at the baseline instruction set). Opaque is 255 here.
    fn load_rgb_row(out: &mut [[u8; 4]], samples: &[u8], (red, _): (usize, usize), _: u8) {
        lapclone::rgb8_to_levels(samples, red == 2, out);
    }

    fn write_rgb_row(dst: &mut [u8], row: &[[u8; 4]], bgr: bool) {
        lapclone::levels_to_rgb8(row, bgr, dst);
    }
}

impl CanvasTexel for u16 {
    fn texels_mut(canvas: &mut Canvas) -> Option<&mut Vec<[u16; 4]>> {
        match canvas.pixels_mut() {
            lapclone::CanvasPixels::Sixteen(p) => Some(p),
            _ => None,
        }
    }
}

/// Samples in `layout`'s format (8-bit, or 16-bit big-endian as [`Canvas::samples`] gives
/// them) as an array of its dtype, shape and channel order.
pub fn new_array<'py>(
    py: Python<'py>,
    samples: Vec<u8>,
    layout: &Layout,
    bgr: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let (h, w, c) = (layout.height, layout.width, layout.channel_count());
    match layout.dtype {
        Dtype::U8 => shaped(py, reorder(samples, c, bgr), h, w, layout.channels),
        Dtype::U16 => shaped(py, reorder(words(&samples), c, bgr), h, w, layout.channels),
    }
}

fn words(samples: &[u8]) -> Vec<u16> {
    samples
        .chunks_exact(2)
        .map(|b| u16::from_be_bytes([b[0], b[1]]))
        .collect()
}

fn reorder<T>(mut samples: Vec<T>, channels: usize, bgr: bool) -> Vec<T> {
    if bgr && channels >= 3 {
        for pixel in samples.chunks_exact_mut(channels) {
            pixel.swap(0, 2);
        }
    }
    samples
}

fn shaped<'py, T: Element>(
    py: Python<'py>,
    data: Vec<T>,
    h: usize,
    w: usize,
    channels: Option<usize>,
) -> PyResult<Bound<'py, PyAny>> {
    let flat = numpy::PyArray1::from_vec(py, data);
    Ok(match channels {
        None => flat.reshape([h, w])?.into_any(),
        Some(c) => flat.reshape([h, w, c])?.into_any(),
    })
}

/// Writes samples of the `rect` part of an image in `layout` (as [`Canvas::samples_in`]
/// gives them) into the same part of `array`, which has that layout.
fn write_rect(
    array: &Bound<'_, PyAny>,
    layout: &Layout,
    bgr: bool,
    samples: &[u8],
    rect: Rect,
) -> PyResult<()> {
    match layout.dtype {
        Dtype::U8 => write_rect_typed(array, layout, bgr, samples, rect),
        Dtype::U16 => write_rect_typed(array, layout, bgr, &words(samples), rect),
    }
}

/// The output array borrowed for writing, or why it cannot be.
fn writable<'py, T: Element>(
    array: &Bound<'py, PyAny>,
) -> PyResult<numpy::PyReadwriteArrayDyn<'py, T>> {
    array
        .downcast::<PyArrayDyn<T>>()?
        .try_readwrite()
        .map_err(|e| PyValueError::new_err(format!("out cannot be written: {e}")))
}

fn write_rect_typed<T: Element + Copy>(
    array: &Bound<'_, PyAny>,
    layout: &Layout,
    bgr: bool,
    samples: &[T],
    rect: Rect,
) -> PyResult<()> {
    let mut writable = writable(array)?;
    let view = writable.as_array_mut();
    let view = match view.ndim() {
        2 => view.insert_axis(Axis(2)),
        _ => view,
    };
    let mut view: ArrayViewMut3<'_, T> = view
        .into_dimensionality::<Ix3>()
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let c = layout.channel_count();
    let columns = (rect.x1 - rect.x0) as usize;
    if columns == 0 {
        return Ok(());
    }
    let (red, blue) = if bgr && c >= 3 { (2, 0) } else { (0, 2) };
    let channel = |k: usize| match k {
        0 => red,
        2 => blue,
        other => other,
    };
    let x0 = rect.x0 as usize;
    for (row, y) in samples.chunks_exact(columns * c).zip(rect.y0..rect.y1) {
        let mut out = view.index_axis_mut(Axis(0), y as usize);
        match out.as_slice_mut() {
            // A contiguous row (the usual case): written in place.
            Some(dst) => {
                let dst = &mut dst[x0 * c..(x0 + columns) * c];
                match c {
                    1 => write_row::<T, 1>(dst, row, channel),
                    3 => write_row::<T, 3>(dst, row, channel),
                    _ => write_row::<T, 4>(dst, row, channel),
                }
            }
            None => {
                for (pixel, x) in row.chunks_exact(c).zip(x0..) {
                    let mut d = out.index_axis_mut(Axis(0), x);
                    for (k, &value) in pixel.iter().enumerate() {
                        d[channel(k)] = value;
                    }
                }
            }
        }
    }
    Ok(())
}

/// Writes the canvas's `rect` into `array` (of `layout`, which the canvas was loaded from):
/// the samples [`Canvas::samples_in`] gives for the layout's format. RGB(A) canvas texels
/// of the array's depth are those samples, so they are copied straight into the array;
/// grey arrays take the canvas's luma through `samples_in`.
pub fn write_canvas_rect(
    array: &Bound<'_, PyAny>,
    layout: &Layout,
    bgr: bool,
    canvas: &Canvas,
    rect: Rect,
) -> PyResult<()> {
    if layout.channel_count() >= 3 {
        match (canvas.pixels(), layout.dtype) {
            (CanvasPixels::Eight(p), Dtype::U8) => {
                return write_texels(array, layout, bgr, p, canvas.width(), rect)
            }
            (CanvasPixels::Sixteen(p), Dtype::U16) => {
                return write_texels(array, layout, bgr, p, canvas.width(), rect)
            }
            _ => {}
        }
    }
    let samples = canvas.samples_in(layout.format(), rect.x0..rect.x1, rect.y0..rect.y1);
    write_rect(array, layout, bgr, &samples, rect)
}

/// [`write_canvas_rect`] for RGB(A) arrays of the canvas's depth: each texel's first
/// `channels` values, red and blue swapped for `bgr`.
fn write_texels<T: Element + CanvasTexel>(
    array: &Bound<'_, PyAny>,
    layout: &Layout,
    bgr: bool,
    texels: &[[T; 4]],
    canvas_width: u32,
    rect: Rect,
) -> PyResult<()> {
    let mut writable = writable(array)?;
    let mut view: ArrayViewMut3<'_, T> = writable
        .as_array_mut()
        .into_dimensionality::<Ix3>()
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let c = layout.channel_count();
    let (x0, x1) = (rect.x0 as usize, rect.x1 as usize);
    let order = if bgr { [2, 1, 0, 3] } else { [0, 1, 2, 3] };
    let width = canvas_width as usize;
    for y in rect.y0 as usize..rect.y1 as usize {
        let row = &texels[y * width + x0..y * width + x1];
        let mut out = view.index_axis_mut(Axis(0), y);
        match out.as_slice_mut() {
            // A contiguous row (the usual case): written in place.
            Some(dst) => {
                let dst = &mut dst[x0 * c..x1 * c];
                match c {
                    3 => T::write_rgb_row(dst, row, bgr),
                    _ => texels_into_row::<T, 4>(dst, row, order),
                }
            }
            None => {
                for (texel, x) in row.iter().zip(x0..) {
                    let mut d = out.index_axis_mut(Axis(0), x);
                    for k in 0..c {
                        d[k] = texel[order[k]];
                    }
                }
            }
        }
    }
    Ok(())
}

/// Canvas texels into one contiguous array row of `C` channels, array channel `k` from
/// texel channel `order[k]`.
#[inline]
fn texels_into_row<T: Copy, const C: usize>(dst: &mut [T], row: &[[T; 4]], order: [usize; 4]) {
    for (d, texel) in dst.chunks_exact_mut(C).zip(row) {
        for k in 0..C {
            d[k] = texel[order[k]];
        }
    }
}

/// One contiguous row of `C`-channel samples into canvas texels. The channel count is a
/// constant so each pixel's gather compiles to fixed moves instead of a loop.
#[inline]
fn load_row<T: Copy, const C: usize>(
    out: &mut [[T; 4]],
    samples: &[T],
    red_blue: (usize, usize),
    opaque: T,
) {
    for (t, px) in out.iter_mut().zip(samples.chunks_exact(C)) {
        *t = gather(px, C, red_blue, opaque);
    }
}

/// The canvas texel of one pixel's `channels` samples (grey spread to RGB, no alpha
/// opaque), reading red and blue from the indices `red_blue`.
#[inline(always)]
fn gather<T: Copy>(px: &[T], channels: usize, (red, blue): (usize, usize), opaque: T) -> [T; 4] {
    match channels {
        1 => [px[0], px[0], px[0], opaque],
        3 => [px[red], px[1], px[blue], opaque],
        _ => [px[red], px[1], px[blue], px[3]],
    }
}

/// One contiguous row of `C`-channel samples into an array row, channel `k` to
/// `channel(k)`; the channel count is a constant for the same reason as in [`load_row`].
#[inline]
fn write_row<T: Copy, const C: usize>(dst: &mut [T], row: &[T], channel: impl Fn(usize) -> usize) {
    for (d, pixel) in dst.chunks_exact_mut(C).zip(row.chunks_exact(C)) {
        for (k, &value) in pixel.iter().enumerate() {
            d[channel(k)] = value;
        }
    }
}

/// Checks that `object` still has `layout`: Python code run during a call (a number's
/// `__float__`, another thread between the call's steps) may have reshaped it.
pub fn check_unchanged(object: &Bound<'_, PyAny>, layout: &Layout, what: &str) -> PyResult<()> {
    if layout_of(object, what, false)? != *layout {
        return Err(PyValueError::new_err(format!(
            "{what} changed shape or dtype during the call"
        )));
    }
    Ok(())
}

/// A copy of the array `object` as a plain numpy array (not a subclass, whose `copy` could
/// run any code).
pub fn plain_copy<'py>(object: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let py = object.py();
    let order = pyo3::types::PyDict::new(py);
    order.set_item("order", "C")?;
    py.import("numpy")?
        .call_method("array", (object,), Some(&order))
}

/// Checks that `out` is a writable array of exactly `layout`.
pub fn check_out(out: &Bound<'_, PyAny>, layout: &Layout) -> PyResult<()> {
    let out_layout = layout_of(out, "out", false)?;
    if out_layout != *layout {
        return Err(PyValueError::new_err(format!(
            "out must be a {} array of shape {}, as the target is, not a {} array of shape {}",
            layout.dtype.name(),
            layout.shape_text(),
            out_layout.dtype.name(),
            out_layout.shape_text()
        )));
    }
    Ok(())
}

/// Copies a whole array of `layout` into `out` (same layout), for a clone written into
/// `out` rather than a new array.
pub fn copy_into(
    source: &Bound<'_, PyAny>,
    out: &Bound<'_, PyAny>,
    layout: &Layout,
) -> PyResult<()> {
    if source.is(out) {
        return Ok(());
    }
    match layout.dtype {
        Dtype::U8 => copy_typed::<u8>(source, out),
        Dtype::U16 => copy_typed::<u16>(source, out),
    }
}

fn copy_typed<T: Element + Copy>(
    source: &Bound<'_, PyAny>,
    out: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let source = source.downcast::<PyArrayDyn<T>>()?;
    let out = out.downcast::<PyArrayDyn<T>>()?;
    let unwritable = |e| PyValueError::new_err(format!("out cannot be written: {e}"));
    let copy = {
        let readonly = source
            .try_readonly()
            .map_err(|e| PyValueError::new_err(format!("the target cannot be read now: {e}")))?;
        match out.try_readwrite() {
            Ok(mut writable) => {
                let (from, mut to) = (readonly.as_array(), writable.as_array_mut());
                match (from.as_slice(), to.as_slice_mut()) {
                    (Some(from), Some(to)) => to.copy_from_slice(from),
                    _ => to.assign(&from),
                }
                return Ok(());
            }
            // `out` shares memory with the target under another view: through a buffer.
            Err(_) => readonly.as_array().to_owned(),
        }
    };
    out.try_readwrite()
        .map_err(unwritable)?
        .as_array_mut()
        .assign(&copy);
    Ok(())
}

/// A mesh's vertices (N×2 float64) and triangles (M×3 uint32).
pub type MeshArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<u32>>);

/// An N×2 float64 and an M×3 uint32 array: a mesh's vertices and triangles.
pub fn mesh_arrays<'py>(
    py: Python<'py>,
    vertices: &[[f64; 2]],
    triangles: &[[u32; 3]],
) -> PyResult<MeshArrays<'py>> {
    let v: Vec<f64> = vertices.iter().flatten().copied().collect();
    let t: Vec<u32> = triangles.iter().flatten().copied().collect();
    let v = numpy::PyArray1::from_vec(py, v).reshape([vertices.len(), 2])?;
    let t = numpy::PyArray1::from_vec(py, t).reshape([triangles.len(), 3])?;
    Ok((v, t))
}
