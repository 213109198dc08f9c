//! lapclone: seamless image cloning and deformation with the combinatorial Laplacian
//! (Cuadros-Vargas, Nonato, Pascucci). The library takes masks or polygons, images and scenes
//! in and gives patch meshes, seamless clones, deformed patches and rendered frames out; the
//! `lapclone` binary (default feature `cli`) is a thin command line over it.
//!
//! The API follows the pipeline:
//!
//! 1. **Mesh** a patch: [`mesh_from_mask`] (a [`BitMask`]) or [`mesh_from_polygons`], tuned
//!    by [`MeshOptions`], gives a [`PatchMesh`] (or [`MeshError`] / [`CloneError`]).
//! 2. **Clone**: a [`PatchCloner`] factors the mesh's Laplacian once; every
//!    [`PatchCloner::clone_onto`] at a new [`Placement`] only switches constraints and
//!    back-substitutes. Its [`CloneOptions`] pick the [`LaplacianKind`], the [`CloneMode`] and
//!    the [`BoundaryData`]. Errors: [`CloneError`].
//! 3. **Deform**: a [`DeformRig`] moves the mesh by drag [`Handle`]s and [`Pin`]s into
//!    [`Deformed`] positions, which [`PatchCloner::clone_deformed`] clones. Errors:
//!    [`DeformError`].
//! 4. **Animate**: an [`animation::Scene`] (built in Rust, or loaded from a `.rhai` file with
//!    [`load_scene`]) is rendered frame by frame by a [`Renderer`]. Its background, and any
//!    patch's source, may be [`animation::Footage`]: numbered plates or a video, one frame
//!    per scene frame. Errors: [`SceneError`], [`RenderError`], [`FootageError`].
//! 5. **Images**: [`FloatImage`] (sources and targets, any 8/16-bit PNG or JPEG) and
//!    [`Canvas`] (the premultiplied frame being composited) with their [`PixelFormat`];
//!    [`Canvas::to_rgba8_image`] hands a frame to the `image` crate. Errors: [`PixelError`].
//! 6. **Output**: [`render_scene`] writes a loaded scene's frames to a path as `lapclone
//!    render` does (a PNG folder, GIF, APNG, Y4M, or MP4/WebM/MOV through ffmpeg; the
//!    [`OutputKind`] the path names, or the one [`RenderOptions`] give), reporting to a
//!    [`RenderProgress`]. Errors: [`OutputError`].
//!
//! Points are [`glam`] vectors, re-exported so callers use the same version.
//!
//! Clone the cat's face of the bundled photo into an espresso:
//!
//! ```
//! use lapclone::glam::DVec2;
//! use lapclone::{mesh_from_mask, BitMask, Canvas, CloneOptions, FloatImage, MeshOptions};
//! use lapclone::{PatchCloner, Placement};
//! use std::path::Path;
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let source = FloatImage::load(Path::new("assets/chelsea.png"))?;
//! let mask = BitMask::load(Path::new("assets/masks/chelsea_face.png"), 0.5)?;
//! let target = FloatImage::load(Path::new("assets/coffee.png"))?;
//! let patch = mesh_from_mask(&mask, None, (source.width(), source.height()), &MeshOptions::default())?;
//! let centre = (patch.bbox_min + patch.bbox_max) / 2.0;
//! let mut cloner = PatchCloner::new(source, patch.result.mesh, &CloneOptions::default())?;
//! let mut canvas = Canvas::from_image(&target);
//! cloner.clone_onto(&mut canvas, &Placement::translate(centre, DVec2::new(288.0, 143.0)))?;
//! let png = canvas.encode_png(target.format())?; // or canvas.save_png(path, format)
//! assert!(png.starts_with(b"\x89PNG"));
//! # Ok(())
//! # }
//! ```
//!
//! Load a scene file and render one frame for the `image` crate:
//!
//! ```
//! use lapclone::{load_scene, Renderer};
//! use std::path::Path;
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let loaded = load_scene(Path::new("scenes/cat_in_coffee.rhai"))?;
//! let mut renderer = Renderer::new(loaded.scene)?;
//! let frame: lapclone::image::RgbaImage = renderer.render_time(1.5)?.to_rgba8_image();
//! assert_eq!(frame.dimensions(), (600, 400));
//! # Ok(())
//! # }
//! ```
//!
//! Features: `cli` (default) builds the `lapclone` program and its terminal dependencies;
//! library users turn it off with `default-features = false`. `gif`, `bmp`, `tiff` and `webp`
//! add those input decoders (PNG and JPEG are always read).

#![warn(missing_docs)]
#![warn(unnameable_types)]
#![forbid(unsafe_code)]

pub use glam;
pub use image;

pub use clone::{
    mesh_from_mask, mesh_from_polygons, Anchor, BoundaryData, CloneError, CloneMode, CloneOptions,
    CloneStats, GlueStats, MembraneStats, PatchCloner, PatchMesh, Placement,
};
pub use deform::{DeformError, DeformOptions, DeformRig, DeformStats, Deformed, Handle, Pin};
pub use limits::{
    check_image_size, feather_in_range, position_error, scale_error, LimitError, MAX_FEATHER,
    MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE, MAX_POSITION, MAX_SCALE,
};
pub use mesh::{
    BitMask, BoundaryLoop, BoundaryPlacement, LoopKind, Mesh, MeshError, MeshOptions, MeshResult,
    MeshStats, Polygon, SanityError, MASK_THRESHOLD,
};
pub use output::{
    render_scene, FrameRange, OutputError, OutputKind, PngCompression, RenderOptions,
    RenderProgress, Rendered, SinkSettings,
};
pub use pixels::{
    Canvas, CanvasPixels, ColorKind, Depth, FloatImage, FootageError, PixelError, PixelFormat,
    PixelRect,
};
pub use raster::{RasterError, RasterStats, MAX_RASTER_THREADS};
pub use render::{DrawnRegion, FrameStats, RenderError, Renderer, SceneUpdate};
/// The scene language's engine: [`SceneError::position`] is its [`rhai::Position`].
pub use rhai;
pub use script::{
    load_scene, load_scene_and_imports, load_scene_cancellable, set_allocation_probe,
    ErrorKind as SceneErrorKind, LoadedScene, SceneError,
};
pub use simd::{levels_to_rgb8, rgb8_to_levels};
pub use solve::{FactorMethod, LaplacianKind, PenaltyOptions, SolveError, SwitchStats};
pub use util::{available_cores, not_a_file, number_text};

/// Opens a scene file as `lapclone render` does: loads and runs it ([`load_scene`]), then
/// [`build_renderer`].
pub fn open_scene(path: &std::path::Path) -> Result<(LoadedScene, Renderer), SceneError> {
    let loaded = load_scene(path)?;
    let renderer = build_renderer(&loaded)?;
    Ok((loaded, renderer))
}

/// Validates a loaded scene (a canvas, patches whose masks and sources exist and fit, ...)
/// and builds its [`Renderer`], which meshes and factors every patch. Every error is a
/// [`SceneError`] positioned at the scene call it is about (the renderer's at the call that
/// made the patch).
pub fn build_renderer(loaded: &LoadedScene) -> Result<Renderer, SceneError> {
    script::validate_scene(loaded)?;
    Renderer::new(loaded.scene.clone()).map_err(|e| output::render_error_at_call(loaded, &e))
}

/// A renderer's error for a loaded scene, positioned as [`build_renderer`] and
/// [`render_scene`] position theirs: at the call that made the patch it is about, or at
/// `canvas(...)` for the background's footage.
pub fn scene_render_error(loaded: &LoadedScene, error: &RenderError) -> SceneError {
    output::render_error_at_call(loaded, error)
}

/// Scenes: the animated description a [`Renderer`] draws, built in Rust or loaded from a
/// `.rhai` file with [`load_scene`]. A [`Scene`](animation::Scene) is a
/// [`SceneCanvas`](animation::SceneCanvas) (size, frame rate, duration,
/// [`Background`](animation::Background)) and layered [`Patch`](animation::Patch)es, each
/// with a [`Shape`](animation::Shape), an animated
/// [`ScenePlacement`](animation::ScenePlacement), drag [`SceneHandle`](animation::SceneHandle)s
/// and [`ScenePin`](animation::ScenePin)s; every animated value is a
/// [`Track`](animation::Track) of [`Key`](animation::Key)s, each with an
/// [`Easing`](animation::Easing). [`Footage`](animation::Footage) (numbered plates through a
/// [`Pattern`](animation::Pattern), or a video) is a background or a patch's animated source;
/// [`Footage::open`](animation::Footage::open) reads its size. Errors: [`FootageError`].
/// The four `Scene…` names keep these apart from the root's [`Canvas`], [`Handle`], [`Pin`]
/// and [`Placement`], which are a frame's pixels and one clone's or deformation's values.
pub mod animation {
    pub use crate::golden::{GoldenSettings, Thresholds};
    pub use crate::pixels::footage::Pattern;
    pub use crate::scene::{
        Background, Canvas as SceneCanvas, Easing, Follow, FollowTarget, Footage, FootageSource,
        FrameState, Handle as SceneHandle, HandleState, Interpolate, Key, KeyError, ModelError,
        Patch, PatchState, Pin as ScenePin, Placement as ScenePlacement, Scene, Shape, Track,
    };
    /// Renamed [`SceneCanvas`].
    #[deprecated(note = "renamed `SceneCanvas`")]
    pub type Canvas = SceneCanvas;
    /// Renamed [`SceneHandle`].
    #[deprecated(note = "renamed `SceneHandle`")]
    pub type Handle = SceneHandle;
    /// Renamed [`ScenePin`].
    #[deprecated(note = "renamed `ScenePin`")]
    pub type Pin = ScenePin;
    /// Renamed [`ScenePlacement`].
    #[deprecated(note = "renamed `ScenePlacement`")]
    pub type Placement = ScenePlacement;
}

/// Declares methods that name stage-internal types: public (and hidden) with the
/// `internals` feature for lapclone's own tests and benchmarks, crate-private otherwise, so
/// the API names only types a user can name.
macro_rules! internal_fn {
    ($(#[$meta:meta])* fn $($rest:tt)*) => {
        #[cfg(feature = "internals")]
        #[doc(hidden)]
        $(#[$meta])* pub fn $($rest)*
        #[cfg(not(feature = "internals"))]
        #[allow(dead_code)]
        $(#[$meta])* pub(crate) fn $($rest)*
    };
}

/// Declares the pipeline's stage modules: private in the library, public (and undocumented)
/// with the `internals` feature, which lapclone's own tests and `lapclone-bench` use.
macro_rules! stage_modules {
    ($($name:ident),* $(,)?) => {$(
        #[cfg(feature = "internals")]
        #[doc(hidden)]
        pub mod $name;
        // Without `internals`, what only the tests and benchmarks reach is unused here.
        #[cfg(not(feature = "internals"))]
        #[allow(dead_code, unused_imports)]
        mod $name;
    )*};
}

/// `eprintln!` that never panics: a line to a closed or full standard error is dropped (the
/// standard macro panics then), and the exit code still says how the run went.
macro_rules! eprint_line {
    ($($arg:tt)*) => {
        $crate::util::stderr_line(format_args!($($arg)*))
    };
}

stage_modules!(
    clone, deform, golden, limits, mesh, output, pixels, png_bands, process, raster, render, scene,
    script, simd, solve, track, util,
);

// The CLI's files name library items as `lapclone::…`, as any other user would.
extern crate self as lapclone;

// The CLI's doc comments are clap's help texts, where `[…]` marks an optional part. The CLI
// is the program, not API: its modules share types among themselves without exporting them.
#[cfg(all(feature = "cli", feature = "internals"))]
#[doc(hidden)]
#[allow(rustdoc::broken_intra_doc_links, unnameable_types)]
pub mod cli;
#[cfg(all(feature = "cli", not(feature = "internals")))]
#[allow(rustdoc::broken_intra_doc_links, unnameable_types)]
mod cli;

/// The `lapclone` program: parses `std::env::args`, runs the subcommand, reports an error on
/// stderr and gives the exit code (0 ok, 1 failure, 2 usage). Only `src/main.rs` calls it.
#[cfg(feature = "cli")]
#[doc(hidden)]
pub fn run_cli() -> i32 {
    use clap::Parser as _;
    let args = match cli::Cli::try_parse() {
        Ok(args) => args,
        Err(error) => return cli::clap_exit(&error),
    };
    match cli::run(args) {
        Ok(()) => 0,
        Err(err) => {
            if let Some(usage) = err.downcast_ref::<cli::UsageError>() {
                eprint_line!("lapclone: {usage}");
                return 2;
            }
            eprint_line!("lapclone: error: {}", cli::describe(&err));
            1
        }
    }
}
