//! lapclone's measurements, kept out of the library: takes lapclone's pipeline (through its
//! internal stage modules) and gives the baselines it is measured against and the benchmark
//! commands of the `lapclone-bench` binary.
//!
//! - [`reference`](mod@reference): the pixel-grid Poisson membrane, MVC cloning, the quality metrics and
//!   the paper's experiments and figures;
//! - [`commands`]: `lapclone-bench mesh | factor | solver | deform | render | clone | paper |
//!   opencv | track | view | browser`, each printing a table or, with `--json`, one JSON
//!   document;
//! - [`cdp`]: the headless chromium client the `browser` benchmark and the live view's browser
//!   test share;
//! - [`matrix_market`]: the Matrix Market reader `lapclone-bench solver` loads its matrices
//!   with;
//! - [`fixtures`] and [`synth`]: the meshes and masks lapclone's own tests are built on.

pub mod cdp;
pub mod commands;
#[path = "../../tests/common/mesh_fixtures.rs"]
pub mod fixtures;
pub mod matrix_market;
pub mod reference;
#[path = "../../tests/common/synth_masks.rs"]
pub mod synth;
