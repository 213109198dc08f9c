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
                let last = self.last_frame_time();
                short_track(&mut out, &owner, follow, (last, self.canvas.fps));
            }
        }
        out
    }

    /// When the last frame is shown, seconds.
    fn last_frame_time(&self) -> f64 {
        super::frame_time(self.canvas.frame_count() - 1, self.canvas.fps)
    }
}

/// A followed track that starts after the first frame or ends before the last (`last`, the
/// last frame's time, at `fps`).
fn short_track(out: &mut Vec<String>, owner: &str, follow: &Follow, (last, fps): (f64, f64)) {
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
            "{owner}: {what} follows {name} from {} only; earlier frames hold its first position",
            moment(first, fps)
        ));
    }
    if end < last - 1e-9 {
        out.push(format!(
            "{owner}: {what} follows {name} until {}; the frames after it (to {}) hold its last position",
            moment(end, fps),
            moment(last, fps)
        ));
    }
}

/// A time as a warning names it: the frame shown then when it is a frame's time (numbered
/// from 1, as the frame files are), with the time rounded for reading; otherwise the time.
/// A track read from frame numbers has frame times, which written in full are 17 digits.
fn moment(t: f64, fps: f64) -> String {
    let frames = t * fps;
    let index = frames.round();
    if (frames - index).abs() > 1e-6 || !(0.0..1e15).contains(&index) {
        return format!("t = {} s", number_text(t));
    }
    let rounded = (t * 1e4).round() / 1e4;
    let sign = if rounded == t { "=" } else { "≈" };
    format!("frame {} (t {sign} {} s)", index as u64 + 1, number_text(rounded))
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
    fn frame_times_are_named_by_their_frame() {
        assert_eq!(moment(1.0 / 24.0, 24.0), "frame 2 (t ≈ 0.0417 s)");
        assert_eq!(moment(23.0 / 24.0, 24.0), "frame 24 (t ≈ 0.9583 s)");
        assert_eq!(moment(1.5, 24.0), "frame 37 (t = 1.5 s)");
        assert_eq!(moment(0.0, 30.0), "frame 1 (t = 0 s)");
        // Between frames, or past any frame number: the time itself.
        assert_eq!(moment(0.01, 24.0), "t = 0.01 s");
        assert_eq!(moment(1e300, 24.0), "t = 1e300 s");
    }

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
