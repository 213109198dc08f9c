//! solve stage (not yet implemented).
