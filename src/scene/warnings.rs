//! Things a scene allows but a user probably did not mean: takes a [`Scene`] and gives
//! warnings as sentences (today: keys after the scene's end, which no frame shows).

use super::follow::{Follow, FollowTarget};
use super::track::{Interpolate, Track};
use super::types::Scene;

impl Scene {
    /// One line per track whose keys run past the scene's duration.
    pub fn warnings(&self) -> Vec<String> {
        let end = self.canvas.duration;
        let mut out = Vec::new();
        for patch in &self.patches {
            let p = &patch.placement;
            let owner = format!("patch {:?}", patch.name);
            late(&mut out, &owner, "at", &p.position, end);
            late(&mut out, &owner, "scale", &p.scale, end);
            late(&mut out, &owner, "rotate", &p.rotation, end);
            late(&mut out, &owner, "depth", &p.depth, end);
            late(&mut out, &owner, "opacity", &p.opacity, end);
            for (i, h) in patch.handles.iter().enumerate() {
                let owner = format!("handle {i} of {owner}");
                late(&mut out, &owner, "at", &h.to, end);
                late(&mut out, &owner, "rotate", &h.rotation, end);
            }
            for follow in patch.follows.iter().filter(|f| f.is_intact(patch)) {
                short_track(&mut out, &owner, follow, self.last_frame_time());
            }
        }
        out
    }

    /// When the last frame is shown, seconds.
    fn last_frame_time(&self) -> f64 {
        super::frame_time(self.canvas.frame_count() - 1, self.canvas.fps)
    }
}

/// A followed track that starts after the first frame or ends before the last.
fn short_track(out: &mut Vec<String>, owner: &str, follow: &Follow, last: f64) {
    let times: Vec<f64> = follow.at.times().collect();
    let (Some(&first), Some(&end)) = (times.first(), times.last()) else {
        return;
    };
    let what = match follow.target {
        FollowTarget::Patch => "at".to_string(),
        FollowTarget::Handle(i) => format!("handle {i}"),
    };
    let name = follow.file_name();
    if first > 0.0 {
        out.push(format!(
            "{owner}: {what} follows {name} from t = {first} s only; earlier frames hold its first position"
        ));
    }
    if end < last - 1e-9 {
        out.push(format!(
            "{owner}: {what} follows {name} until t = {end} s; the frames after it (to t = {last} s) hold its last position"
        ));
    }
}

fn late<T: Interpolate>(
    out: &mut Vec<String>,
    owner: &str,
    name: &str,
    track: &Track<T>,
    end: f64,
) {
    let times: Vec<String> = track
        .times()
        .filter(|&t| t > end)
        .map(|t| t.to_string())
        .collect();
    if !times.is_empty() {
        out.push(format!(
            "{owner}: {name:?} key(s) at t = {} after the scene's end ({end} s); no frame shows them",
            times.join(", ")
        ));
    }
}
