//! Baselines the combinatorial-Laplacian clone is measured against; used by tests and
//! benches, never by the render path. It takes pixel masks, boundary data and meshes in and
//! gives reference membranes and quality figures out:
//!
//! - [`grid_mask`]: the pixel mask shared by the reference solver and the metrics;
//! - [`poisson_membrane`](fn@poisson_membrane): the exact pixel-grid Laplace membrane (Pérez et al. 2003), the
//!   quality reference;
//! - [`mvc`]: Mean-Value-Coordinates cloning (Farbman et al. 2009) on a triangle mesh, the
//!   speed and quality baseline of the paper's Table I and Fig. 5;
//! - [`metrics`]: PSNR over a mask, the seam step across the patch boundary, uncovered mask
//!   pixels, and a one-call comparison of a membrane against the pixel-grid reference;
//! - [`synthetic`]: masks at the sizes of the paper's Table I models;
//! - [`paper_models`]: those masks with source/target photos cut from the bundled assets;
//! - [`mesh_sampler`]: a mesh membrane read back at pixel centres;
//! - [`experiment`]: the paper's comparison (Table I, Fig. 5, density sweep) as library code;
//! - [`figure`]: the Fig.-5-style comparison picture.
//!
//! Image buffers throughout are row-major and pixel-interleaved: sample `c` of pixel
//! `(x, y)` sits at `(y * width + x) * channels + c`.

pub mod experiment;
pub mod figure;
pub mod grid_mask;
pub mod mesh_sampler;
pub mod metrics;
pub mod mvc;
pub mod paper_models;
pub mod poisson_membrane;
pub mod synthetic;

pub use grid_mask::{GridMask, MaskError};
pub use metrics::{
    composite, psnr, psnr_by_ring, ring_of_pixels, seam_step, uncovered_pixels, ComparisonInput,
    MembraneComparison, MetricError, SeamStep,
};
pub use mvc::{mean_value_coordinates, MvcError, MvcWeights};
pub use poisson_membrane::{poisson_membrane, GridMembrane, GridPoisson, PoissonError};
