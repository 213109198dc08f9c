//! The point tracker: takes the first frame, the points to follow and [`TrackOptions`],
//! then each following frame, and gives per point per frame a sub-pixel position and a
//! confidence. Pyramidal Lucas–Kanade carries each point from the last frame it was sure of
//! (coarse levels catch fast motion); a second alignment against the first frame's template
//! pulls the estimate back onto the original feature, so errors do not add up while the
//! feature still looks as it did. A point whose match falls below [`LOST_BELOW`] (covered,
//! gone off the frame, or in a featureless region) is reported lost at its last sure
//! position, and is searched for again from there on the next frames.

use glam::DVec2;

use super::lucas_kanade::Template;
use super::pyramid::{window_area, FramePyramid, Pyramid};
use super::TrackError;
use crate::pixels::FloatImage;

/// A match whose normalised cross-correlation is below this is not trusted: the point is
/// reported lost for that frame.
pub const LOST_BELOW: f64 = 0.6;
/// A point lost in the last frame is found again only when it matches at least this well
/// (hysteresis: a near-miss beside an occluder must not count as the point).
pub const FOUND_ABOVE: f64 = 0.92;
/// Tracked back into the last frame, a sure position must land within this many pixels of
/// where the point was there (forward–backward check).
const BACK_WITHIN: f64 = 1.0;
/// The first frame's template replaces the last frame's result when it lands within this
/// many pixels of it (farther, it has locked on to something else).
const ANCHOR_REACH: f64 = 1.5;
/// A template whose grey values vary less than this (standard deviation, of 1) has nothing
/// to lock on to.
const FLAT_BELOW: f64 = 0.01;
/// How far (pixels) the point may stray from where its motion so far predicts for the
/// small search around the prediction to be tried first.
const NEAR: f64 = 8.0;
/// The small search's match is taken only when it correlates at least this well with the
/// last frame's look; anything less searches the whole range.
const NEAR_ABOVE: f64 = 0.9;
/// A step shorter than this (pixels) ends the iterations that place a point.
const PRECISE: f64 = 1e-3;
/// The same at a coarse pyramid level (its pixels): the level below refines the estimate
/// anyway, so finer steps there would be wasted.
const COARSE: f64 = 0.02;
/// The same for the forward–backward check, which only asks whether the point comes back
/// within [`BACK_WITHIN`].
const CHECKED: f64 = 0.01;
/// Largest `size` and `search`, in pixels.
pub const MAX_SIZE: u32 = 255;
/// Largest search radius, in pixels.
pub const MAX_SEARCH: u32 = 1024;

/// How points are followed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TrackOptions {
    /// Side of the square matched around each point, in pixels (odd sizes are exact).
    pub size: u32,
    /// How far a point may move between frames, in pixels.
    pub search: u32,
}

impl Default for TrackOptions {
    fn default() -> Self {
        TrackOptions {
            size: 31,
            search: 48,
        }
    }
}

/// Why a point was not found in a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LostReason {
    /// The square around the point reaches beyond the frame.
    LeftFrame,
    /// The region has no texture to follow.
    Featureless,
    /// Nothing in reach looks like the point (covered, or changed too much).
    NoMatch,
}

impl LostReason {
    /// A few words for warnings.
    pub fn describe(self) -> &'static str {
        match self {
            LostReason::LeftFrame => "left the frame",
            LostReason::Featureless => "featureless region",
            LostReason::NoMatch => "no match (covered or changed)",
        }
    }
}

/// One point in one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Where the point is (its last sure position when lost), pixel coordinates.
    pub at: DVec2,
    /// How well it matched its first-frame look, 0 (no idea) to 1 (exactly as then); below
    /// [`LOST_BELOW`] exactly when the point is lost.
    pub confidence: f64,
    /// Set when the point was not found in this frame.
    pub lost: Option<LostReason>,
}

struct PointState {
    first: Vec<Template>,
    sure: Vec<Template>,
    sure_at: DVec2,
    velocity: DVec2,
    /// The feature's turn and scale against the first frame, as `[s cos θ, s sin θ]`.
    shape: [f64; 2],
    /// Whether the point was lost in the last frame.
    was_lost: bool,
    /// The last frame's pyramid around the point, when it was sure there.
    last: Option<Pyramid>,
}

/// Follows points from frame to frame; frames must all have the first frame's size.
pub struct PointTracker {
    half: i32,
    search: f64,
    levels: usize,
    /// Levels of the small search around the prediction; `None` when the whole range is
    /// no larger.
    near_levels: Option<usize>,
    size: (u32, u32),
    points: Vec<PointState>,
}

impl PointTracker {
    /// Starts on `first` at `points`; gives the tracker and the first frame's estimates.
    pub fn start(
        first: &FloatImage,
        points: &[DVec2],
        options: TrackOptions,
    ) -> Result<(PointTracker, Vec<Estimate>), TrackError> {
        check_options(options)?;
        let half = (options.size / 2) as i32;
        let search = f64::from(options.search);
        let levels = levels_for(half, search);
        let near_levels = (search > NEAR).then(|| levels_for(half, NEAR));
        let mut tracker = PointTracker {
            half,
            search,
            levels,
            near_levels,
            size: (first.width(), first.height()),
            points: Vec::with_capacity(points.len()),
        };
        let mut estimates = Vec::with_capacity(points.len());
        let mut shared = None;
        for (index, &at) in points.iter().enumerate() {
            let inside = at.x >= 0.0
                && at.y >= 0.0
                && at.x <= f64::from(first.width())
                && at.y <= f64::from(first.height());
            if !at.is_finite() || !inside {
                return Err(TrackError::PointOutside {
                    point: index + 1,
                    x: at.x,
                    y: at.y,
                    width: first.width(),
                    height: first.height(),
                });
            }
            let pyramid = tracker.full_range(first, at, points.len(), &mut shared);
            let templates = tracker.templates(&pyramid, at);
            let mut anchors = templates.clone();
            anchors[0].prepare_similarity();
            let lost = tracker.lost_reason(&templates[0], at, 1.0, LOST_BELOW);
            estimates.push(Estimate {
                at,
                confidence: if lost.is_some() { 0.0 } else { 1.0 },
                lost,
            });
            tracker.points.push(PointState {
                first: anchors,
                sure: templates,
                sure_at: at,
                velocity: DVec2::ZERO,
                shape: [1.0, 0.0],
                was_lost: lost.is_some(),
                last: Some(pyramid),
            });
        }
        Ok((tracker, estimates))
    }

    /// The estimates in the next frame.
    pub fn next(&mut self, frame: &FloatImage) -> Result<Vec<Estimate>, TrackError> {
        if (frame.width(), frame.height()) != self.size {
            return Err(TrackError::FrameSize {
                width: frame.width(),
                height: frame.height(),
                expected_width: self.size.0,
                expected_height: self.size.1,
            });
        }
        let mut out = Vec::with_capacity(self.points.len());
        let mut shared = None;
        for index in 0..self.points.len() {
            out.push(self.follow(index, frame, &mut shared));
        }
        Ok(out)
    }

    /// The pyramid of `frame` a point at `centre` is searched for in over the whole range:
    /// its own window, or a window of the frame's `shared` pyramid (built on first use) when
    /// `points` such windows would hold more than that pyramid. Either gives the same values.
    fn full_range(
        &self,
        frame: &FloatImage,
        centre: DVec2,
        points: usize,
        shared: &mut Option<FramePyramid>,
    ) -> Pyramid {
        let (reach, levels) = (self.reach(self.search, self.levels), self.levels);
        let windows = window_area(self.size, centre, reach, levels).saturating_mul(points as u64);
        if windows <= FramePyramid::area(self.size, levels) {
            return Pyramid::around(frame, centre, reach, levels);
        }
        shared
            .get_or_insert_with(|| FramePyramid::new(frame, levels))
            .around(centre, reach)
    }

    fn follow(
        &mut self,
        index: usize,
        frame: &FloatImage,
        shared: &mut Option<FramePyramid>,
    ) -> Estimate {
        let state = &self.points[index];
        let predicted = state.sure_at + state.velocity;
        let (pyramid, carried) = self.carry(state, frame, predicted, shared);
        // Re-anchor on the first frame's look, turned and scaled as the feature now is:
        // from the carried estimate when there is one, from the whole search range when
        // the point was lost or the last frame's look is gone.
        let first = &state.first[0];
        let anchor = |p| first.align_similarity(&pyramid.levels[0], p, state.shape, PRECISE);
        let anchored = match carried {
            Some(p) => anchor(p),
            None => self
                .pyramidal(&state.first, &pyramid, predicted, self.search, PRECISE)
                .and_then(anchor),
        };
        let (mut at, mut shape) = (carried.unwrap_or(predicted), state.shape);
        if let Some((p, m)) = anchored.filter(|(p, _)| p.is_finite()) {
            if carried.is_none_or(|c| c.distance(p) <= ANCHOR_REACH) {
                (at, shape) = (p, m);
            }
        }
        // Confidence is always against the first frame's look, so a drifted template
        // that matches itself cannot vouch for a wrong position.
        let score = first.correlation_warped(&pyramid.levels[0], at, shape);
        let threshold = if state.was_lost { FOUND_ABOVE } else { LOST_BELOW };
        let mut lost = self.lost_reason(&state.first[0], at, score, threshold);
        let templates = self.templates(&pyramid, at);
        if lost.is_none() && !self.comes_back(&templates, index, at) {
            lost = Some(LostReason::NoMatch);
        }
        let state = &mut self.points[index];
        state.was_lost = lost.is_some();
        if lost.is_some() {
            state.velocity = DVec2::ZERO;
            state.last = None;
            // Scaled below the threshold, so a lost point never reads as a sure one.
            return Estimate {
                at: state.sure_at,
                confidence: score.clamp(0.0, 1.0) * LOST_BELOW * 0.99,
                lost,
            };
        }
        state.shape = shape;
        state.velocity = at - state.sure_at;
        state.sure_at = at;
        state.sure = templates;
        state.last = Some(pyramid);
        Estimate {
            at,
            confidence: score.clamp(0.0, 1.0),
            lost: None,
        }
    }

    /// The pyramid of `frame` the point is looked for in, and where the last frame's look
    /// carries it (`None` when it does not match there). Most frames the point is close to
    /// where its motion predicts and still looks as it did: a small pyramid around the
    /// prediction finds it at a fraction of the cost. Anything else searches the whole range,
    /// with the last frame's look when it was cut at every level, and otherwise leaves the
    /// search to the first frame's look.
    fn carry(
        &self,
        state: &PointState,
        frame: &FloatImage,
        predicted: DVec2,
        shared: &mut Option<FramePyramid>,
    ) -> (Pyramid, Option<DVec2>) {
        if let Some(levels) = self.near_levels {
            let near = Pyramid::around(frame, predicted, self.reach(NEAR, levels), levels);
            let found = self
                .pyramidal(&state.sure, &near, predicted, NEAR, PRECISE)
                .filter(|&p| state.sure[0].correlation(&near.levels[0], p) >= NEAR_ABOVE);
            if found.is_some() {
                return (near, found);
            }
        }
        let pyramid = self.full_range(frame, predicted, self.points.len(), shared);
        let carried = (state.sure.len() == self.levels)
            .then(|| self.pyramidal(&state.sure, &pyramid, predicted, self.search, PRECISE))
            .flatten()
            .filter(|&p| state.sure[0].correlation(&pyramid.levels[0], p) >= LOST_BELOW);
        (pyramid, carried)
    }

    /// Whether `templates` (cut at `at`), tracked back into the last frame, land where the
    /// point was there; true when the last frame was not sure (nothing to go back to). The
    /// way back starts off the last position by as much as the way forward missed its
    /// prediction (as far as the last frame's pyramid reaches), so it has as far to go.
    fn comes_back(&self, templates: &[Template], index: usize, at: DVec2) -> bool {
        let state = &self.points[index];
        let Some(last) = &state.last else {
            return true;
        };
        let levels = templates.len().min(last.levels.len());
        let motion = if levels == self.levels {
            self.search
        } else {
            NEAR
        };
        let missed = at - (state.sure_at + state.velocity);
        let start = state.sure_at + missed.clamp_length_max(motion);
        self.pyramidal(&templates[..levels], last, start, motion, CHECKED)
            .is_some_and(|back| back.distance(state.sure_at) <= BACK_WITHIN)
    }

    /// Pyramidal alignment of `templates` (cut around one point, at every level) starting
    /// with their centre at `start`, over the levels both have, to steps shorter than `done`
    /// pixels at full size; where their centre lands, or `None` when it strays much beyond
    /// `motion` pixels from `start` (the pyramid's window ends there).
    fn pyramidal(
        &self,
        templates: &[Template],
        pyramid: &Pyramid,
        start: DVec2,
        motion: f64,
        done: f64,
    ) -> Option<DVec2> {
        let levels = templates.len().min(pyramid.levels.len());
        let mut at = start;
        for level in (0..levels).rev() {
            let scale = f64::from(1u32 << level);
            let guess = at / scale;
            let done = if level == 0 { done } else { COARSE };
            let found = templates[level].align(&pyramid.levels[level], guess, done)?;
            at = found * scale;
            if at.distance(start) > motion * 1.5 + 2.0 {
                return None;
            }
        }
        Some(at)
    }

    /// Templates at every level of `pyramid` around `at`.
    fn templates(&self, pyramid: &Pyramid, at: DVec2) -> Vec<Template> {
        (0..pyramid.levels.len())
            .map(|level| {
                let scale = f64::from(1u32 << level);
                Template::cut(&pyramid.levels[level], at / scale, self.half)
            })
            .collect()
    }

    fn lost_reason(
        &self,
        first: &Template,
        at: DVec2,
        score: f64,
        threshold: f64,
    ) -> Option<LostReason> {
        let half = f64::from(self.half);
        let (w, h) = (f64::from(self.size.0), f64::from(self.size.1));
        if at.x - half < 0.0 || at.y - half < 0.0 || at.x + half > w || at.y + half > h {
            Some(LostReason::LeftFrame)
        } else if first.contrast < FLAT_BELOW {
            Some(LostReason::Featureless)
        } else if score < threshold {
            Some(LostReason::NoMatch)
        } else {
            None
        }
    }

    /// Half-side of the window a frame's pyramid must cover: the motion allowed, plus the
    /// template at the coarsest level, plus the gradients' border.
    fn reach(&self, motion: f64, levels: usize) -> f64 {
        let coarse = f64::from(1u32 << (levels - 1));
        motion + (f64::from(self.half) + 2.0) * coarse
    }
}

/// Levels so the motion at the coarsest level is within half the template.
fn levels_for(half: i32, search: f64) -> usize {
    let mut levels = 1;
    while search / f64::from(1u32 << (levels - 1)) > f64::from(half.max(1)) / 2.0 && levels < 6 {
        levels += 1;
    }
    levels
}

fn check_options(options: TrackOptions) -> Result<(), TrackError> {
    options.check()
}

impl TrackOptions {
    /// Whether these settings are in range: `size` 5 to 255 px, `search` 1 to 1024 px.
    pub fn check(&self) -> Result<(), TrackError> {
        let options = self;
        if !(5..=MAX_SIZE).contains(&options.size) {
        return Err(TrackError::Options(format!(
            "size {} must be between 5 and {MAX_SIZE} pixels",
            options.size
        )));
    }
    if !(1..=MAX_SEARCH).contains(&options.search) {
        return Err(TrackError::Options(format!(
            "search {} must be between 1 and {MAX_SEARCH} pixels",
            options.search
        )));
        }
        Ok(())
    }
}

/// Rotation (degrees, continuing past ±180) and scale of the pair `(a, b)` relative to the
/// pair `(a0, b0)`; `previous` is the last rotation given, so the angle never jumps by 360.
pub fn pair_motion(a0: DVec2, b0: DVec2, a: DVec2, b: DVec2, previous: f64) -> (f64, f64) {
    let (v0, v) = (b0 - a0, b - a);
    let mut degrees = (v.y.atan2(v.x) - v0.y.atan2(v0.x)).to_degrees();
    degrees += 360.0 * ((previous - degrees) / 360.0).round();
    let scale = if v0.length() > 0.0 {
        v.length() / v0.length()
    } else {
        1.0
    };
    (degrees, scale)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixels::PixelFormat;

    /// A smooth texture moved by `shift`.
    fn frame(shift: DVec2) -> FloatImage {
        FloatImage::from_fn(160, 120, PixelFormat::RGBA8, |i, j| {
            let (x, y) = (f64::from(i) - shift.x, f64::from(j) - shift.y);
            let v = 0.5 + 0.25 * (x * 0.21).sin() * (y * 0.17).cos() + 0.2 * (x * 0.05 + y * 0.09).sin();
            let v = v as f32;
            [v, v * 0.8, 1.0 - v, 1.0]
        })
        .unwrap()
    }

    /// Points followed together, whose full-range windows share each frame's pyramid, land
    /// where each lands followed alone (its own windows), bit for bit, and on the motion.
    #[test]
    fn points_followed_together_land_where_each_lands_alone() {
        let points = [DVec2::new(60.0, 50.0), DVec2::new(100.0, 70.0), DVec2::new(80.0, 40.0)];
        let options = TrackOptions { size: 63, search: 200 };
        let step = DVec2::new(1.3, 0.7);
        let follow = |points: &[DVec2]| {
            let (mut tracker, _) = PointTracker::start(&frame(DVec2::ZERO), points, options).unwrap();
            (1..6).map(|k| tracker.next(&frame(step * f64::from(k))).unwrap()).collect::<Vec<_>>()
        };
        let together = follow(&points);
        for (index, &point) in points.iter().enumerate() {
            let alone = follow(&[point]);
            for (k, (all, one)) in together.iter().zip(&alone).enumerate() {
                assert_eq!(all[index], one[0], "point {index}, frame {k}");
                let expected = point + step * (k + 1) as f64;
                assert!(one[0].lost.is_none() && one[0].at.distance(expected) < 0.05, "{:?}", one[0]);
            }
        }
    }
}
