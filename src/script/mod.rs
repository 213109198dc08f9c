//! script stage (not yet implemented).
