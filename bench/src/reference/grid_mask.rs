//! A borrowed pixel mask: width, height and a row-major `&[bool]` (true = inside the patch).
//! It gives 4-neighbour iteration and the crack test used by the pixel-grid reference and the
//! metrics.

use thiserror::Error;

/// Why a mask was rejected.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum MaskError {
    #[error("mask has {got} entries, expected width × height = {width} × {height}")]
    WrongLength {
        width: usize,
        height: usize,
        got: usize,
    },
    #[error("mask is empty (width {width}, height {height})")]
    EmptyGrid { width: usize, height: usize },
}

/// A pixel mask borrowed from a row-major `&[bool]` of `width * height` entries.
#[derive(Clone, Copy, Debug)]
pub struct GridMask<'a> {
    width: usize,
    height: usize,
    inside: &'a [bool],
}

impl<'a> GridMask<'a> {
    pub fn new(width: usize, height: usize, inside: &'a [bool]) -> Result<Self, MaskError> {
        if width == 0 || height == 0 {
            return Err(MaskError::EmptyGrid { width, height });
        }
        let expected = width.checked_mul(height);
        if expected != Some(inside.len()) {
            return Err(MaskError::WrongLength {
                width,
                height,
                got: inside.len(),
            });
        }
        Ok(Self {
            width,
            height,
            inside,
        })
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    pub fn pixel_count(&self) -> usize {
        self.inside.len()
    }

    pub fn as_slice(&self) -> &'a [bool] {
        self.inside
    }

    /// Whether row-major pixel index `p` is inside the patch.
    pub fn is_inside(&self, p: usize) -> bool {
        self.inside[p]
    }

    pub fn inside_count(&self) -> usize {
        self.inside.iter().filter(|&&b| b).count()
    }

    /// The in-image 4-neighbours of row-major pixel `p`, in the fixed order left, right, up,
    /// down (out-of-image neighbours are skipped).
    pub fn neighbours(&self, p: usize) -> impl Iterator<Item = usize> {
        let (w, h) = (self.width, self.height);
        let (x, y) = (p % w, p / w);
        [
            (x > 0).then(|| p - 1),
            (x + 1 < w).then(|| p + 1),
            (y > 0).then(|| p - w),
            (y + 1 < h).then(|| p + w),
        ]
        .into_iter()
        .flatten()
    }

    /// Every 4-neighbour pair `(inside, outside)` straddling the patch boundary (a "crack"),
    /// in row-major order of the inside pixel, then neighbour order left, right, up, down.
    pub fn cracks(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        (0..self.inside.len())
            .filter(|&p| self.inside[p])
            .flat_map(move |p| {
                self.neighbours(p)
                    .filter(|&q| !self.inside[q])
                    .map(move |q| (p, q))
            })
    }

    /// Checks the invariant the constructor established (length = width × height).
    pub fn sanity_check(&self) -> Result<(), MaskError> {
        Self::new(self.width, self.height, self.inside).map(|_| ())
    }
}
