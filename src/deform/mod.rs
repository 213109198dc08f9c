//! deform stage (not yet implemented).
