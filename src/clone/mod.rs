//! clone stage (not yet implemented).
