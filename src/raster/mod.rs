//! raster stage (not yet implemented).
