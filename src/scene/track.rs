//! Keyframe tracks: takes keys (time, value, easing) in strictly increasing time order and
//! gives the value at any time `t`, pure and deterministic.
//!
//! **Which segment a key's easing governs:** the segment that *ends* at the key. The easing
//! passed with `key(1.5, value, "ease_in_out")` says how the value *arrives* at `value` by
//! t = 1.5, so every call is self-contained, appending a key never changes a segment that was
//! already defined, and the first key's easing is unused (nothing arrives at it). Before the
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
    fn interpolate(a: Self, b: Self, weight: f64) -> Self;
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
    /// Keys must be added in increasing time.
    #[error("key at t = {time} is out of order: the previous key is at t = {previous} (keys must be added in increasing time)")]
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

    /// Appends a key after the last one; refuses negative, non-finite or out-of-order times.
    pub fn push(&mut self, time: f64, value: T, easing: Easing) -> Result<(), KeyError> {
        if !time.is_finite() {
            return Err(KeyError::NonFiniteTime(time));
        }
        if time < 0.0 {
            return Err(KeyError::NegativeTime(time));
        }
        if !value.is_finite_value() {
            return Err(KeyError::NonFiniteValue);
        }
        if let Some(last) = self.keys.last() {
            if time <= last.time {
                return Err(KeyError::OutOfOrder {
                    time,
                    previous: last.time,
                });
            }
        }
        self.keys.push(Key {
            time,
            value,
            easing,
        });
        Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn easing_endpoints() {
        for e in Easing::ALL {
            assert_eq!(e.apply(1.0), 1.0, "{e:?}");
            assert_eq!(e.apply(0.0), 0.0, "{e:?}");
            assert_eq!(Easing::from_name(e.name()), Some(e));
        }
    }

    #[test]
    fn out_of_order_is_refused() {
        let mut t = Track::<f64>::new();
        t.push(1.0, 0.0, Easing::Linear).unwrap();
        assert!(matches!(
            t.push(0.5, 1.0, Easing::Linear),
            Err(KeyError::OutOfOrder { .. })
        ));
        assert!(matches!(
            t.push(1.0, 1.0, Easing::Linear),
            Err(KeyError::OutOfOrder { .. })
        ));
        assert_eq!(t.keys().len(), 1);
    }
}
