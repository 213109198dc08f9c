//! The models of the paper's Table I, rebuilt from what the project ships. It takes the
//! assets folder and gives, per model, a mask at the paper's image size and a source and a
//! target photo cropped (mirror-tiled where the photo is smaller) to that size:
//! mouth 121×85, raft 342×353, spiral 770×743, palm 577×586, snake 470×280 from
//! [`super::synthetic`], horse 392×399 from `horse_mask.png` scaled to fit and padded.
//!
//! Source and target are always different photos, so `target − source` varies along the
//! boundary and the membrane has something to do; the patch is cloned at identity.

use std::path::{Path, PathBuf};

use thiserror::Error;

use super::synthetic::{self, SyntheticMask};
use lapclone::pixels::{FloatImage, PixelError, PixelFormat};

/// Pixels of margin kept around the resized horse silhouette.
const HORSE_MARGIN: u32 = 4;

/// Why a model could not be built.
#[derive(Debug, Error)]
pub enum ModelError {
    #[error(transparent)]
    Pixels(#[from] PixelError),
    #[error("{path}: {source}")]
    Mask {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
}

/// One Table-I model: a mask and the two photos, all `width × height`.
#[derive(Clone, Debug)]
pub struct PaperModel {
    pub name: &'static str,
    pub width: usize,
    pub height: usize,
    pub inside: Vec<bool>,
    pub source: FloatImage,
    pub target: FloatImage,
}

impl PaperModel {
    pub fn inside_count(&self) -> usize {
        self.inside.iter().filter(|&&b| b).count()
    }
}

/// Model names in table order.
pub const MODEL_NAMES: [&str; 6] = ["mouth", "raft", "spiral", "horse", "palm", "snake"];

/// Source and target photo (asset file names) and a crop offset per model.
fn photos_of(name: &str) -> (&'static str, &'static str, (u32, u32)) {
    match name {
        "mouth" => ("astronaut.png", "chelsea.png", (200, 330)),
        "raft" => ("rocket.jpg", "coffee.png", (120, 20)),
        "spiral" => ("chelsea.png", "coffee.png", (0, 0)),
        "horse" => ("coffee.png", "astronaut.png", (60, 40)),
        "palm" => ("astronaut.png", "rocket.jpg", (0, 0)),
        _ => ("hubble_deep_field.jpg", "chelsea.png", (100, 100)),
    }
}

/// The mask of a model by name (`None` for an unknown name).
pub fn model_mask(assets: &Path, name: &str) -> Result<Option<SyntheticMask>, ModelError> {
    Ok(Some(match name {
        "mouth" => synthetic::mouth(121, 85),
        "raft" => synthetic::raft(342, 353),
        "spiral" => synthetic::spiral(770, 743),
        "horse" => horse(assets, 392, 399)?,
        "palm" => synthetic::palm(577, 586),
        "snake" => synthetic::snake(470, 280),
        _ => return Ok(None),
    }))
}

/// A model by name with its photos (`None` for an unknown name).
pub fn paper_model(assets: &Path, name: &str) -> Result<Option<PaperModel>, ModelError> {
    let Some(mut mask) = model_mask(assets, name)? else {
        return Ok(None);
    };
    fill_holes(mask.width, mask.height, &mut mask.inside);
    let (source, target, offset) = photos_of(mask.name);
    let (w, h) = (mask.width as u32, mask.height as u32);
    let source = mirror_tile(&FloatImage::load(&assets.join(source))?, w, h, offset)?;
    let target = mirror_tile(&FloatImage::load(&assets.join(target))?, w, h, offset)?;
    Ok(Some(PaperModel {
        name: mask.name,
        width: mask.width,
        height: mask.height,
        inside: mask.inside,
        source,
        target,
    }))
}

/// `width × height` pixels of `photo` starting at `offset`, mirrored at its edges so any
/// size can be cut from any photo without a visible tiling seam. Always 8-bit RGBA.
pub fn mirror_tile(
    photo: &FloatImage,
    width: u32,
    height: u32,
    offset: (u32, u32),
) -> Result<FloatImage, PixelError> {
    let reflect = |i: u32, size: u32| {
        let period = 2 * size;
        let k = i % period;
        if k < size {
            k
        } else {
            period - 1 - k
        }
    };
    FloatImage::from_fn(width, height, PixelFormat::RGBA8, |x, y| {
        let (px, py) = (
            reflect(x + offset.0, photo.width()),
            reflect(y + offset.1, photo.height()),
        );
        let mut p = photo.pixels()[py as usize * photo.width() as usize + px as usize];
        p[3] = 1.0;
        p
    })
}

/// The bundled horse silhouette scaled to fit `width × height` minus a margin, centred.
pub fn horse(assets: &Path, width: usize, height: usize) -> Result<SyntheticMask, ModelError> {
    let path = assets.join("horse_mask.png");
    let image = image::open(&path).map_err(|source| ModelError::Mask {
        path: path.clone(),
        source,
    })?;
    let grey = image.to_luma8();
    let room = (
        (width as u32).saturating_sub(2 * HORSE_MARGIN).max(1),
        (height as u32).saturating_sub(2 * HORSE_MARGIN).max(1),
    );
    let scale = f64::min(
        room.0 as f64 / grey.width() as f64,
        room.1 as f64 / grey.height() as f64,
    );
    let fit = (
        ((grey.width() as f64 * scale).round() as u32).max(1),
        ((grey.height() as f64 * scale).round() as u32).max(1),
    );
    let resized =
        image::imageops::resize(&grey, fit.0, fit.1, image::imageops::FilterType::Triangle);
    let left = (width as u32 - fit.0) / 2;
    let top = (height as u32 - fit.1) / 2;
    let inside = (0..width * height)
        .map(|p| {
            let (x, y) = ((p % width) as u32, (p / width) as u32);
            x >= left
                && y >= top
                && x < left + fit.0
                && y < top + fit.1
                && resized.get_pixel(x - left, y - top).0[0] >= 128
        })
        .collect();
    Ok(SyntheticMask {
        name: "horse",
        width,
        height,
        inside,
    })
}

/// Marks inside every outside pixel not 4-connected to the image border: the paper's models
/// have no holes (the synthetic shapes leave a few enclosed specks, and MVC refuses holes).
pub fn fill_holes(width: usize, height: usize, inside: &mut [bool]) {
    let mut reached = vec![false; width * height];
    let mut stack: Vec<usize> = (0..width * height)
        .filter(|&p| {
            let (x, y) = (p % width, p / width);
            !inside[p] && (x == 0 || y == 0 || x + 1 == width || y + 1 == height)
        })
        .collect();
    for &p in &stack {
        reached[p] = true;
    }
    while let Some(p) = stack.pop() {
        let (x, y) = (p % width, p / width);
        let neighbours = [
            (x > 0).then(|| p - 1),
            (x + 1 < width).then(|| p + 1),
            (y > 0).then(|| p - width),
            (y + 1 < height).then(|| p + width),
        ];
        for q in neighbours.into_iter().flatten() {
            if !inside[q] && !reached[q] {
                reached[q] = true;
                stack.push(q);
            }
        }
    }
    for (cell, &r) in inside.iter_mut().zip(&reached) {
        *cell |= !r;
    }
}
