//! Feathering: takes the per-pixel triangle ids over the work rectangle and gives a coverage
//! multiplier that ramps from 0 at the silhouette to 1 at `feather` px inside it.
//!
//! Distance to the silhouette is approximated by a two-pass chamfer transform (steps 1 and
//! √2) to the nearest pixel whose centre misses the patch, measured between pixel centres;
//! the ramp is smoothstep((d − ½) / feather), so it is monotone in d.

use super::triangles::NO_TRIANGLE;

const DIAGONAL: f32 = std::f32::consts::SQRT_2;

/// Multiplies `coverage` by the feather ramp; `distance` is scratch of the same length.
pub(crate) fn apply_feather(
    ids: &[u32],
    width: usize,
    feather: f32,
    distance: &mut [f32],
    coverage: &mut [f32],
) {
    if feather <= 0.0 || width == 0 {
        return;
    }
    chamfer_distance(ids, width, distance);
    for (c, &d) in coverage.iter_mut().zip(distance.iter()) {
        *c *= ramp(d, feather);
    }
}

#[inline]
pub(crate) fn ramp(distance: f32, feather: f32) -> f32 {
    let t = ((distance - 0.5) / feather).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn chamfer_distance(ids: &[u32], width: usize, distance: &mut [f32]) {
    let height = ids.len() / width;
    for (d, &id) in distance.iter_mut().zip(ids) {
        *d = if id == NO_TRIANGLE {
            0.0
        } else {
            f32::INFINITY
        };
    }
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            let mut d = distance[i];
            if x > 0 {
                d = d.min(distance[i - 1] + 1.0);
            }
            if y > 0 {
                let up = i - width;
                d = d.min(distance[up] + 1.0);
                if x > 0 {
                    d = d.min(distance[up - 1] + DIAGONAL);
                }
                if x + 1 < width {
                    d = d.min(distance[up + 1] + DIAGONAL);
                }
            }
            distance[i] = d;
        }
    }
    for y in (0..height).rev() {
        for x in (0..width).rev() {
            let i = y * width + x;
            let mut d = distance[i];
            if x + 1 < width {
                d = d.min(distance[i + 1] + 1.0);
            }
            if y + 1 < height {
                let down = i + width;
                d = d.min(distance[down] + 1.0);
                if x + 1 < width {
                    d = d.min(distance[down + 1] + DIAGONAL);
                }
                if x > 0 {
                    d = d.min(distance[down - 1] + DIAGONAL);
                }
            }
            distance[i] = d;
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
        chamfer_distance(&ids, width, &mut distance);
        assert_eq!(distance[0], 0.0);
        assert_eq!(distance[8], 1.0);
        assert_eq!(distance[24], 3.0);
    }
}
