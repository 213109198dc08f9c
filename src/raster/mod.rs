//! raster stage (not yet implemented).

pub mod overlay;
