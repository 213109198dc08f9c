//! Feathering: takes the per-pixel triangle ids over the work rectangle and gives a coverage
//! multiplier that ramps from 0 at the silhouette to 1 at `feather` px inside it.
//!
//! Distance to the silhouette is approximated by a two-pass chamfer transform (steps 1 and
//! √2) to the nearest pixel whose centre misses the patch, measured between pixel centres;
//! the ramp is smoothstep((d − ½) / feather), so it is monotone in d.

use super::triangles::NO_TRIANGLE;

const DIAGONAL: f32 = std::f32::consts::SQRT_2;

/// Multiplies `coverage` by the feather ramp; `distance` is scratch of the same length and
/// `row` scratch of at least `width`.
pub(crate) fn apply_feather(
    ids: &[u32],
    width: usize,
    feather: f32,
    distance: &mut [f32],
    row: &mut Vec<f32>,
    coverage: &mut [f32],
) {
    if feather <= 0.0 || width == 0 {
        return;
    }
    let cap = saturation_distance(feather);
    chamfer_distance(ids, width, cap, distance, row);
    for (c, &d) in coverage.iter_mut().zip(distance.iter()) {
        // ramp(d) = 1 for d ≥ cap, and 0 · ramp = 0: skipping both changes nothing.
        if *c > 0.0 && d < cap {
            *c *= ramp(d, feather);
        }
    }
}

/// A distance from which on the ramp is exactly 1 (with margin for rounding); distances
/// are only tracked below it.
fn saturation_distance(feather: f32) -> f32 {
    (feather + 2.0).ceil()
}

#[inline]
pub(crate) fn ramp(distance: f32, feather: f32) -> f32 {
    let t = ((distance - 0.5) / feather).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Two-pass chamfer distance, capped at `cap`: below the cap it equals the classic
/// raster-order chamfer (up to the rounding of summing unit steps), at or above it reads
/// `cap`. Each pass takes the neighbouring row's terms in one vectorisable sweep, then the
/// in-row term as a min over the `cap` previous pixels (vectorisable shifted mins) instead
/// of a serial dependency chain through every pixel.
fn chamfer_distance(ids: &[u32], width: usize, cap: f32, distance: &mut [f32], row: &mut Vec<f32>) {
    let height = ids.len() / width;
    for (d, &id) in distance.iter_mut().zip(ids) {
        *d = if id == NO_TRIANGLE { 0.0 } else { cap };
    }
    let reach = cap as usize;
    if height == 0 {
        return;
    }
    row.resize(width, 0.0);
    along_row(&mut distance[..width], row, reach, false);
    for y in 1..height {
        let (done, rest) = distance.split_at_mut(y * width);
        from_neighbour_row(&done[(y - 1) * width..], &mut rest[..width]);
        along_row(&mut rest[..width], row, reach, false);
    }
    let last = (height - 1) * width;
    along_row(&mut distance[last..last + width], row, reach, true);
    for y in (0..height - 1).rev() {
        let (head, done) = distance.split_at_mut((y + 1) * width);
        from_neighbour_row(&done[..width], &mut head[y * width..]);
        along_row(&mut head[y * width..], row, reach, true);
    }
}

/// `a.min(b)` for the (never NaN) distances: a plain comparison vectorises to `minps`
/// without `f32::min`'s NaN fix-ups.
#[inline(always)]
fn smaller(a: f32, b: f32) -> f32 {
    if b < a {
        b
    } else {
        a
    }
}

/// `current[x] = min(current[x], other[x] + 1, other[x ± 1] + √2)`.
fn from_neighbour_row(other: &[f32], current: &mut [f32]) {
    let width = current.len();
    let other = &other[..width];
    for (d, &o) in current.iter_mut().zip(other) {
        *d = smaller(*d, o + 1.0);
    }
    if width > 1 {
        for (d, &o) in current[1..].iter_mut().zip(&other[..width - 1]) {
            *d = smaller(*d, o + DIAGONAL);
        }
        for (d, &o) in current[..width - 1].iter_mut().zip(&other[1..]) {
            *d = smaller(*d, o + DIAGONAL);
        }
    }
}

/// Propagates along the row, left to right (`backward`: right to left), over up to `reach`
/// steps: `d[x] = min_k d[x ∓ k] + k`.
fn along_row(current: &mut [f32], scratch: &mut [f32], reach: usize, backward: bool) {
    let width = current.len();
    let before = &mut scratch[..width];
    before.copy_from_slice(current);
    for step in 1..=reach.min(width.saturating_sub(1)) {
        let offset = step as f32;
        let pairs: (&mut [f32], &[f32]) = if backward {
            (&mut current[..width - step], &before[step..])
        } else {
            (&mut current[step..], &before[..width - step])
        };
        for (d, &o) in pairs.0.iter_mut().zip(pairs.1) {
            *d = smaller(*d, o + offset);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_is_monotone_and_bounded() {
        let mut previous = 0.0;
        for k in 0..200 {
            let value = ramp(k as f32 * 0.05, 4.0);
            assert!(value >= previous && (0.0..=1.0).contains(&value));
            previous = value;
        }
        assert_eq!(ramp(0.0, 4.0), 0.0);
        assert_eq!(ramp(4.5, 4.0), 1.0);
    }

    /// The classic serial two-pass chamfer (the definition the fast one must match).
    fn reference_chamfer(ids: &[u32], width: usize) -> Vec<f32> {
        let height = ids.len() / width;
        let mut distance: Vec<f32> = ids
            .iter()
            .map(|&id| {
                if id == NO_TRIANGLE {
                    0.0
                } else {
                    f32::INFINITY
                }
            })
            .collect();
        let relax = |i: usize, j: usize, step: f32, distance: &mut Vec<f32>| {
            distance[i] = distance[i].min(distance[j] + step);
        };
        for y in 0..height {
            for x in 0..width {
                let i = y * width + x;
                if x > 0 {
                    relax(i, i - 1, 1.0, &mut distance);
                }
                if y > 0 {
                    relax(i, i - width, 1.0, &mut distance);
                    if x > 0 {
                        relax(i, i - width - 1, DIAGONAL, &mut distance);
                    }
                    if x + 1 < width {
                        relax(i, i - width + 1, DIAGONAL, &mut distance);
                    }
                }
            }
        }
        for y in (0..height).rev() {
            for x in (0..width).rev() {
                let i = y * width + x;
                if x + 1 < width {
                    relax(i, i + 1, 1.0, &mut distance);
                }
                if y + 1 < height {
                    relax(i, i + width, 1.0, &mut distance);
                    if x + 1 < width {
                        relax(i, i + width + 1, DIAGONAL, &mut distance);
                    }
                    if x > 0 {
                        relax(i, i + width - 1, DIAGONAL, &mut distance);
                    }
                }
            }
        }
        distance
    }

    #[test]
    fn capped_chamfer_matches_the_serial_one_below_the_cap() {
        use proptest::prelude::*;
        use proptest::test_runner::{Config, RngSeed, TestRunner};
        let config = Config {
            rng_seed: RngSeed::Fixed(46),
            cases: 64,
            ..Config::default()
        };
        let shape = (1usize..24, 1usize..24, 0u32..8, 0.5f32..6.0).prop_flat_map(
            |(width, height, blobs, feather)| {
                let blob = (0..width as i32, 0..height as i32, 1i32..12);
                (
                    Just(width),
                    Just(height),
                    proptest::collection::vec(blob, blobs as usize),
                    Just(feather),
                )
            },
        );
        TestRunner::new(config)
            .run(&shape, |(width, height, blobs, feather)| {
                // Inside = within any blob's square (overlapping squares make odd shapes).
                let ids: Vec<u32> = (0..width * height)
                    .map(|i| {
                        let (x, y) = ((i % width) as i32, (i / width) as i32);
                        let inside = blobs
                            .iter()
                            .any(|&(bx, by, r)| (x - bx).abs() < r && (y - by).abs() < r);
                        if inside {
                            0
                        } else {
                            NO_TRIANGLE
                        }
                    })
                    .collect();
                let cap = saturation_distance(feather);
                let mut fast = vec![0.0; ids.len()];
                chamfer_distance(&ids, width, cap, &mut fast, &mut Vec::new());
                let reference = reference_chamfer(&ids, width);
                for (i, (&f, &r)) in fast.iter().zip(&reference).enumerate() {
                    if r < cap {
                        prop_assert!((f - r).abs() <= 1e-5, "pixel {i}: {f} vs {r}");
                    } else {
                        prop_assert_eq!(f, cap, "pixel {}", i);
                    }
                    prop_assert_eq!(ramp(f.min(cap), feather) == 1.0, ramp(r, feather) == 1.0);
                }
                Ok(())
            })
            .unwrap();
    }

    #[test]
    fn chamfer_on_a_square_counts_steps_to_the_outside() {
        // 7×7 with a 5×5 inside: the centre is 3 steps from the outside ring.
        let width = 7;
        let ids: Vec<u32> = (0..49)
            .map(|i| {
                let (x, y) = (i % 7, i / 7);
                if (1..6).contains(&x) && (1..6).contains(&y) {
                    0
                } else {
                    NO_TRIANGLE
                }
            })
            .collect();
        let mut distance = vec![0.0; 49];
        chamfer_distance(&ids, width, 10.0, &mut distance, &mut Vec::new());
        assert_eq!(distance[0], 0.0);
        assert_eq!(distance[8], 1.0);
        assert_eq!(distance[24], 3.0);
    }
}
