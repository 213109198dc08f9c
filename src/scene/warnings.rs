//! Things a scene allows but a user probably did not mean: takes a [`Scene`] and gives
//! warnings as sentences (today: keys after the scene's end, which no frame shows).

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
        }
        out
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
