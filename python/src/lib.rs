//! The `lapclone._lapclone` extension module, which the `lapclone` Python package re-exports:
//! numpy arrays in and out of lapclone's library. `cloner` has `seamless_clone` (a drop-in
//! for `cv2.seamlessClone`), `Cloner` and `mesh`; `scene` has `Scene`; `arrays` converts
//! arrays; `errors` maps lapclone's errors to Python exceptions.

#![forbid(unsafe_code)]

mod arrays;
mod cloner;
mod errors;
mod patch;
mod scene;

use pyo3::prelude::*;

#[pymodule]
fn _lapclone(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("NORMAL_CLONE", cloner::NORMAL_CLONE)?;
    m.add("MIXED_CLONE", cloner::MIXED_CLONE)?;
    m.add("MONOCHROME_TRANSFER", cloner::MONOCHROME_TRANSFER)?;
    m.add("SceneError", m.py().get_type::<errors::SceneError>())?;
    m.add_class::<cloner::Cloner>()?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<scene::SceneFrames>()?;
    m.add_function(wrap_pyfunction!(cloner::seamless_clone, m)?)?;
    m.add_function(wrap_pyfunction!(cloner::mesh, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
