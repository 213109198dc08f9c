//! lapclone's errors as Python exceptions: takes the library's typed errors and gives
//! `ValueError` with lapclone's message, `FileNotFoundError` for a missing file, and
//! `lapclone.SceneError` (with `file`, `line` and `column`) for a scene file's errors; an
//! output's errors as `ValueError` (bad format, an output that is an input),
//! `FileNotFoundError` (missing folder) or `OSError` (the write failed). A clone's errors
//! that would name what only the CLI has (a mask offset, a vertex budget) say what Python's
//! API can do instead.

use lapclone::{CloneError, MeshError, OutputError};
use pyo3::exceptions::{
    PyFileExistsError, PyFileNotFoundError, PyIndexError, PyIsADirectoryError,
    PyNotADirectoryError, PyOSError, PyOverflowError, PyValueError,
};
use pyo3::prelude::*;

pyo3::create_exception!(
    lapclone,
    SceneError,
    pyo3::exceptions::PyException,
    "A scene file's error, positioned: `file`, `line` and `column` (1-based; None when \
     unknown) say where, the message says `file:line:col: what`."
);

/// Any lapclone error whose message is the whole story (bad masks, options, placements,
/// arrays): a `ValueError`.
pub fn to_py(error: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(error.to_string())
}

/// A meshing or cloning error as a `ValueError`, in terms of what `Cloner` and `mesh` take:
/// no mask offset (a mask has the source's height and width) and no `max_vertices` (density,
/// or a simpler mask, gives fewer vertices); sizes in numpy's order, (height, width).
pub fn clone_error(error: CloneError) -> PyErr {
    let message = match error {
        CloneError::MaskSize { mask, source_size } => format!(
            "mask has height and width ({}, {}) but source ({}, {}): they must be the same; \
             crop or pad the mask to the source's size",
            mask.1, mask.0, source_size.1, source_size.0
        ),
        CloneError::Mesh(MeshError::VertexBudget {
            max_vertices,
            needed,
        }) => format!(
            "the mask's boundary needs {needed} vertices at this density, more than the \
             {max_vertices} a patch mesh may have: raise density (the longest boundary edge, \
             in pixels) or use a mask of fewer, larger pieces and holes"
        ),
        CloneError::Mesh(MeshError::BoundaryTooLong { edges, max_edges }) => format!(
            "the mask's boundary has {edges} pixel edges, more than the {max_edges} a patch \
             mesh allows: use a smoother mask (fewer, larger pieces and holes)"
        ),
        other => other.to_string(),
    };
    PyValueError::new_err(message)
}

/// A number argument of type `T` whose value outside `T`'s range (a negative thread count,
/// `2**1024` as a scale) is a `ValueError` like any other bad value, not an `OverflowError`.
pub struct InRange<T>(pub T);

impl<'py, T: FromPyObject<'py>> FromPyObject<'py> for InRange<T> {
    fn extract_bound(object: &Bound<'py, PyAny>) -> PyResult<Self> {
        T::extract_bound(object)
            .map(InRange)
            .map_err(|e| overflow_as(object.py(), e, PyValueError::new_err))
    }
}

/// A frame index: one outside any integer lapclone holds is past the end, an `IndexError`.
pub struct FrameIndex(pub i64);

impl<'py> FromPyObject<'py> for FrameIndex {
    fn extract_bound(object: &Bound<'py, PyAny>) -> PyResult<Self> {
        i64::extract_bound(object)
            .map(FrameIndex)
            .map_err(|e| overflow_as(object.py(), e, PyIndexError::new_err))
    }
}

/// `error`, or when it is an `OverflowError`, `make` of its message.
fn overflow_as(py: Python<'_>, error: PyErr, make: fn(String) -> PyErr) -> PyErr {
    if error.is_instance_of::<PyOverflowError>(py) {
        make(format!("a number is out of range: {}", error.value(py)))
    } else {
        error
    }
}

/// A scene error as `lapclone.SceneError` with its position attributes.
pub fn scene_error(py: Python<'_>, error: &lapclone::SceneError) -> PyResult<PyErr> {
    let err = SceneError::new_err(error.to_string());
    let value = err.value(py);
    let attributes = [
        (
            "file",
            error
                .file
                .display()
                .to_string()
                .into_pyobject(py)?
                .into_any(),
        ),
        ("line", error.line().into_pyobject(py)?.into_any()),
        ("column", error.column().into_pyobject(py)?.into_any()),
        (
            "message",
            error.message.clone().into_pyobject(py)?.into_any(),
        ),
    ];
    for (name, attribute) in attributes {
        value.setattr(name, attribute)?;
    }
    Ok(err)
}

/// An output error as the Python exception that says what kind of failure it is; the
/// message is lapclone's, with its causes.
pub fn output_error(py: Python<'_>, error: OutputError) -> PyErr {
    let message = with_causes(&error);
    match error {
        // The library's message names the command line's `--force`.
        OutputError::ForeignFrames {
            folder,
            count,
            example,
        } => PyFileExistsError::new_err(format!(
            "{} holds {count} frame files of another render (e.g. {example}); pass \
             force=True to remove them, or render into another folder",
            folder.display()
        )),
        OutputError::Scene(scene) => scene_error(py, &scene).unwrap_or_else(|e| e),
        OutputError::UnknownFormat(_)
        | OutputError::UnknownExtension { .. }
        | OutputError::StdoutNeedsY4m
        | OutputError::FramesOutOfRange { .. }
        | OutputError::ReplacesInput { .. }
        | OutputError::TooManyFrames(_) => PyValueError::new_err(message),
        OutputError::MissingFolder { exists: false, .. } => PyFileNotFoundError::new_err(message),
        OutputError::MissingFolder { exists: true, .. } | OutputError::NotAFrameFolder(_) => {
            PyNotADirectoryError::new_err(message)
        }
        OutputError::IsAFolder { .. } => PyIsADirectoryError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

/// `error: cause: …`, each cause once (lapclone's messages often end with their cause's).
fn with_causes(error: &dyn std::error::Error) -> String {
    let mut line = error.to_string();
    let mut cause = error.source();
    while let Some(next) = cause {
        let text = next.to_string();
        if !line.contains(&text) {
            line.push_str(": ");
            line.push_str(&text);
        }
        cause = next.source();
    }
    line
}
