//! One GIF frame record from two consecutive frames: takes the current and previous RGBA8
//! frames and a [`PaletteMap`], gives an LZW-compressed `gif::Frame` holding only the
//! bounding rectangle of pixels whose palette index changed, with unchanged pixels inside it
//! set to the transparent index (drawn with disposal `Keep`, so the decoder shows exactly the
//! current frame's indices).
//!
//! A pixel that must turn transparent after being opaque cannot be expressed on top of a
//! kept canvas; such a frame is written whole, and the previous record is replaced by a
//! whole-canvas one with disposal `Background` (which clears the canvas). Both records are
//! computed here from the two frames alone, so frames can be encoded in any order, on any
//! thread, with identical bytes.

use std::borrow::Cow;

use super::gif_palette::{PaletteMap, ALPHA_THRESHOLD};

/// A compressed frame record, and the replacement for the previous one if it must clear.
pub struct EncodedFrame {
    pub frame: gif::Frame<'static>,
    pub replace_previous: Option<gif::Frame<'static>>,
}

/// Encodes frames of one size with one palette; keeps its scratch between frames.
pub struct FrameEncoder {
    map: PaletteMap,
    width: usize,
    height: usize,
    indices: Vec<u8>,
}

/// Compares pixels the way a GIF shows them: all transparent pixels are alike.
#[inline]
fn shown(pixel: &[u8]) -> u32 {
    if pixel[3] < ALPHA_THRESHOLD {
        0
    } else {
        u32::from_le_bytes([pixel[0], pixel[1], pixel[2], 255])
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Rect {
    left: usize,
    top: usize,
    right: usize,
    bottom: usize,
}

impl Rect {
    fn width(&self) -> usize {
        self.right - self.left
    }
    fn height(&self) -> usize {
        self.bottom - self.top
    }
}

impl FrameEncoder {
    pub fn new(map: PaletteMap, width: u32, height: u32) -> FrameEncoder {
        FrameEncoder {
            map,
            width: width as usize,
            height: height as usize,
            indices: Vec::new(),
        }
    }

    /// The record for `current` shown for `delay_cs` after `previous` (shown for
    /// `previous_delay_cs`); the first frame has no previous.
    pub fn encode(
        &mut self,
        current: &[u8],
        previous: Option<(&[u8], u16)>,
        delay_cs: u16,
    ) -> EncodedFrame {
        let Some((previous, previous_delay_cs)) = previous else {
            return EncodedFrame {
                frame: self.whole(current, delay_cs, gif::DisposalMethod::Keep),
                replace_previous: None,
            };
        };
        let (changed, needs_clear) = self.changed_box(current, previous);
        if needs_clear {
            return EncodedFrame {
                frame: self.whole(current, delay_cs, gif::DisposalMethod::Keep),
                replace_previous: Some(self.whole(
                    previous,
                    previous_delay_cs,
                    gif::DisposalMethod::Background,
                )),
            };
        }
        let frame = match changed.and_then(|r| self.changed_indices(current, previous, r)) {
            Some(rect) => self.record(rect, delay_cs, gif::DisposalMethod::Keep),
            None => self.unchanged(delay_cs),
        };
        EncodedFrame {
            frame,
            replace_previous: None,
        }
    }

    /// Bounding box of pixels shown differently, and whether any opaque one turns transparent.
    fn changed_box(&self, current: &[u8], previous: &[u8]) -> (Option<Rect>, bool) {
        let mut rect: Option<Rect> = None;
        let mut needs_clear = false;
        for y in 0..self.height {
            let row = y * self.width * 4..(y + 1) * self.width * 4;
            let cur = current[row.clone()].chunks_exact(4);
            let prev = previous[row].chunks_exact(4);
            let mut first = None;
            let mut last = 0;
            for (x, (c, p)) in cur.zip(prev).enumerate() {
                let (c, p) = (shown(c), shown(p));
                if c != p {
                    first.get_or_insert(x);
                    last = x;
                    needs_clear |= c == 0;
                }
            }
            if let Some(first) = first {
                rect = Some(match rect {
                    None => Rect {
                        left: first,
                        top: y,
                        right: last + 1,
                        bottom: y + 1,
                    },
                    Some(r) => Rect {
                        left: r.left.min(first),
                        top: r.top,
                        right: r.right.max(last + 1),
                        bottom: y + 1,
                    },
                });
            }
        }
        (rect, needs_clear)
    }

    /// Fills `indices` with the current indices inside `rect` (transparent where the index
    /// did not change) and gives the tight box of changed indices, packed, or `None`.
    fn changed_indices(&mut self, current: &[u8], previous: &[u8], rect: Rect) -> Option<Rect> {
        let transparent = self.map.palette().transparent_index();
        self.indices.clear();
        let mut tight: Option<Rect> = None;
        for y in rect.top..rect.bottom {
            for x in rect.left..rect.right {
                let at = (y * self.width + x) * 4;
                let (c, p) = (&current[at..at + 4], &previous[at..at + 4]);
                let mut index = transparent;
                if shown(c) != shown(p) {
                    let ci = self.map.index(c, x, y);
                    if ci != self.map.index(p, x, y) {
                        index = ci;
                        tight = Some(grow(tight, x, y));
                    }
                }
                self.indices.push(index);
            }
        }
        let tight = tight?;
        pack(&mut self.indices, rect, tight);
        Some(tight)
    }

    /// A whole-canvas record of `pixels`.
    fn whole(
        &mut self,
        pixels: &[u8],
        delay_cs: u16,
        dispose: gif::DisposalMethod,
    ) -> gif::Frame<'static> {
        self.indices.clear();
        for (i, pixel) in pixels.chunks_exact(4).enumerate() {
            let index = self.map.index(pixel, i % self.width, i / self.width);
            self.indices.push(index);
        }
        let rect = Rect {
            left: 0,
            top: 0,
            right: self.width,
            bottom: self.height,
        };
        self.record(rect, delay_cs, dispose)
    }

    /// A 1×1 transparent record: nothing changed, but the frame's delay must be there.
    fn unchanged(&mut self, delay_cs: u16) -> gif::Frame<'static> {
        self.indices.clear();
        self.indices.push(self.map.palette().transparent_index());
        let rect = Rect {
            left: 0,
            top: 0,
            right: 1,
            bottom: 1,
        };
        self.record(rect, delay_cs, gif::DisposalMethod::Keep)
    }

    /// Compresses `indices` (packed `rect`) into a record.
    fn record(
        &mut self,
        rect: Rect,
        delay_cs: u16,
        dispose: gif::DisposalMethod,
    ) -> gif::Frame<'static> {
        // invariant: frames are at most u16::MAX wide and high (checked by the writer).
        let dim = |v: usize| u16::try_from(v).expect("frame size checked");
        let mut frame = gif::Frame {
            delay: delay_cs,
            dispose,
            transparent: Some(self.map.palette().transparent_index()),
            left: dim(rect.left),
            top: dim(rect.top),
            width: dim(rect.width()),
            height: dim(rect.height()),
            buffer: Cow::Borrowed(&self.indices[..]),
            ..gif::Frame::default()
        };
        frame.make_lzw_pre_encoded();
        gif::Frame {
            delay: frame.delay,
            dispose: frame.dispose,
            transparent: frame.transparent,
            left: frame.left,
            top: frame.top,
            width: frame.width,
            height: frame.height,
            buffer: Cow::Owned(frame.buffer.into_owned()),
            ..gif::Frame::default()
        }
    }
}

fn grow(rect: Option<Rect>, x: usize, y: usize) -> Rect {
    match rect {
        None => Rect {
            left: x,
            top: y,
            right: x + 1,
            bottom: y + 1,
        },
        Some(r) => Rect {
            left: r.left.min(x),
            top: r.top.min(y),
            right: r.right.max(x + 1),
            bottom: r.bottom.max(y + 1),
        },
    }
}

/// Moves the `inner` box of a row-major `outer`-sized buffer to the front, packed.
fn pack(buffer: &mut Vec<u8>, outer: Rect, inner: Rect) {
    let mut to = 0;
    for y in inner.top..inner.bottom {
        let from = (y - outer.top) * outer.width() + (inner.left - outer.left);
        buffer.copy_within(from..from + inner.width(), to);
        to += inner.width();
    }
    buffer.truncate(to);
}
