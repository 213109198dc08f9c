//! The Fig.-5-style comparison picture. It takes an [`Experiment`] and several [`MeshRun`]s
//! made with `keep_membranes` and gives an RGBA picture (a `tiny_skia::Pixmap`): one column
//! per mesh; on top the mesh drawn over the source, below it the combinatorial result (left,
//! green bar underneath) and the MVC result (right, orange bar; grey tile when MVC did not
//! run) side by side. Every tile is the mask's bounding box plus a margin, box-filtered down
//! by an integer factor. No text: columns go left to right in the order given.

use tiny_skia::{Color, Paint, PathBuilder, Pixmap, PixmapPaint, Rect, Stroke, Transform};

use super::experiment::{Experiment, MeshRun, CHANNELS};

/// Pixels of target kept around the mask's bounding box in every tile.
const CROP_MARGIN: usize = 12;
/// Gap between tiles and around the picture, px.
const GAP: u32 = 10;
/// Height of the colour bar under a result tile, px.
const BAR: u32 = 6;
const COMBINATORIAL_BAR: [u8; 3] = [40, 170, 60];
const MVC_BAR: [u8; 3] = [235, 130, 20];

/// Why the picture could not be made.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    #[error("no mesh run was given")]
    NoRuns,
    #[error("mesh run {0} was made without keep_membranes")]
    MissingMembrane(usize),
    #[error("picture of {0}×{1} px cannot be allocated")]
    TooLarge(u32, u32),
}

/// Composes the picture (see the module doc); `shrink` ≥ 1 divides every tile's size.
pub fn comparison_figure(
    experiment: &Experiment,
    runs: &[MeshRun],
    shrink: usize,
) -> Result<Pixmap, FigureError> {
    if runs.is_empty() {
        return Err(FigureError::NoRuns);
    }
    let shrink = shrink.max(1);
    let crop = mask_crop(experiment);
    let tile = ((crop.2 / shrink) as u32, (crop.3 / shrink) as u32);
    let column_width = 2 * tile.0 + GAP;
    let width = GAP + runs.len() as u32 * (column_width + GAP);
    let height = GAP + tile.1 + GAP + tile.1 + BAR + GAP;
    let mut picture = Pixmap::new(width, height).ok_or(FigureError::TooLarge(width, height))?;
    picture.fill(Color::WHITE);
    for (index, run) in runs.iter().enumerate() {
        let left = GAP + index as u32 * (column_width + GAP);
        let mesh_tile = tile_pixmap(experiment, None, crop, shrink)?;
        let mesh_left = left + (column_width - tile.0) / 2;
        draw(&mut picture, &mesh_tile, mesh_left, GAP);
        draw_mesh(&mut picture, run, crop, shrink, (mesh_left, GAP));
        let combinatorial = run
            .combinatorial
            .membrane
            .as_deref()
            .ok_or(FigureError::MissingMembrane(index))?;
        let row = 2 * GAP + tile.1;
        draw(
            &mut picture,
            &tile_pixmap(experiment, Some(combinatorial), crop, shrink)?,
            left,
            row,
        );
        bar(&mut picture, left, row + tile.1, tile.0, COMBINATORIAL_BAR);
        let right = left + tile.0 + GAP;
        match run.mvc.figures() {
            Some(f) => {
                let membrane = f
                    .membrane
                    .as_deref()
                    .ok_or(FigureError::MissingMembrane(index))?;
                draw(
                    &mut picture,
                    &tile_pixmap(experiment, Some(membrane), crop, shrink)?,
                    right,
                    row,
                );
            }
            None => fill(&mut picture, right, row, tile, [200, 200, 200]),
        }
        bar(&mut picture, right, row + tile.1, tile.0, MVC_BAR);
    }
    Ok(picture)
}

/// `(x, y, width, height)` of the mask's bounding box grown by the margin, clipped.
fn mask_crop(experiment: &Experiment) -> (usize, usize, usize, usize) {
    let (w, h) = (experiment.width(), experiment.height());
    let mask = experiment.mask();
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for p in (0..w * h).filter(|&p| mask.is_inside(p)) {
        let (x, y) = (p % w, p / w);
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
    }
    if x0 >= x1 {
        return (0, 0, w, h);
    }
    let (x0, y0) = (
        x0.saturating_sub(CROP_MARGIN),
        y0.saturating_sub(CROP_MARGIN),
    );
    let (x1, y1) = ((x1 + CROP_MARGIN).min(w), (y1 + CROP_MARGIN).min(h));
    (x0, y0, x1 - x0, y1 - y0)
}

/// The crop of `source + membrane` inside the mask and the target outside (or, without a
/// membrane, the plain source), clamped, box-filtered by `shrink`.
fn tile_pixmap(
    experiment: &Experiment,
    membrane: Option<&[f64]>,
    crop: (usize, usize, usize, usize),
    shrink: usize,
) -> Result<Pixmap, FigureError> {
    let (tw, th) = (crop.2 / shrink, crop.3 / shrink);
    let mut tile =
        Pixmap::new(tw as u32, th as u32).ok_or(FigureError::TooLarge(tw as u32, th as u32))?;
    let width = experiment.width();
    let mask = experiment.mask();
    let (source, target) = (experiment.source_rgb(), experiment.target_rgb());
    let value = |p: usize, c: usize| -> f64 {
        let i = p * CHANNELS + c;
        match membrane {
            None => f64::from(source[i]),
            Some(m) if mask.is_inside(p) => f64::from(source[i]) + m[i],
            Some(_) => f64::from(target[i]),
        }
    };
    let samples = (shrink * shrink) as f64;
    for (index, out) in tile.pixels_mut().iter_mut().enumerate() {
        let (tx, ty) = (index % tw, index / tw);
        let mut rgb = [0.0; 3];
        for dy in 0..shrink {
            for dx in 0..shrink {
                let p = (crop.1 + ty * shrink + dy) * width + crop.0 + tx * shrink + dx;
                for (c, sum) in rgb.iter_mut().enumerate() {
                    *sum += value(p, c).clamp(0.0, 1.0);
                }
            }
        }
        let [r, g, b] = rgb.map(|v| (v / samples * 255.0).round() as u8);
        // invariant: alpha 255 makes any r, g, b a valid premultiplied colour.
        *out = tiny_skia::ColorU8::from_rgba(r, g, b, 255).premultiply();
    }
    Ok(tile)
}

fn draw(picture: &mut Pixmap, tile: &Pixmap, left: u32, top: u32) {
    picture.draw_pixmap(
        left as i32,
        top as i32,
        tile.as_ref(),
        &PixmapPaint::default(),
        Transform::identity(),
        None,
    );
}

/// Every mesh edge, thin and dark, over the mesh tile at `origin`.
fn draw_mesh(
    picture: &mut Pixmap,
    run: &MeshRun,
    crop: (usize, usize, usize, usize),
    shrink: usize,
    origin: (u32, u32),
) {
    let mut path = PathBuilder::new();
    let positions = &run.mesh.positions;
    for (i, j) in run.mesh.edges() {
        let (a, b) = (positions[i as usize], positions[j as usize]);
        path.move_to(a.x as f32, a.y as f32);
        path.line_to(b.x as f32, b.y as f32);
    }
    let Some(path) = path.finish() else {
        return;
    };
    let scale = 1.0 / shrink as f32;
    let transform = Transform::from_translate(origin.0 as f32, origin.1 as f32)
        .pre_scale(scale, scale)
        .pre_translate(-(crop.0 as f32), -(crop.1 as f32));
    let mut paint = Paint::default();
    paint.set_color_rgba8(20, 20, 60, 200);
    paint.anti_alias = true;
    let stroke = Stroke {
        width: 0.7 * shrink as f32,
        ..Stroke::default()
    };
    let mut clip = tiny_skia::Mask::new(picture.width(), picture.height());
    if let (Some(clip), Some(rect)) = (
        clip.as_mut(),
        Rect::from_xywh(
            origin.0 as f32,
            origin.1 as f32,
            (crop.2 / shrink) as f32,
            (crop.3 / shrink) as f32,
        ),
    ) {
        clip.fill_path(
            &PathBuilder::from_rect(rect),
            tiny_skia::FillRule::Winding,
            false,
            Transform::identity(),
        );
    }
    picture.stroke_path(&path, &paint, &stroke, transform, clip.as_ref());
}

fn bar(picture: &mut Pixmap, left: u32, top: u32, width: u32, rgb: [u8; 3]) {
    fill(picture, left, top, (width, BAR), rgb);
}

fn fill(picture: &mut Pixmap, left: u32, top: u32, size: (u32, u32), rgb: [u8; 3]) {
    let Some(rect) = Rect::from_xywh(left as f32, top as f32, size.0 as f32, size.1 as f32) else {
        return;
    };
    let mut paint = Paint::default();
    paint.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
    picture.fill_rect(rect, &paint, Transform::identity(), None);
}
