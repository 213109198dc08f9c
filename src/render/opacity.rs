//! Layer opacity: takes the frame just after a layer was cloned onto it, a copy of the frame
//! before (the layers below), the rectangle the layer drew into and an opacity in (0, 1),
//! and gives the frame with the layer blended over the layers below, per pixel and channel:
//! `below + round(opacity · (cloned − below))` in the canvas's own integer levels (rounding
//! half away from zero), so every result lies within half a level of the exact blend. The
//! seamless clone itself is unchanged; opacity only weighs its finished pixels.

use crate::pixels::{Canvas, CanvasPixels};
use crate::pixels::PixelRect;

/// Blends `frame` (cloned) towards `below` inside `rect` (clipped to the canvas). Both
/// canvases have the same size and depth (the renderer keeps `below` as a copy of `frame`).
pub(super) fn blend_over_below(frame: &mut Canvas, below: &Canvas, rect: PixelRect, opacity: f64) {
    let width = frame.width() as usize;
    let rect = rect.intersect(&frame.bounds());
    if rect.is_empty() {
        return;
    }
    match (frame.pixels_mut(), below.pixels()) {
        (CanvasPixels::Eight(dst), CanvasPixels::Eight(src)) => {
            blend_rows(dst, src, width, rect, opacity, |v| v as f64, |v| v as u8)
        }
        (CanvasPixels::Sixteen(dst), CanvasPixels::Sixteen(src)) => {
            blend_rows(dst, src, width, rect, opacity, |v| v as f64, |v| v as u16)
        }
        // invariant: `below` is always a copy of `frame` (same depth).
        _ => unreachable!("frame and the copy below have one depth"),
    }
}

fn blend_rows<T: Copy>(
    dst: &mut [[T; 4]],
    src: &[[T; 4]],
    width: usize,
    rect: PixelRect,
    opacity: f64,
    to_f64: impl Fn(T) -> f64,
    from_f64: impl Fn(f64) -> T,
) {
    for y in rect.y0 as usize..rect.y1 as usize {
        let row = y * width;
        let span = row + rect.x0 as usize..row + rect.x1 as usize;
        for (cloned, below) in dst[span.clone()].iter_mut().zip(&src[span]) {
            for (c, &b) in cloned.iter_mut().zip(below) {
                let b = to_f64(b);
                // Between b and the cloned level, so always a valid level of the type.
                *c = from_f64(b + (opacity * (to_f64(*c) - b)).round());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixels::Depth;

    #[test]
    fn half_opacity_is_within_one_level_of_the_average() {
        let mut frame = Canvas::new(3, 2, Depth::Eight).unwrap();
        let mut below = frame.clone();
        if let (CanvasPixels::Eight(f), CanvasPixels::Eight(b)) =
            (frame.pixels_mut(), below.pixels_mut())
        {
            for (i, (f, b)) in f.iter_mut().zip(b.iter_mut()).enumerate() {
                *f = [255, 3, 100, 255];
                *b = [0, i as u8, 101, 255];
            }
        }
        let before = frame.clone();
        let rect = PixelRect {
            x0: -5,
            y0: 1,
            x1: 10,
            y1: 9,
        };
        blend_over_below(&mut frame, &below, rect, 0.5);
        let (CanvasPixels::Eight(f), CanvasPixels::Eight(b), CanvasPixels::Eight(c)) =
            (frame.pixels(), below.pixels(), before.pixels())
        else {
            unreachable!()
        };
        // Row 0 is outside the rectangle: unchanged.
        assert_eq!(&f[..3], &c[..3]);
        for i in 3..6 {
            for k in 0..4 {
                let average = (f64::from(b[i][k]) + f64::from(c[i][k])) / 2.0;
                assert!((f64::from(f[i][k]) - average).abs() <= 1.0, "{i} {k}");
            }
        }
    }
}
