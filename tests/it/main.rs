//! lapclone's integration tests, one binary with a module per area (linking one binary
//! instead of one per file keeps a fresh `cargo test` short). Each module tests one stage
//! or command through the library (with the `internals` feature) or the built `lapclone`
//! binary; `tests/common/` holds the shared helpers, declared here once.

#[path = "../common/solve_checks.rs"]
mod checks;
#[path = "../common/files.rs"]
mod files;
#[path = "../common/clone_fixtures.rs"]
mod fixtures;
#[path = "../common/golden.rs"]
mod golden;
// lapclone-bench's reader, for the written Laplacian's round trip.
#[path = "../../bench/src/matrix_market.rs"]
#[allow(dead_code)]
mod matrix_market;
#[path = "../common/mesh_fixtures.rs"]
mod mesh_fixtures;
#[path = "../common/processes.rs"]
mod processes;
#[path = "../common/raster_meshes.rs"]
mod raster_meshes;
#[path = "../common/synth_masks.rs"]
mod synth;
#[path = "../common/track_footage.rs"]
mod track_footage;

mod architecture;
mod bad_input;
mod clone_boundary_data;
mod clone_cli;
mod clone_expand;
mod clone_glue;
mod clone_golden;
mod clone_numeric;
mod clone_placement;
mod deform_basic;
mod deform_switching;
mod determinism_cli;
mod footage_api;
mod fuzz_mesh;
mod fuzz_scene;
mod hostile_cli;
mod interrupt_cli;
mod limits;
mod mask_agreement;
mod mesh_angles;
mod mesh_centre_loops;
mod mesh_cli;
mod mesh_contour;
mod mesh_quality_options;
mod mesh_sanity;
mod mesh_shapes;
mod numeric_faults;
mod output_apng;
mod output_formats;
mod output_gif;
mod output_render_scene;
mod output_rule;
mod output_writers;
mod pixels_bilinear;
mod pixels_formats;
mod png_bands;
mod png_bands_huffman;
mod program_lookup;
mod raster_covered;
mod raster_draw;
mod raster_fill_rule;
mod raster_golden;
mod raster_overlay;
mod render_cli;
mod repl_pty;
mod repl_session;
mod repl_set_scene;
mod scene_check_cli;
mod scene_editing;
mod scene_golden;
mod scene_language;
mod scene_renames;
mod scene_roundtrip;
mod scene_tracks;
mod simd_paths;
mod solve_factor;
mod solve_layout;
mod solve_panels;
mod solve_supernodal;
mod solve_supernodes;
mod solve_update;
mod test_cli;
mod track_cli;
mod track_follow;
mod track_video;
mod video_cli;
mod video_encode;
mod view_browser;
mod view_faults;
mod view_open;
mod view_ws;
