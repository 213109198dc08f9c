//! `sample_bilinear_rgba`: a hand-computed value, exact at pixel centres, clamped outside.

use lapclone::pixels::sample_bilinear_rgba;

#[test]
fn hand_computed_value() {
    // 2×2 grey ramp; (1.25, 0.75) lies 0.75 of the way from column 0 to 1 and 0.25 of
    // the way from row 0 to 1: top = 0.1 + 0.75·(0.3 − 0.1) = 0.25,
    // bottom = 0.5 + 0.75·(0.9 − 0.5) = 0.8, value = 0.25 + 0.25·(0.8 − 0.25) = 0.3875.
    let px = |v: f32| [v, v, v, 1.0];
    let pixels = [px(0.1), px(0.3), px(0.5), px(0.9)];
    let s = sample_bilinear_rgba(&pixels, 2, 2, 1.25, 0.75);
    assert!((s[0] - 0.3875).abs() < 1e-6, "{s:?}");
    assert_eq!(s[3], 1.0);
}

#[test]
fn exact_at_centres_and_clamped_outside() {
    let pixels: Vec<[f32; 4]> = (0..6).map(|i| [i as f32 / 8.0, 0.0, 0.0, 1.0]).collect();
    for j in 0..2 {
        for i in 0..3 {
            let s = sample_bilinear_rgba(&pixels, 3, 2, i as f64 + 0.5, j as f64 + 0.5);
            assert_eq!(s[0], pixels[j * 3 + i][0]);
        }
    }
    assert_eq!(
        sample_bilinear_rgba(&pixels, 3, 2, -5.0, -5.0)[0],
        pixels[0][0]
    );
    assert_eq!(
        sample_bilinear_rgba(&pixels, 3, 2, 50.0, 50.0)[0],
        pixels[5][0]
    );
    assert_eq!(
        sample_bilinear_rgba(&pixels, 3, 2, f64::NAN, 0.5)[0],
        pixels[0][0]
    );
}
