//! Thresholds and per-scene golden settings: plain data, filled from defaults, a scene's
//! `golden(#{ … })` call and command-line flags, in that order of precedence.

/// When a frame warns or fails, as OpenImageIO's `idiff` decides it. Errors are in 8-bit
/// units (see the module documentation); percentages are of all pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thresholds {
    /// A pixel fails when any channel differs by more than this.
    pub fail: f64,
    /// The frame fails when more than this percentage of pixels fail.
    pub fail_percent: f64,
    /// The frame fails when any channel of any pixel differs by more than this.
    pub hard_fail: f64,
    /// A pixel warns when any channel differs by more than this.
    pub warn: f64,
    /// The frame warns when more than this percentage of pixels warn.
    pub warn_percent: f64,
    /// The frame fails when its SSIM is below this.
    pub min_ssim: Option<f64>,
}

impl Default for Thresholds {
    /// Byte-exact frames and one-level differences (a platform's float rounding) pass; any
    /// difference warns.
    fn default() -> Self {
        Thresholds {
            fail: 1.0,
            fail_percent: 0.0,
            hard_fail: f64::INFINITY,
            warn: 0.0,
            warn_percent: 0.0,
            min_ssim: None,
        }
    }
}

/// A scene's own choices from `golden(#{ … })`: each `None` keeps the default (or the
/// command line's value, which wins).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GoldenSettings {
    /// Frame numbers (from 1, as `lapclone render` numbers them) to check.
    pub frames: Option<Vec<u64>>,
    /// [`Thresholds::fail`].
    pub fail: Option<f64>,
    /// [`Thresholds::fail_percent`].
    pub fail_percent: Option<f64>,
    /// [`Thresholds::hard_fail`].
    pub hard_fail: Option<f64>,
    /// [`Thresholds::warn`].
    pub warn: Option<f64>,
    /// [`Thresholds::warn_percent`].
    pub warn_percent: Option<f64>,
    /// [`Thresholds::min_ssim`].
    pub min_ssim: Option<f64>,
}

impl GoldenSettings {
    /// The keys `golden(#{ … })` accepts.
    pub const KEYS: [&'static str; 7] = [
        "frames",
        "fail",
        "fail_percent",
        "hard_fail",
        "warn",
        "warn_percent",
        "min_ssim",
    ];

    /// The `golden(#{ … })` call that gives these settings back (floats in Rust's shortest
    /// round-trip form, so a written scene reads back equal).
    pub fn to_rhai(&self) -> String {
        let mut keys = Vec::new();
        if let Some(frames) = &self.frames {
            let list: Vec<String> = frames.iter().map(u64::to_string).collect();
            keys.push(format!("frames: [{}]", list.join(", ")));
        }
        let values = [
            ("fail", self.fail),
            ("fail_percent", self.fail_percent),
            ("hard_fail", self.hard_fail),
            ("warn", self.warn),
            ("warn_percent", self.warn_percent),
            ("min_ssim", self.min_ssim),
        ];
        for (key, value) in values {
            if let Some(v) = value {
                keys.push(format!("{key}: {v:?}"));
            }
        }
        format!("golden(#{{ {} }});\n", keys.join(", "))
    }

    /// `base` with every value this scene sets replaced.
    pub fn apply(&self, base: Thresholds) -> Thresholds {
        Thresholds {
            fail: self.fail.unwrap_or(base.fail),
            fail_percent: self.fail_percent.unwrap_or(base.fail_percent),
            hard_fail: self.hard_fail.unwrap_or(base.hard_fail),
            warn: self.warn.unwrap_or(base.warn),
            warn_percent: self.warn_percent.unwrap_or(base.warn_percent),
            min_ssim: self.min_ssim.or(base.min_ssim),
        }
    }
}
