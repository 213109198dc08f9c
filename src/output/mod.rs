//! output stage (not yet implemented).
