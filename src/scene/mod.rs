//! scene stage (not yet implemented).
