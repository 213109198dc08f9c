//! reference stage (not yet implemented).
