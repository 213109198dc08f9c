//! Followed tracks: takes what a scene's `follow` call asked for and the tracks it keyed,
//! and gives whether a patch's (or handle's) tracks still hold exactly those keys — then the
//! REPL lists them as one entry, `:save` writes the `follow` call again instead of every key,
//! and `check` warns about frames the track does not reach.

use std::path::PathBuf;

use glam::DVec2;

use super::track::Track;
use super::types::Patch;

/// What a `follow` call drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FollowTarget {
    /// The patch's placement (`at`, and `rotate` / `scale` when followed).
    Patch,
    /// The target of the patch's handle with this index.
    Handle(usize),
}

/// One `follow` call: the file, its settings as written, and the tracks it set.
#[derive(Clone, Debug, PartialEq)]
pub struct Follow {
    /// The track file (resolved against the scene's folder).
    pub file: PathBuf,
    /// What it drives.
    pub target: FollowTarget,
    /// The point followed (from 1).
    pub point: usize,
    /// The offset added to the point.
    pub offset: DVec2,
    /// `rotate` as written (`None`: not written).
    pub rotate: Option<bool>,
    /// `scale` as written (`None`: not written).
    pub scale: Option<bool>,
    /// `from_frame` as written.
    pub from_frame: Option<u64>,
    /// The position keys it set.
    pub at: Track<DVec2>,
    /// The rotation keys it set, when it followed the rotation.
    pub rotation: Option<Track<f64>>,
    /// The scale keys it set, when it followed the scale.
    pub scale_keys: Option<Track<f64>>,
}

impl Follow {
    /// Whether `patch`'s tracks still hold exactly the keys this call set.
    pub fn is_intact(&self, patch: &Patch) -> bool {
        match self.target {
            FollowTarget::Patch => {
                let p = &patch.placement;
                p.position == self.at
                    && self.rotation.as_ref().is_none_or(|r| *r == p.rotation)
                    && self.scale_keys.as_ref().is_none_or(|s| *s == p.scale)
            }
            FollowTarget::Handle(i) => patch.handles.get(i).is_some_and(|h| {
                h.to == self.at && self.rotation.as_ref().is_none_or(|r| *r == h.rotation)
            }),
        }
    }

    /// How many keys it set on its position track.
    pub fn key_count(&self) -> usize {
        self.at.keys().len()
    }

    /// The file name as lists show it.
    pub fn file_name(&self) -> String {
        self.file
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| self.file.display().to_string())
    }
}

impl Patch {
    /// The follows whose keys are still in place, for `target`.
    pub fn intact_follows(&self, target: FollowTarget) -> impl Iterator<Item = &Follow> {
        self.follows
            .iter()
            .filter(move |f| f.target == target && f.is_intact(self))
    }
}
