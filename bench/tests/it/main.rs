//! lapclone-bench's integration tests, one binary with a module per area: the quality
//! baselines (pixel-grid Poisson, MVC, metrics, synthetic cases) and the paper's experiments
//! through the library and the built `lapclone-bench` binary, and the arguments and JSON of
//! `lapclone-bench opencv`.

mod opencv_cli;
mod paper_cli;
mod paper_experiment;
mod reference_metrics;
mod reference_mvc;
mod reference_poisson;
mod reference_synthetic;
