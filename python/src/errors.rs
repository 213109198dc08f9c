//! lapclone's errors as Python exceptions: takes the library's typed errors and gives
//! `ValueError` with lapclone's message, `FileNotFoundError` for a missing file, and
//! `lapclone.SceneError` (with `file`, `line` and `column`) for a scene file's errors.

use pyo3::exceptions::PyValueError;
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
