//! Followed tracks: takes what a scene's `follow` call asked for and the tracks it keyed,
//! and gives whether a patch's (or handle's) tracks still hold exactly those keys — then the
//! REPL lists them as one entry, `:save` writes the `follow` call again instead of every key,
//! and `check` warns about frames the track does not reach.


use crate::util::ShowPath;
use super::types::{Follow, FollowTarget, Patch};


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
            .unwrap_or_else(|| self.file.shown().to_string())
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
