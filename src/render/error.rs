//! Errors of the render stage: which patch failed, and why.

use crate::util::ShowPath;
use std::path::PathBuf;

use crate::clone::CloneError;
use crate::deform::DeformError;
use crate::pixels::PixelError;

/// Why building a renderer or rendering a frame failed.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Cloning a patch failed.
    #[error("patch `{patch}`: {source}")]
    Clone {
        /// The patch's name.
        patch: String,
        /// The cloner's error.
        #[source]
        source: CloneError,
    },
    /// Deforming a patch failed.
    #[error("patch `{patch}`: {source}")]
    Deform {
        /// The patch's name.
        patch: String,
        /// The rig's error.
        #[source]
        source: DeformError,
    },
    /// A patch's mask cannot be read or meshed.
    #[error("patch `{patch}`: mask {}: {source}", path.shown())]
    Mask {
        /// The patch's name.
        patch: String,
        /// The mask file.
        path: PathBuf,
        /// Boxed: mesh errors are large and every render result carries this type.
        #[source]
        source: Box<crate::mesh::MeshError>,
    },
    /// A polygon patch whose polygons all lie outside its source image: it would clone
    /// nothing but the source's edge pixels repeated.
    #[error("patch `{patch}`: its polygons lie entirely outside its {}×{} source (polygon points are source pixels)", size.0, size.1)]
    OutsideSource {
        /// The patch's name.
        patch: String,
        /// The source's width and height.
        size: (u32, u32),
    },
    /// The scene's still sources hold more pixels in all than a scene may; `patch` is the
    /// first whose source goes past the limit.
    #[error("patch `{patch}`: {source}")]
    Sources {
        /// The patch's name.
        patch: String,
        /// The limit passed.
        #[source]
        source: crate::limits::LimitError,
    },
    /// Reading an image or drawing the background failed.
    #[error(transparent)]
    Pixels(#[from] PixelError),
    /// Reading footage (an image sequence or a video) failed.
    #[error("{}{source}", patch.as_ref().map(|p| format!("patch `{p}`: source footage: ")).unwrap_or_else(|| "background footage: ".into()))]
    Footage {
        /// The patch whose source this is; `None` for the background.
        patch: Option<String>,
        /// Why.
        #[source]
        source: Box<crate::pixels::FootageError>,
    },
    /// The scene is not valid.
    #[error("scene is not valid: {0}")]
    Scene(#[from] crate::scene::ModelError),
}

impl RenderError {
    /// The scene patch this error is about, if any (to position it at the patch's call).
    pub fn patch_name(&self) -> Option<&str> {
        match self {
            RenderError::Clone { patch, .. }
            | RenderError::Deform { patch, .. }
            | RenderError::Mask { patch, .. }
            | RenderError::OutsideSource { patch, .. }
            | RenderError::Sources { patch, .. } => Some(patch),
            RenderError::Footage { patch, .. } => patch.as_deref(),
            RenderError::Pixels(_) | RenderError::Scene(_) => None,
        }
    }

    /// Whether it is about the background (its footage), so positioned at `canvas(...)`.
    pub fn is_about_background(&self) -> bool {
        matches!(self, RenderError::Footage { patch: None, .. })
    }

    /// A footage error of `patch`'s animated source (`None`: of the background footage).
    pub(crate) fn footage(patch: Option<&str>, error: crate::pixels::FootageError) -> Self {
        RenderError::Footage {
            patch: patch.map(str::to_string),
            source: Box::new(error),
        }
    }
}
