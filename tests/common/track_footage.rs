//! Synthetic footage for the tracking tests and benchmarks: takes a photograph, a frame size
//! and a known motion (sub-pixel translation, rotation and scale about the frame's centre),
//! and gives frame k as 8-bit RGB with deterministic noise, plus where any point of frame 0
//! truly is in frame k. Included with `#[path = ".../track_footage.rs"] mod track_footage;`.
#![allow(dead_code)]

use lapclone::glam::DVec2;
use lapclone::FloatImage;

/// Frame k shows the photo moved by `shift(k)`, turned by `degrees(k)` and scaled by
/// `scale(k)` about the frame's centre.
#[derive(Clone, Copy)]
pub struct Motion {
    /// Translation in pixels at frame k.
    pub shift: fn(u32) -> DVec2,
    /// Rotation in degrees at frame k (positive turns x towards y).
    pub degrees: fn(u32) -> f64,
    /// Uniform scale at frame k.
    pub scale: fn(u32) -> f64,
}

impl Motion {
    /// A sub-pixel wandering translation only.
    pub fn translation() -> Motion {
        Motion {
            shift: |k| {
                let k = f64::from(k);
                DVec2::new(
                    18.0 * (k * 0.045).sin() + 0.173 * k,
                    11.0 * (k * 0.061).cos() - 11.0 + 0.0917 * k,
                )
            },
            degrees: |_| 0.0,
            scale: |_| 1.0,
        }
    }

    /// Translation, a turn of up to 6° and a growth of up to 6 %.
    pub fn similarity() -> Motion {
        Motion {
            shift: |k| {
                let k = f64::from(k);
                DVec2::new(9.0 * (k * 0.05).sin() + 0.07 * k, 0.113 * k)
            },
            degrees: |k| 6.0 * (f64::from(k) * 0.031).sin(),
            scale: |k| 1.0 + 0.06 * f64::from(k) / 99.0,
        }
    }

    /// Where frame 0's point `p` is in frame k (frame size `size`).
    pub fn truth(&self, size: (u32, u32), k: u32, p: DVec2) -> DVec2 {
        let centre = DVec2::new(f64::from(size.0), f64::from(size.1)) / 2.0;
        let rest = self.photo_offset(size, 0, p);
        let turn = DVec2::from_angle((self.degrees)(k).to_radians());
        centre + (self.shift)(k) + turn.rotate(rest) * (self.scale)(k)
    }

    /// Frame k's point `p` as an offset from the photo's centre.
    fn photo_offset(&self, size: (u32, u32), k: u32, p: DVec2) -> DVec2 {
        let centre = DVec2::new(f64::from(size.0), f64::from(size.1)) / 2.0;
        let back = DVec2::from_angle(-(self.degrees)(k).to_radians());
        back.rotate(p - centre - (self.shift)(k)) / (self.scale)(k)
    }
}

/// SplitMix64 noise, the same on every run.
pub struct Noise(u64);

impl Noise {
    pub fn new(seed: u64) -> Noise {
        Noise(seed)
    }

    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) as f64 / u64::MAX as f64
    }

    /// Roughly Gaussian, standard deviation `sigma` (a sum of four uniforms).
    fn gaussian(&mut self, sigma: f64) -> f64 {
        let sum: f64 = (0..4).map(|_| self.next()).sum();
        (sum - 2.0) * sigma * (3.0f64).sqrt()
    }
}

/// Frame k of `photo` under `motion`, with noise of `sigma` levels.
pub fn frame(
    photo: &FloatImage,
    size: (u32, u32),
    motion: &Motion,
    k: u32,
    sigma: f64,
    noise: &mut Noise,
) -> image::RgbImage {
    let photo_centre = DVec2::new(f64::from(photo.width()), f64::from(photo.height())) / 2.0;
    image::RgbImage::from_fn(size.0, size.1, |i, j| {
        let p = DVec2::new(f64::from(i) + 0.5, f64::from(j) + 0.5);
        let q = photo_centre + motion.photo_offset(size, k, p);
        let [r, g, b, _] = photo.sample_bilinear(q.x, q.y);
        let level = |v: f32, n: f64| (f64::from(v) * 255.0 + n).round().clamp(0.0, 255.0) as u8;
        let n = noise.gaussian(sigma);
        image::Rgb([level(r, n), level(g, n), level(b, n)])
    })
}

/// `image` as JPEG of the given quality.
pub fn jpeg(image: &image::RgbImage, quality: u8) -> Vec<u8> {
    let mut bytes = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, quality)
        .encode_image(image)
        .expect("JPEG encoding in memory");
    bytes
}
