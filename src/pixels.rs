//! Float images shared by all stages (not yet implemented).
