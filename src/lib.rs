//! lapclone: seamless image cloning and deformation with the combinatorial Laplacian
//! (Cuadros-Vargas, Nonato, Pascucci). The library takes masks, images and scene files in
//! and gives meshes, factored Laplacians, membranes, deformed meshes and rendered frames
//! out; the `lapclone` binary is a thin CLI over it.
//!
//! The modules follow the pipeline: [`mesh`] → [`solve`] → [`clone`] / [`deform`] →
//! [`raster`], driven per frame by [`scene`]. [`pixels`] holds the float image type shared by
//! all stages; [`reference`](mod@reference) holds the pixel-grid and MVC baselines used by tests and benches;
//! [`limits`] the documented resource limits every input is checked against; [`golden`]
//! compares rendered frames with reference frames (`lapclone test` and the project's tests).

pub mod clone;
pub mod deform;
pub mod golden;
pub mod limits;
pub mod mesh;
pub mod output;
pub mod pixels;
pub mod raster;
pub mod reference;
pub mod render;
pub mod scene;
pub mod script;
pub mod simd;
pub mod solve;
pub mod util;
