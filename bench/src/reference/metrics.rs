//! Quality figures for a clone. It takes pixel buffers (row-major, interleaved, any of
//! `f32`/`f64`, values nominally in [0, 1]) and a [`GridMask`] and gives: PSNR over the mask
//! pixels, the seam step across the patch boundary, the count of mask pixels a rasteriser left
//! uncovered, and [`MembraneComparison`], all of them for one membrane against the pixel-grid
//! reference. Nothing here rasterises: a mesh membrane comes in already drawn to pixels.
//!
//! Conventions:
//! - PSNR uses peak 1.0 (images as floats in [0, 1]): `10 log10(1 / MSE)`, MSE averaged over
//!   every mask pixel and channel; identical inputs give `+∞`.
//! - The seam step is `mean |result[p] − target[q]|` over every 4-neighbour pair with `p`
//!   inside and `q` outside the mask (both in the image) and every channel: how far apart the
//!   two sides of the seam are. Only meaningful beside the same figure for the reference,
//!   because a seamless clone still steps wherever the source itself has an edge.
//! - Composites are not clamped, so PSNR of `source + membrane` against `source + reference`
//!   measures the membranes alone.

use thiserror::Error;

use super::grid_mask::GridMask;

/// Why a metric could not be computed.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum MetricError {
    #[error("channels must be at least 1")]
    NoChannels,
    #[error("{what} has {got} samples, expected width × height × channels = {expected}")]
    BufferLength {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("mask has no inside pixel")]
    EmptyMask,
    #[error("mask has no inside pixel with an outside 4-neighbour in the image")]
    NoSeam,
}

/// Mean absolute step across the seam and how many pixel pairs it averages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeamStep {
    pub mean_abs: f64,
    pub pairs: usize,
}

fn check_len(
    what: &'static str,
    len: usize,
    mask: GridMask<'_>,
    channels: usize,
) -> Result<(), MetricError> {
    if channels == 0 {
        return Err(MetricError::NoChannels);
    }
    let expected = mask.pixel_count() * channels;
    if len != expected {
        return Err(MetricError::BufferLength {
            what,
            expected,
            got: len,
        });
    }
    Ok(())
}

/// PSNR (peak 1.0) of `a` against `b` over the mask pixels; `+∞` when they agree exactly.
pub fn psnr<A: Copy + Into<f64>, B: Copy + Into<f64>>(
    a: &[A],
    b: &[B],
    channels: usize,
    mask: GridMask<'_>,
) -> Result<f64, MetricError> {
    check_len("first image", a.len(), mask, channels)?;
    check_len("second image", b.len(), mask, channels)?;
    let mut squared = 0.0;
    let mut samples = 0usize;
    for p in (0..mask.pixel_count()).filter(|&p| mask.is_inside(p)) {
        for i in p * channels..(p + 1) * channels {
            let d = a[i].into() - b[i].into();
            squared += d * d;
            samples += 1;
        }
    }
    if samples == 0 {
        return Err(MetricError::EmptyMask);
    }
    Ok(10.0 * (samples as f64 / squared).log10())
}

/// Ring of every mask pixel: 1 for pixels with an outside in-image 4-neighbour (the
/// pixels next to the reference's Dirichlet values), k + 1 for pixels 4-adjacent to ring k;
/// 0 outside the mask and for pieces with no outside neighbour in the image.
pub fn ring_of_pixels(mask: GridMask<'_>) -> Vec<u32> {
    let mut ring = vec![0u32; mask.pixel_count()];
    let mut frontier: Vec<usize> = (0..mask.pixel_count())
        .filter(|&p| mask.is_inside(p) && mask.neighbours(p).any(|q| !mask.is_inside(q)))
        .collect();
    let mut k = 1;
    while !frontier.is_empty() {
        for &p in &frontier {
            ring[p] = k;
        }
        let mut next = Vec::new();
        for &p in &frontier {
            for q in mask.neighbours(p) {
                if mask.is_inside(q) && ring[q] == 0 {
                    ring[q] = u32::MAX; // claimed for the next ring
                    next.push(q);
                }
            }
        }
        frontier = next;
        k += 1;
    }
    ring
}

/// PSNR (peak 1.0) of `a` against `b` per ring band: `bands[i]` is the inclusive range of
/// rings ([`ring_of_pixels`]) of band i. A band with no pixel gives `None`.
pub fn psnr_by_ring<A: Copy + Into<f64>, B: Copy + Into<f64>>(
    a: &[A],
    b: &[B],
    channels: usize,
    mask: GridMask<'_>,
    bands: &[(u32, u32)],
) -> Result<Vec<Option<f64>>, MetricError> {
    check_len("first image", a.len(), mask, channels)?;
    check_len("second image", b.len(), mask, channels)?;
    let ring = ring_of_pixels(mask);
    let mut squared = vec![0.0; bands.len()];
    let mut samples = vec![0usize; bands.len()];
    for (p, &r) in ring.iter().enumerate().filter(|(_, &r)| r > 0) {
        let Some(band) = bands.iter().position(|&(lo, hi)| (lo..=hi).contains(&r)) else {
            continue;
        };
        for i in p * channels..(p + 1) * channels {
            let d = a[i].into() - b[i].into();
            squared[band] += d * d;
            samples[band] += 1;
        }
    }
    Ok(squared
        .iter()
        .zip(&samples)
        .map(|(&sq, &n)| (n > 0).then(|| 10.0 * (n as f64 / sq).log10()))
        .collect())
}

/// Mean `|result[p] − target[q]|` over 4-neighbour pairs `p` inside, `q` outside the mask.
pub fn seam_step<R: Copy + Into<f64>, T: Copy + Into<f64>>(
    result: &[R],
    target: &[T],
    channels: usize,
    mask: GridMask<'_>,
) -> Result<SeamStep, MetricError> {
    check_len("result", result.len(), mask, channels)?;
    check_len("target", target.len(), mask, channels)?;
    let mut sum = 0.0;
    let mut pairs = 0usize;
    for (p, q) in mask.cracks() {
        for c in 0..channels {
            sum += (result[p * channels + c].into() - target[q * channels + c].into()).abs();
        }
        pairs += 1;
    }
    if pairs == 0 {
        return Err(MetricError::NoSeam);
    }
    Ok(SeamStep {
        mean_abs: sum / (pairs * channels) as f64,
        pairs,
    })
}

/// Mask pixels whose `covered` flag is false (pixels a rasteriser never reached).
pub fn uncovered_pixels(mask: GridMask<'_>, covered: &[bool]) -> Result<usize, MetricError> {
    check_len("coverage", covered.len(), mask, 1)?;
    Ok((0..mask.pixel_count())
        .filter(|&p| mask.is_inside(p) && !covered[p])
        .count())
}

/// The clone result: `source + membrane` on mask pixels, `target` elsewhere (not clamped).
pub fn composite<S, T, M>(
    source: &[S],
    target: &[T],
    membrane: &[M],
    channels: usize,
    mask: GridMask<'_>,
) -> Result<Vec<f64>, MetricError>
where
    S: Copy + Into<f64>,
    T: Copy + Into<f64>,
    M: Copy + Into<f64>,
{
    check_len("source", source.len(), mask, channels)?;
    check_len("target", target.len(), mask, channels)?;
    check_len("membrane", membrane.len(), mask, channels)?;
    Ok((0..source.len())
        .map(|i| {
            if mask.is_inside(i / channels) {
                source[i].into() + membrane[i].into()
            } else {
                target[i].into()
            }
        })
        .collect())
}

/// One membrane measured against the pixel-grid reference on the same mask.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MembraneComparison {
    /// PSNR of `source + membrane` against `source + reference` over the mask (dB, peak 1).
    pub psnr_db: f64,
    /// Seam step of `source + membrane` against the target.
    pub seam_step: SeamStep,
    /// Seam step of `source + reference` against the target, the figure to read it beside.
    pub reference_seam_step: SeamStep,
    /// Mask pixels the membrane's rasteriser did not cover.
    pub uncovered: usize,
}

/// Buffers for [`MembraneComparison::new`]: all interleaved with `channels`, sized to `mask`.
#[derive(Clone, Copy, Debug)]
pub struct ComparisonInput<'a> {
    pub mask: GridMask<'a>,
    pub channels: usize,
    pub source: &'a [f32],
    pub target: &'a [f32],
    /// The membrane under test, rasterised to pixels.
    pub membrane: &'a [f64],
    /// Which pixels the rasteriser wrote.
    pub covered: &'a [bool],
    /// The pixel-grid membrane ([`super::GridMembrane::values`]).
    pub reference: &'a [f64],
}

impl MembraneComparison {
    pub fn new(input: ComparisonInput<'_>) -> Result<Self, MetricError> {
        let ComparisonInput {
            mask,
            channels,
            source,
            target,
            membrane,
            covered,
            reference,
        } = input;
        let result = composite(source, target, membrane, channels, mask)?;
        let expected = composite(source, target, reference, channels, mask)?;
        Ok(Self {
            psnr_db: psnr(&result, &expected, channels, mask)?,
            seam_step: seam_step(&result, target, channels, mask)?,
            reference_seam_step: seam_step(&expected, target, channels, mask)?,
            uncovered: uncovered_pixels(mask, covered)?,
        })
    }
}
