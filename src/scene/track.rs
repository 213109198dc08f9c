//! Keyframe tracks: takes keys (time, value, easing) in any order — each is inserted at its
//! time, replacing a key already there — and gives the value at any time `t` by binary
//! search, pure and deterministic. Keys can be removed and moved by their exact time.
//!
//! **Which segment a key's easing governs:** the segment that *ends* at the key. The easing
//! passed with `key(1.5, value, "ease_in_out")` says how the value *arrives* at `value` by
//! t = 1.5, so every call is self-contained, and the first key's easing is unused (nothing
//! arrives at it). Inserting a key k between keys a and b splits the segment a → b in two:
//! a → k takes k's easing, k → b keeps b's easing (now over the shorter span). Before the
//! first key the track holds the first value; after the last key it holds the last value.

use glam::DVec2;

/// How a segment between two keys is traversed; `s` runs 0 → 1 over the segment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Easing {
    /// `s`.
    #[default]
    Linear,
    /// Stays at the previous value and jumps at the key's time.
    Hold,
    /// Cubic `s³`.
    EaseIn,
    /// Cubic `1 − (1 − s)³`.
    EaseOut,
    /// Cubic in, then cubic out: `4s³` below ½, `1 − (−2s + 2)³ / 2` above.
    EaseInOut,
    /// Smoothstep `3s² − 2s³`.
    Smooth,
}

impl Easing {
    /// Every easing, in the order the scene language documents them.
    pub const ALL: [Easing; 6] = [
        Easing::Linear,
        Easing::Hold,
        Easing::EaseIn,
        Easing::EaseOut,
        Easing::EaseInOut,
        Easing::Smooth,
    ];

    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Easing::Linear => "linear",
            Easing::Hold => "hold",
            Easing::EaseIn => "ease_in",
            Easing::EaseOut => "ease_out",
            Easing::EaseInOut => "ease_in_out",
            Easing::Smooth => "smooth",
        }
    }

    /// The easing named `name` (as scenes spell it).
    pub fn from_name(name: &str) -> Option<Easing> {
        Easing::ALL.into_iter().find(|e| e.name() == name)
    }

    /// Maps the segment fraction `s` ∈ [0, 1] to the interpolation weight.
    pub fn apply(self, s: f64) -> f64 {
        let s = s.clamp(0.0, 1.0);
        match self {
            Easing::Linear => s,
            Easing::Hold => {
                if s >= 1.0 {
                    1.0
                } else {
                    0.0
                }
            }
            Easing::EaseIn => s * s * s,
            Easing::EaseOut => 1.0 - (1.0 - s).powi(3),
            Easing::EaseInOut => {
                if s < 0.5 {
                    4.0 * s * s * s
                } else {
                    1.0 - (-2.0 * s + 2.0).powi(3) / 2.0
                }
            }
            Easing::Smooth => s * s * (3.0 - 2.0 * s),
        }
    }
}

/// Values a track can blend between keys.
pub trait Interpolate: Copy {
    /// `a` blended towards `b` by `weight` in [0, 1].
    fn interpolate(a: Self, b: Self, weight: f64) -> Self;
    /// Whether every component is finite.
    fn is_finite_value(&self) -> bool;
}

impl Interpolate for f64 {
    fn interpolate(a: f64, b: f64, weight: f64) -> f64 {
        a + (b - a) * weight
    }
    fn is_finite_value(&self) -> bool {
        self.is_finite()
    }
}

impl Interpolate for DVec2 {
    fn interpolate(a: DVec2, b: DVec2, weight: f64) -> DVec2 {
        a + (b - a) * weight
    }
    fn is_finite_value(&self) -> bool {
        self.is_finite()
    }
}

/// One keyframe: at `time` the track has `value`; `easing` governs the segment ending here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key<T> {
    /// Seconds from the start (≥ 0).
    pub time: f64,
    /// The value at `time`.
    pub value: T,
    /// How the segment ending at this key is interpolated.
    pub easing: Easing,
}

/// Why a key was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KeyError {
    /// The time is NaN or infinite.
    #[error("key time {0} is not a finite number")]
    NonFiniteTime(f64),
    /// The time is below zero.
    #[error("key time {0} is negative")]
    NegativeTime(f64),
    /// The value has a NaN or infinite component.
    #[error("key value is not finite")]
    NonFiniteValue,
    /// A key that must come after the track's last one does not.
    #[error("key at t = {time} is out of order: the previous key is at t = {previous}")]
    OutOfOrder {
        /// The key's time.
        time: f64,
        /// The time of the key before it.
        previous: f64,
    },
}

/// Keys in strictly increasing time. Empty tracks have no value (the caller's default).
#[derive(Clone, Debug, PartialEq)]
pub struct Track<T> {
    keys: Vec<Key<T>>,
}

impl<T> Default for Track<T> {
    fn default() -> Self {
        Track { keys: Vec::new() }
    }
}

/// A key time must be finite and ≥ 0.
fn check_time(time: f64) -> Result<(), KeyError> {
    if !time.is_finite() {
        return Err(KeyError::NonFiniteTime(time));
    }
    if time < 0.0 {
        return Err(KeyError::NegativeTime(time));
    }
    Ok(())
}

impl<T: Interpolate> Track<T> {
    /// An empty track (the property keeps its default).
    pub fn new() -> Self {
        Track::default()
    }

    /// A track holding `value` from t = 0 on.
    pub fn constant(value: T) -> Self {
        Track {
            keys: vec![Key {
                time: 0.0,
                value,
                easing: Easing::Linear,
            }],
        }
    }

    /// The keys, in time order.
    pub fn keys(&self) -> &[Key<T>] {
        &self.keys
    }

    /// Whether the track has no key.
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    /// Puts a key at `time`: inserted in time order, or replacing (value and easing) the key
    /// already at exactly that time. Refuses negative or non-finite times and values.
    pub fn push(&mut self, time: f64, value: T, easing: Easing) -> Result<(), KeyError> {
        check_time(time)?;
        if !value.is_finite_value() {
            return Err(KeyError::NonFiniteValue);
        }
        let key = Key {
            time: time + 0.0,
            value,
            easing,
        };
        match self.find(time) {
            Ok(index) => self.keys[index] = key,
            Err(index) => self.keys.insert(index, key),
        }
        Ok(())
    }

    /// The index of the key at exactly `time` (`Ok`), or where one would be inserted (`Err`).
    fn find(&self, time: f64) -> Result<usize, usize> {
        // Adding 0 turns −0 into +0, so the two zeros name one time.
        let time = time + 0.0;
        self.keys.binary_search_by(|k| k.time.total_cmp(&time))
    }

    /// Whether a key sits at exactly `time`.
    pub fn has_key_at(&self, time: f64) -> bool {
        self.find(time).is_ok()
    }

    /// Removes and gives the key at exactly `time`, if there is one.
    pub fn remove(&mut self, time: f64) -> Option<Key<T>> {
        self.find(time).ok().map(|index| self.keys.remove(index))
    }

    /// Moves the key at exactly `from` to `to` (value and easing kept), replacing a key at
    /// `to`. Gives `false` (and changes nothing) when no key is at `from` or `to` is not a
    /// valid time.
    pub fn move_key(&mut self, from: f64, to: f64) -> bool {
        if check_time(to).is_err() {
            return false;
        }
        let Some(key) = self.remove(from) else {
            return false;
        };
        // invariant: `to` was checked and the value came from this (valid) track.
        self.push(to, key.value, key.easing)
            .expect("a checked time and a stored value are accepted");
        true
    }

    /// The key times in increasing order.
    pub fn times(&self) -> impl Iterator<Item = f64> + '_ {
        self.keys.iter().map(|k| k.time)
    }

    /// The value at time `t`, or `None` for an empty track.
    pub fn value_at(&self, t: f64) -> Option<T> {
        let first = self.keys.first()?;
        let last = self.keys.last().expect("non-empty track"); // invariant: a non-empty track has a last key.
        if t <= first.time {
            return Some(first.value);
        }
        if t >= last.time {
            return Some(last.value);
        }
        // First key strictly after t; it exists and is not the first key (t > first.time).
        let end = self.keys.partition_point(|k| k.time <= t);
        let (a, b) = (&self.keys[end - 1], &self.keys[end]);
        let s = (t - a.time) / (b.time - a.time);
        Some(T::interpolate(a.value, b.value, b.easing.apply(s)))
    }

    /// Keys are finite, non-negative and strictly increasing.
    pub fn sanity_check(&self) -> Result<(), KeyError> {
        let mut previous: Option<f64> = None;
        for key in &self.keys {
            if !key.time.is_finite() {
                return Err(KeyError::NonFiniteTime(key.time));
            }
            if key.time < 0.0 {
                return Err(KeyError::NegativeTime(key.time));
            }
            if !key.value.is_finite_value() {
                return Err(KeyError::NonFiniteValue);
            }
            if let Some(p) = previous {
                if key.time <= p {
                    return Err(KeyError::OutOfOrder {
                        time: key.time,
                        previous: p,
                    });
                }
            }
            previous = Some(key.time);
        }
        Ok(())
    }
}
