//! Errors of the render stage: which patch failed, and why.

use std::path::PathBuf;

use crate::clone::CloneError;
use crate::deform::DeformError;
use crate::pixels::PixelError;

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("patch `{patch}`: {source}")]
    Clone {
        patch: String,
        #[source]
        source: CloneError,
    },
    #[error("patch `{patch}`: {source}")]
    Deform {
        patch: String,
        #[source]
        source: DeformError,
    },
    #[error("patch `{patch}`: mask {}: {source}", path.display())]
    Mask {
        patch: String,
        path: PathBuf,
        /// Boxed: mesh errors are large and every render result carries this type.
        #[source]
        source: Box<crate::mesh::MeshError>,
    },
    #[error(transparent)]
    Pixels(#[from] PixelError),
    #[error("{}{source}", patch.as_ref().map(|p| format!("patch `{p}`: source footage: ")).unwrap_or_else(|| "background footage: ".into()))]
    Footage {
        /// The patch whose source this is; `None` for the background.
        patch: Option<String>,
        #[source]
        source: Box<crate::pixels::FootageError>,
    },
    #[error("scene is not valid: {0}")]
    Scene(#[from] crate::scene::ModelError),
}

impl RenderError {
    /// The scene patch this error is about, if any (to position it at the patch's call).
    pub fn patch_name(&self) -> Option<&str> {
        match self {
            RenderError::Clone { patch, .. }
            | RenderError::Deform { patch, .. }
            | RenderError::Mask { patch, .. } => Some(patch),
            RenderError::Footage { patch, .. } => patch.as_deref(),
            RenderError::Pixels(_) | RenderError::Scene(_) => None,
        }
    }
}
