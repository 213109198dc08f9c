//! Things a scene allows but a user probably did not mean: takes a [`Scene`] and gives
//! warnings as sentences (today: keys after the scene's end, which no frame shows).

use crate::util::number_text;
use super::types::{Follow, FollowTarget};
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
    let (first_text, end_text) = (number_text(first), number_text(end));
    if first > 0.0 {
        out.push(format!(
            "{owner}: {what} follows {name} from t = {first_text} s only; earlier frames hold its first position"
        ));
    }
    if end < last - 1e-9 {
        out.push(format!(
            "{owner}: {what} follows {name} until t = {end_text} s; the frames after it (to t = {} s) hold its last position",
            number_text(last)
        ));
    }
}

/// How many key times a warning lists before it only counts them.
const SHOWN_TIMES: usize = 5;

fn late<T: Interpolate>(
    out: &mut Vec<String>,
    owner: &str,
    name: &str,
    track: &Track<T>,
    end: f64,
) {
    let keys = track.keys();
    // Keys are in time order: the late ones are a tail.
    let late = &keys[keys.partition_point(|k| k.time <= end)..];
    let Some(last) = late.last() else { return };
    let shown: Vec<String> = late
        .iter()
        .take(SHOWN_TIMES)
        .map(|k| number_text(k.time))
        .collect();
    let times = if late.len() > SHOWN_TIMES {
        format!(
            "{} keys at t = {}, … {}",
            late.len(),
            shown.join(", "),
            number_text(last.time)
        )
    } else {
        format!("key(s) at t = {}", shown.join(", "))
    };
    out.push(format!(
        "{owner}: {name:?} {times} after the scene's end ({} s); no frame shows them",
        number_text(end)
    ));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Easing;

    #[test]
    fn many_late_keys_are_counted_not_listed() {
        let mut track = Track::<f64>::new();
        for i in 0..1000 {
            track.push(f64::from(i), 0.0, Easing::Linear).unwrap();
        }
        let mut out = Vec::new();
        late(&mut out, "patch \"p\"", "scale", &track, 10.5);
        assert_eq!(
            out,
            ["patch \"p\": \"scale\" 989 keys at t = 11, 12, 13, 14, 15, … 999 after the scene's end (10.5 s); no frame shows them"]
        );
        out.clear();
        late(&mut out, "patch \"p\"", "scale", &track, 996.0);
        assert_eq!(
            out,
            ["patch \"p\": \"scale\" key(s) at t = 997, 998, 999 after the scene's end (996 s); no frame shows them"]
        );
    }

    /// Times far from a second are written short, not as hundreds of digits.
    #[test]
    fn extreme_key_times_are_written_short() {
        let mut track = Track::<f64>::new();
        track.push(1e-320, 0.0, Easing::Linear).unwrap();
        track.push(1e308, 0.0, Easing::Linear).unwrap();
        let mut out = Vec::new();
        late(&mut out, "patch \"p\"", "scale", &track, 0.0);
        assert_eq!(
            out,
            ["patch \"p\": \"scale\" key(s) at t = 1e-320, 1e308 after the scene's end (0 s); no frame shows them"]
        );
    }
}
