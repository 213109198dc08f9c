//! `lapclone.Cloner`, `lapclone.seamless_clone` and `lapclone.mesh`: take numpy arrays and
//! Python numbers, check them (every bad value a `ValueError`), and give arrays back through
//! [`Patch`]; `seamless_clone` reads its arguments as `cv2.seamlessClone` does.

use lapclone::glam::DVec2;
use lapclone::number_text;
use lapclone::{
    mesh_from_mask, Anchor, BitMask, BoundaryData, CloneMode, CloneOptions, Handle, LaplacianKind,
    MeshOptions, Pin, Placement,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::arrays::{self, Layout};
use crate::errors::{clone_error, to_py, InRange};
use crate::patch::{Patch, Pose, MASK_THRESHOLD};

/// `cv2.NORMAL_CLONE`.
pub const NORMAL_CLONE: i64 = 1;
/// `cv2.MIXED_CLONE` (refused).
pub const MIXED_CLONE: i64 = 2;
/// `cv2.MONOCHROME_TRANSFER`.
pub const MONOCHROME_TRANSFER: i64 = 3;

/// Cloner(source, mask, *, density=3.0, laplacian="combinatorial", mode="normal",
/// feather=0.0, boundary_data="hat-average", bgr=False, threads=None)
///
/// A patch meshed and factored once, cloned onto any number of targets: a loop over video
/// frames pays only the per-frame solve. Arrays are RGB(A) (BGR(A) with `bgr=True`), grey
/// or colour, uint8 or uint16; the mask is inside where its luma (or alpha) is at least half
/// scale.
#[pyclass(module = "lapclone", frozen)]
pub struct Cloner {
    patch: Patch,
    bgr: bool,
    source_layout: Layout,
}

#[pymethods]
impl Cloner {
    #[new]
    #[pyo3(signature = (source, mask, *, density=InRange(3.0), laplacian="combinatorial", mode="normal", feather=InRange(0.0), boundary_data="hat-average", bgr=false, threads=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        mask: &Bound<'_, PyAny>,
        density: InRange<f64>,
        laplacian: &str,
        mode: &str,
        feather: InRange<f64>,
        boundary_data: &str,
        bgr: bool,
        threads: Option<InRange<usize>>,
    ) -> PyResult<Self> {
        let (threads, density, feather) = (threads.map(|t| t.0), density.0, feather.0);
        // Asked before the cast to the option's f32, so the message names the value given.
        if !lapclone::feather_in_range(feather) {
            return Err(PyValueError::new_err(format!(
                "feather must lie in [0, {}], not {}",
                lapclone::MAX_FEATHER,
                number_text(feather)
            )));
        }
        if threads == Some(0) {
            return Err(PyValueError::new_err("threads must be at least 1"));
        }
        let laplacian = LaplacianKind::from_name(laplacian).ok_or_else(|| {
            PyValueError::new_err(format!(
                "laplacian must be 'combinatorial' or 'cotangent', not {laplacian:?}"
            ))
        })?;
        let mode = CloneMode::from_name(mode).ok_or_else(|| {
            PyValueError::new_err(format!(
                "mode must be 'normal' or 'monochrome', not {mode:?}"
            ))
        })?;
        let boundary_data: BoundaryData = boundary_data.parse().map_err(PyValueError::new_err)?;
        let options = CloneOptions {
            laplacian,
            mode,
            feather: feather as f32,
            boundary_data,
        };
        build(py, source, mask, density, &options, bgr, threads)
    }

    /// Clones the patch onto `target` (any uint8/uint16 grey, RGB or RGBA array) with its
    /// anchor at `at`, scaled, rotated (degrees, clockwise on screen), deformed by `drags`
    /// ((x0, y0), (x1, y1)[, radius]) and `pins` (source pixels); returns the result, or
    /// writes it into `out` (which may be `target`) and returns that. The same pixels as
    /// `lapclone clone` with the same images and flags. The GIL is released while it
    /// computes.
    #[pyo3(signature = (target, at, *, scale=InRange(1.0), rotate=InRange(0.0), drags=Vec::new(), pins=Vec::new(), anchor="centre", out=None))]
    #[allow(clippy::too_many_arguments)]
    fn clone<'py>(
        &self,
        target: &Bound<'py, PyAny>,
        at: &Bound<'py, PyAny>,
        scale: InRange<f64>,
        rotate: InRange<f64>,
        drags: Vec<Bound<'py, PyAny>>,
        pins: Vec<Bound<'py, PyAny>>,
        anchor: &str,
        out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let layout = target_layout(target, out, "target")?;
        let anchor = match anchor {
            "centre" | "center" => Anchor::Centre,
            "topleft" | "top-left" => Anchor::TopLeft,
            other => {
                return Err(PyValueError::new_err(format!(
                    "anchor must be 'centre' or 'topleft', not {other:?}"
                )))
            }
        };
        let at = point(at, "at")?;
        let (scale, rotate) = (scale.0, rotate.0);
        if let Some(why) = lapclone::scale_error(scale) {
            return Err(PyValueError::new_err(format!("scale {why}")));
        }
        if !(rotate.is_finite() && rotate.abs() <= lapclone::MAX_POSITION) {
            return Err(PyValueError::new_err(format!(
                "rotate must be a finite number of degrees within ±{:e}, not {}",
                lapclone::MAX_POSITION,
                number_text(rotate)
            )));
        }
        let handles = drags
            .iter()
            .map(|d| drag(d, self.patch.drag_radius))
            .collect::<PyResult<Vec<_>>>()?;
        let pins = pins
            .iter()
            .map(|p| point(p, "a pin").map(Pin))
            .collect::<PyResult<Vec<_>>>()?;
        let pose = Pose {
            placement: Placement {
                pivot: anchor.point(self.patch.bbox_min, self.patch.bbox_max),
                at,
                scale,
                rotation_deg: rotate,
            },
            handles,
            pins,
        };
        self.patch.clone_onto(target, &layout, self.bgr, &pose, out)
    }

    /// Vertices of the patch mesh.
    #[getter]
    fn vertex_count(&self) -> usize {
        self.patch.vertex_count
    }

    /// Triangles of the patch mesh.
    #[getter]
    fn triangle_count(&self) -> usize {
        self.patch.triangle_count
    }

    /// The bounding box of the mask's inside pixels, (x0, y0, x1, y1), pixel corners.
    #[getter]
    fn bbox(&self) -> (f64, f64, f64, f64) {
        let (a, b) = (self.patch.bbox_min, self.patch.bbox_max);
        (a.x, a.y, b.x, b.y)
    }

    /// The source's shape (rows, columns[, channels]).
    #[getter]
    fn source_shape(&self) -> Vec<usize> {
        let l = &self.source_layout;
        let mut shape = vec![l.height, l.width];
        shape.extend(l.channels);
        shape
    }

    fn __repr__(&self) -> String {
        let (a, b) = (self.patch.bbox_min, self.patch.bbox_max);
        format!(
            "lapclone.Cloner(vertices={}, triangles={}, bbox=({}, {}, {}, {}))",
            self.patch.vertex_count, self.patch.triangle_count, a.x, a.y, b.x, b.y
        )
    }
}

/// Checks the arrays and options and builds the patch (mesh and factor).
fn build(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    mask: &Bound<'_, PyAny>,
    density: f64,
    options: &CloneOptions,
    bgr: bool,
    threads: Option<usize>,
) -> PyResult<Cloner> {
    let mesh_options = mesh_options(density)?;
    let source = arrays::read_picture(source, "source", bgr)?;
    let mask = arrays::read_mask(mask, "mask", bgr)?;
    let source_layout = source.layout;
    let patch = Patch::new(py, source, mask, &mesh_options, options, threads)?;
    Ok(Cloner {
        patch,
        bgr,
        source_layout,
    })
}

/// `lapclone clone`'s mesh options with `density` (its `--density`).
fn mesh_options(density: f64) -> PyResult<MeshOptions> {
    if !(density.is_finite() && density > 0.0) {
        return Err(PyValueError::new_err(format!(
            "density must be a finite length > 0 px, not {}",
            number_text(density)
        )));
    }
    let options = MeshOptions {
        density,
        ..MeshOptions::default()
    };
    options.validate().map_err(to_py)?;
    Ok(options)
}

/// The target's layout, and `out`'s check against it.
fn target_layout(
    target: &Bound<'_, PyAny>,
    out: Option<&Bound<'_, PyAny>>,
    what: &str,
) -> PyResult<Layout> {
    let layout = arrays::layout_of(target, what, false)?;
    if let Some(out) = out {
        arrays::check_out(out, &layout)?;
    }
    Ok(layout)
}

/// A point from two numbers (a tuple, a list, a numpy array), each finite and within the
/// positions lapclone takes (`lapclone clone`'s bound).
fn point(value: &Bound<'_, PyAny>, what: &str) -> PyResult<DVec2> {
    let bad = || PyValueError::new_err(format!("{what} must be two numbers (x, y)"));
    let (x, y) = match value.extract::<(f64, f64)>() {
        Ok(pair) => pair,
        Err(_) => match value.extract::<Vec<f64>>().map_err(|_| bad())?[..] {
            [x, y] => (x, y),
            _ => return Err(bad()),
        },
    };
    for v in [x, y] {
        let why = match v.is_finite() {
            true => lapclone::position_error(v),
            false => Some(format!("{} is not finite", number_text(v))),
        };
        if let Some(why) = why {
            return Err(PyValueError::new_err(format!("{what}: {why}")));
        }
    }
    Ok(DVec2::new(x, y))
}

/// A drag `((x0, y0), (x1, y1))` or `((x0, y0), (x1, y1), radius)` in source pixels.
fn drag(value: &Bound<'_, PyAny>, default_radius: f64) -> PyResult<Handle> {
    let bad = || {
        PyValueError::new_err(
            "a drag must be ((x0, y0), (x1, y1)) or ((x0, y0), (x1, y1), radius)".to_string(),
        )
    };
    let parts: Vec<Bound<'_, PyAny>> = value.extract().map_err(|_| bad())?;
    let radius = match parts.len() {
        2 => default_radius,
        3 => {
            let r: f64 = parts[2].extract().map_err(|_| bad())?;
            if !(r.is_finite() && r > 0.0) {
                return Err(PyValueError::new_err(format!(
                    "a drag's radius must be a finite number > 0, not {}",
                    number_text(r)
                )));
            }
            r
        }
        _ => return Err(bad()),
    };
    let from = point(&parts[0], "a drag's start")?;
    let to = point(&parts[1], "a drag's end")?;
    Ok(Handle::drag(from, to, radius))
}

/// A whole pixel `p` as `cv2.seamlessClone` takes it (integers; integral floats too).
fn pixel(value: &Bound<'_, PyAny>) -> PyResult<[i64; 2]> {
    // Through `point`, so whole numbers past the position bound are refused as floats are.
    let p = point(value, "p")?;
    if p.x.fract() != 0.0 || p.y.fract() != 0.0 {
        return Err(PyValueError::new_err(format!(
            "p must be a whole pixel (x, y), not ({}, {})",
            number_text(p.x),
            number_text(p.y)
        )));
    }
    Ok([p.x as i64, p.y as i64])
}

/// `cv2.seamlessClone` with lapclone: the same arguments, BGR arrays and placement (the
/// centre of the mask's bounding box goes to the pixel `p` of `dst`); `flags` is
/// NORMAL_CLONE or MONOCHROME_TRANSFER (MIXED_CLONE raises ValueError). Deliberate
/// differences: no assert at the borders (the patch is clipped), holes and several pieces
/// are allowed, and the mask is not eroded (the blend's boundary runs through the centres of
/// the first outside pixels). Returns a new array like `dst`.
#[pyfunction]
#[pyo3(signature = (src, dst, mask, p, flags=InRange(NORMAL_CLONE)))]
pub fn seamless_clone<'py>(
    py: Python<'py>,
    src: &Bound<'py, PyAny>,
    dst: &Bound<'py, PyAny>,
    mask: &Bound<'py, PyAny>,
    p: &Bound<'py, PyAny>,
    flags: InRange<i64>,
) -> PyResult<Bound<'py, PyAny>> {
    let flags = flags.0;
    let mode = match flags {
        NORMAL_CLONE => CloneMode::Normal,
        MONOCHROME_TRANSFER => CloneMode::Monochrome,
        MIXED_CLONE => {
            return Err(PyValueError::new_err(
                "MIXED_CLONE is not offered: lapclone clones the source's texture \
                 (NORMAL_CLONE) or its texture in the target's colours (MONOCHROME_TRANSFER); \
                 to keep the target's own detail at the edge, soften the patch with \
                 Cloner(..., feather=pixels) or leave that detail out of the mask",
            ))
        }
        other => {
            return Err(PyValueError::new_err(format!(
                "flags must be NORMAL_CLONE (1) or MONOCHROME_TRANSFER (3), not {other}"
            )))
        }
    };
    let p = pixel(p)?;
    let layout = target_layout(dst, None, "dst")?;
    let src_layout = arrays::layout_of(src, "src", false)?;
    let mask_layout = arrays::layout_of(mask, "mask", true)?;
    if (mask_layout.height, mask_layout.width) != (src_layout.height, src_layout.width) {
        return Err(PyValueError::new_err(format!(
            "mask has height and width ({}, {}) but src ({}, {}): they must be the same",
            mask_layout.height, mask_layout.width, src_layout.height, src_layout.width
        )));
    }
    let options = CloneOptions {
        mode,
        ..CloneOptions::default()
    };
    let cloner = build(
        py,
        src,
        mask,
        MeshOptions::default().density,
        &options,
        true,
        None,
    )?;
    let placement = Placement::centred_on_pixel(cloner.patch.bbox_min, cloner.patch.bbox_max, p);
    let pose = Pose {
        placement,
        handles: Vec::new(),
        pins: Vec::new(),
    };
    cloner.patch.clone_onto(dst, &layout, true, &pose, None)
}

/// The patch mesh of `mask` (inside where its luma, or alpha, is at least half scale; a
/// colour mask's channels in BGR order with `bgr=True`), as `Cloner` meshes it:
/// `(vertices, triangles)`.
#[pyfunction]
#[pyo3(signature = (mask, *, density=InRange(3.0), bgr=false))]
pub fn mesh<'py>(
    py: Python<'py>,
    mask: &Bound<'py, PyAny>,
    density: InRange<f64>,
    bgr: bool,
) -> PyResult<arrays::MeshArrays<'py>> {
    let options = mesh_options(density.0)?;
    let mask = arrays::read_mask(mask, "mask", bgr)?;
    let size = (mask.image.width(), mask.image.height());
    let patch = py.allow_threads(|| {
        let bits = BitMask::from_image(&mask.image, MASK_THRESHOLD);
        mesh_from_mask(&bits, None, size, &options).map_err(clone_error)
    })?;
    let mesh = &patch.result.mesh;
    let vertices: Vec<[f64; 2]> = mesh.positions.iter().map(|p| [p.x, p.y]).collect();
    arrays::mesh_arrays(py, &vertices, &mesh.triangles)
}
