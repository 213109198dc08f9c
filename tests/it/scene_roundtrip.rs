//! `Scene::to_rhai` round trip: parsing the written scene gives back an equal scene, over
//! random scenes (fixed seed) with every feature, awkward floats and awkward names; and over
//! random edit sessions (inserted, replaced, removed and moved keys, removed handles, pins
//! and patches, renames, reordering, opacity) run as REPL entries, where both forms `:save`
//! writes — the text plus the entries, and every key written out — rebuild the same scene.

use std::path::PathBuf;

use glam::DVec2;
use lapclone::scene::{
    Background, BoundaryData, BoundaryPlacement, Canvas, CloneMode, Easing, Handle, LaplacianKind,
    Patch, Pin, Placement, Polygon, Scene, Shape, Track,
};
use lapclone::script::{parse_scene, Limits, ScriptOptions};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn asset(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

fn awkward_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1e4..1e4f64,
        Just(0.1 + 0.2),
        Just(1e-300),
        Just(-0.0),
        // The largest a scene may place something at (`limits::MAX_POSITION`).
        Just(1e9),
        Just(-999_999_999.75),
        (-1000i32..1000).prop_map(f64::from),
    ]
}

fn point() -> impl Strategy<Value = DVec2> {
    (awkward_f64(), awkward_f64()).prop_map(|(x, y)| DVec2::new(x, y))
}

fn easing() -> impl Strategy<Value = Easing> {
    prop::sample::select(Easing::ALL.to_vec())
}

/// Keys at increasing times built from positive gaps.
fn track<T: lapclone::scene::Interpolate + std::fmt::Debug>(
    value: impl Strategy<Value = T>,
) -> impl Strategy<Value = Track<T>> {
    prop::collection::vec((0.001..3.0f64, value, easing()), 0..4).prop_map(|keys| {
        let mut track = Track::new();
        let mut t = 0.0;
        for (i, (gap, v, e)) in keys.into_iter().enumerate() {
            if i > 0 {
                t += gap;
            }
            track.push(t, v, e).unwrap();
        }
        track
    })
}

fn positive() -> impl Strategy<Value = f64> {
    prop_oneof![
        0.001..100.0f64,
        Just(1.0 / 3.0),
        (1i32..50).prop_map(f64::from)
    ]
}

fn polygon() -> impl Strategy<Value = Polygon> {
    (
        prop::collection::vec(point(), 3..6),
        prop::collection::vec(prop::collection::vec(point(), 3..5), 0..2),
    )
        .prop_map(|(outer, holes)| Polygon { outer, holes })
}

fn handle() -> impl Strategy<Value = Handle> {
    (
        point(),
        track(point()),
        positive(),
        prop::option::of(awkward_f64()),
        prop::option::of(point()),
        track(awkward_f64()),
    )
        .prop_map(|(from, to, radius, depth, pivot, rotation)| Handle {
            from,
            to,
            radius,
            depth,
            pivot,
            rotation,
        })
}

fn pin() -> impl Strategy<Value = Pin> {
    (point(), 0.0..5.0f64, prop::option::of(0.01..5.0f64)).prop_map(|(at, start, len)| Pin {
        at,
        start,
        end: len.map(|l| start + l),
    })
}

fn patch(index: usize) -> impl Strategy<Value = Patch> {
    let name = prop_oneof![
        Just("face".to_string()),
        // Quotes, a backslash and non-ASCII survive the round trip (control characters
        // are not allowed in names).
        Just("we\"ird \\ name ✓ ${x}".to_string()),
        "[a-z]{1,8}"
    ];
    let shape = prop_oneof![
        Just(Shape::Mask(asset("horse_mask.png"))),
        prop::collection::vec(polygon(), 1..3).prop_map(Shape::Polygons),
    ];
    (
        name,
        shape,
        prop::option::of(positive()),
        any::<bool>(),
        any::<bool>(),
        prop_oneof![Just(0.0), positive()],
        (any::<bool>(), any::<bool>()),
        (
            track(point()),
            track(positive()),
            track(awkward_f64()),
            track(awkward_f64()),
            track(0.0..=1.0f64),
        ),
        prop::collection::vec(handle(), 0..3),
        prop::collection::vec(pin(), 0..3),
    )
        .prop_map(
            move |(
                name,
                shape,
                density,
                cot,
                mono,
                feather,
                (vertex_data, cracks),
                tracks,
                handles,
                pins,
            )| Patch {
                name: format!("{name}{index}"),
                source: asset("astronaut.png"),
                footage: None,
                shape,
                density,
                laplacian: if cot {
                    LaplacianKind::Cotangent
                } else {
                    LaplacianKind::Combinatorial
                },
                mode: if mono {
                    CloneMode::Monochrome
                } else {
                    CloneMode::Normal
                },
                feather,
                boundary_data: if vertex_data {
                    BoundaryData::Vertex
                } else {
                    BoundaryData::HatAverage
                },
                boundary: if cracks {
                    BoundaryPlacement::Cracks
                } else {
                    BoundaryPlacement::OutsideCentres
                },
                placement: Placement {
                    position: tracks.0,
                    scale: tracks.1,
                    rotation: tracks.2,
                    depth: tracks.3,
                    opacity: tracks.4,
                },
                handles,
                pins,
                follows: Vec::new(),
            },
        )
}

fn scene() -> impl Strategy<Value = Scene> {
    let background = prop_oneof![
        Just(Background::Image(asset("coffee.png"))),
        prop::array::uniform4(0.0..=1.0f32).prop_map(Background::Colour),
    ];
    (
        1u32..5000,
        1u32..5000,
        positive(),
        positive(),
        background,
        prop::collection::vec(0usize..1, 0..3),
    )
        .prop_flat_map(|(width, height, fps, duration, background, n)| {
            let patches: Vec<_> = (0..n.len()).map(patch).collect();
            (
                Just(Canvas {
                    width,
                    height,
                    fps,
                    duration,
                    background,
                }),
                patches,
            )
        })
        .prop_map(|(canvas, patches)| Scene {
            canvas,
            patches,
            golden: None,
        })
}

proptest! {
    #![proptest_config(Config {
        rng_seed: RngSeed::Fixed(0x5CE4E),
        cases: 96,
        ..Config::default()
    })]

    #[test]
    fn to_rhai_round_trips(original in scene()) {
        prop_assert!(original.sanity_check().is_ok());
        let text = original.to_rhai();
        let parsed = read_back(&text).map_err(TestCaseError::fail)?;
        prop_assert_eq!(&parsed, &original, "{}", text);
        // Writing again is a fixed point.
        prop_assert_eq!(parsed.to_rhai(), text);
    }
}

/// The scene `text` (as `to_rhai` wrote it) reads back as; the error shows the text.
fn read_back(text: &str) -> Result<Scene, String> {
    parse_scene(text, &PathBuf::from("saved.rhai"), &temp_options())
        .map(|parsed| parsed.scene)
        .map_err(|e| format!("{e}\n---\n{text}"))
}

/// Patches named as Rhai keywords or reserved words (`is` among them) get variables the
/// scene language accepts, and the scene reads back.
#[test]
fn patches_named_as_keywords_round_trip() {
    let names = ["is", "let", "print", "fn", "this", "goto", "type", "global"];
    let patches = names
        .iter()
        .map(|name| {
            Patch::new(
                *name,
                asset("astronaut.png"),
                Shape::Mask(asset("horse_mask.png")),
            )
        })
        .collect();
    let canvas = Canvas {
        width: 64,
        height: 48,
        fps: 24.0,
        duration: 1.0,
        background: Background::Colour([0.0, 0.0, 0.0, 1.0]),
    };
    let original = Scene::new(canvas, patches);
    let text = original.to_rhai();
    assert_eq!(read_back(&text).unwrap(), original, "{text}");
}

/// One edit as a REPL user would type it; indices pick among what exists when it runs.
#[derive(Clone, Debug)]
enum Edit {
    /// A key at a new time or (`existing`) at the time of an existing key: a replacement.
    Key {
        patch: usize,
        track: usize,
        t: f64,
        existing: Option<usize>,
        value: f64,
        easing: Easing,
    },
    Opacity {
        patch: usize,
        t: f64,
        value: f64,
    },
    RemoveKey {
        patch: usize,
        key: usize,
        one_track: Option<usize>,
    },
    MoveKey {
        patch: usize,
        key: usize,
        to: f64,
    },
    RemoveHandle {
        patch: usize,
        handle: usize,
        by_value: bool,
    },
    RemovePin {
        patch: usize,
        pin: usize,
    },
    Rename {
        patch: usize,
        name: String,
    },
    Reorder {
        patch: usize,
        front: bool,
    },
    RemovePatch {
        patch: usize,
    },
}

fn edit() -> impl Strategy<Value = Edit> {
    let i = || 0usize..8;
    let t = || prop_oneof![0.0..4.0f64, (0u8..8).prop_map(|k| f64::from(k) * 0.5)];
    prop_oneof![
        4 => (i(), 0usize..4, t(), prop::option::of(i()), -50.0..50.0f64, easing()).prop_map(
            |(patch, track, t, existing, value, easing)| Edit::Key { patch, track, t, existing, value, easing }
        ),
        2 => (i(), t(), 0.0..=1.0f64).prop_map(|(patch, t, value)| Edit::Opacity { patch, t, value }),
        2 => (i(), i(), prop::option::of(0usize..5)).prop_map(|(patch, key, one_track)| Edit::RemoveKey { patch, key, one_track }),
        1 => (i(), i(), t()).prop_map(|(patch, key, to)| Edit::MoveKey { patch, key, to }),
        1 => (i(), i(), any::<bool>()).prop_map(|(patch, handle, by_value)| Edit::RemoveHandle { patch, handle, by_value }),
        1 => (i(), i()).prop_map(|(patch, pin)| Edit::RemovePin { patch, pin }),
        1 => (i(), "[a-z]{1,3}").prop_map(|(patch, name)| Edit::Rename { patch, name }),
        1 => (i(), any::<bool>()).prop_map(|(patch, front)| Edit::Reorder { patch, front }),
        1 => i().prop_map(|patch| Edit::RemovePatch { patch }),
    ]
}

const TRACKS: [&str; 5] = ["at", "scale", "rotate", "depth", "opacity"];

/// The Rhai entry for `edit` against `scene` as it is now (`None`: nothing to edit).
fn entry(edit: &Edit, scene: &lapclone::script::Draft) -> Option<String> {
    let on = Drafted {
        patches: &scene.patches,
    };
    match edit {
        Edit::Key { .. } | Edit::Opacity { .. } | Edit::RemoveKey { .. } | Edit::MoveKey { .. } => {
            key_entry(edit, &on)
        }
        _ => structure_entry(edit, &on),
    }
}

/// The patches an entry is written against.
struct Drafted<'a> {
    patches: &'a [lapclone::scene::Patch],
}

impl Drafted<'_> {
    /// The patch index `i` stands for, if there is any patch.
    fn pick(&self, i: usize) -> Option<usize> {
        (!self.patches.is_empty()).then(|| i % self.patches.len())
    }

    /// The Rhai expression for the patch `i` stands for.
    fn patch(&self, i: usize) -> Option<String> {
        let name = &self.patches[self.pick(i)?].name;
        Some(format!(
            "get_patch({})",
            lapclone::scene::rhai_string_literal(name)
        ))
    }

    /// Every key time of patch `p`, over all its tracks, sorted and unique.
    fn times(&self, p: usize) -> Vec<f64> {
        let pl = &self.patches[p].placement;
        let mut all: Vec<f64> = pl
            .position
            .times()
            .chain(pl.scale.times())
            .chain(pl.rotation.times())
            .chain(pl.depth.times())
            .chain(pl.opacity.times())
            .collect();
        all.sort_by(f64::total_cmp);
        all.dedup();
        all
    }

    /// Whether patch `p`'s track `name` has a key at `t`.
    fn has_key(&self, p: usize, name: &str, t: f64) -> bool {
        let pl = &self.patches[p].placement;
        match name {
            "at" => pl.position.has_key_at(t),
            "scale" => pl.scale.has_key_at(t),
            "rotate" => pl.rotation.has_key_at(t),
            "depth" => pl.depth.has_key_at(t),
            _ => pl.opacity.has_key_at(t),
        }
    }
}

fn literal(v: f64) -> String {
    format!("{v:?}")
}

/// The entries that key, unkey or move keys.
fn key_entry(edit: &Edit, on: &Drafted) -> Option<String> {
    Some(match edit {
        Edit::Key {
            patch: p,
            track,
            t,
            existing,
            value,
            easing,
        } => {
            let known = on.times(on.pick(*p)?);
            let t = match existing {
                Some(k) if !known.is_empty() => known[k % known.len()],
                _ => *t,
            };
            let value = match TRACKS[*track] {
                "at" => format!("[{}, 1.5]", literal(*value)),
                "scale" => literal(value.abs() + 0.1),
                _ => literal(*value),
            };
            let (patch, track, easing) = (on.patch(*p)?, TRACKS[*track], easing.name());
            format!("{patch}.{track}({}, {value}, \"{easing}\");", literal(t))
        }
        Edit::Opacity { patch: p, t, value } => {
            let (patch, t, value) = (on.patch(*p)?, literal(*t), literal(*value));
            format!("{patch}.key({t}, #{{ opacity: {value} }});")
        }
        Edit::RemoveKey {
            patch: p,
            key,
            one_track,
        } => {
            let known = on.times(on.pick(*p)?);
            let t = *known.get(key % known.len().max(1))?;
            let patch = on.patch(*p)?;
            match one_track {
                Some(k) => {
                    let name = TRACKS[*k];
                    on.has_key(on.pick(*p)?, name, t)
                        .then(|| format!("{patch}.remove_key({}, \"{name}\");", literal(t)))?
                }
                None => format!("{patch}.remove_key({});", literal(t)),
            }
        }
        Edit::MoveKey { patch: p, key, to } => {
            let known = on.times(on.pick(*p)?);
            let t = *known.get(key % known.len().max(1))?;
            format!(
                "{}.move_key({}, {});",
                on.patch(*p)?,
                literal(t),
                literal(*to)
            )
        }
        _ => return None,
    })
}

/// The entries that remove handles, pins or patches, rename or reorder.
fn structure_entry(edit: &Edit, on: &Drafted) -> Option<String> {
    let patches = on.patches;
    Some(match edit {
        Edit::RemoveHandle {
            patch: p,
            handle,
            by_value,
        } => {
            let handles = patches[on.pick(*p)?].handles.len();
            let h = (handles > 0).then(|| handle % handles)?;
            if *by_value {
                // The handle value a user kept from `drag`: here a fresh one, appended.
                format!(
                    "{0}.remove_handle({0}.drag([1.0, 2.0], 3.0));",
                    on.patch(*p)?
                )
            } else {
                format!("{}.remove_handle({h});", on.patch(*p)?)
            }
        }
        Edit::RemovePin { patch: p, pin } => {
            let pins = &patches[on.pick(*p)?].pins;
            let i = (!pins.is_empty()).then(|| pin % pins.len())?;
            let at = pins[i].at;
            if i % 2 == 0 {
                let (x, y) = (literal(at.x), literal(at.y));
                format!("{}.remove_pin([{x}, {y}]);", on.patch(*p)?)
            } else {
                format!("{}.remove_pin({i});", on.patch(*p)?)
            }
        }
        Edit::Rename { patch: p, name } => {
            let target = on.patch(*p)?;
            let taken = patches.iter().any(|q| &q.name == name);
            (!taken).then(|| format!("{target}.rename(\"{name}\");"))?
        }
        Edit::Reorder { patch: p, front } => {
            let call = if *front { "to_front" } else { "to_back" };
            format!("{}.{call}();", on.patch(*p)?)
        }
        Edit::RemovePatch { patch: p } => {
            let name = &patches[on.pick(*p)?].name;
            format!(
                "remove_patch({});",
                lapclone::scene::rhai_string_literal(name)
            )
        }
        _ => return None,
    })
}

/// The scene with its image paths made canonical (`scenes/../assets/a.png` = `assets/a.png`).
fn canonical(mut scene: Scene) -> Scene {
    let fix = |p: &mut PathBuf| *p = p.canonicalize().unwrap();
    if let Background::Image(p) = &mut scene.canvas.background {
        fix(p);
    }
    for patch in &mut scene.patches {
        fix(&mut patch.source);
        if let Shape::Mask(p) = &mut patch.shape {
            fix(p);
        }
    }
    scene
}

fn temp_options() -> ScriptOptions {
    ScriptOptions {
        scene_dir: std::env::temp_dir(),
        scripts_dir: None,
        limits: Limits::default(),
        cancel: Default::default(),
    }
}

proptest! {
    #![proptest_config(Config {
        rng_seed: RngSeed::Fixed(0xED17),
        cases: 64,
        ..Config::default()
    })]

    #[test]
    fn edit_sessions_save_and_load_back(original in scene(), edits in prop::collection::vec(edit(), 1..12)) {
        let file = PathBuf::from("saved.rhai");
        let start = original.to_rhai();
        let engine = lapclone::script::SceneEngine::new(&temp_options());
        let mut scope = rhai::Scope::new();
        let _ = engine.run(&mut scope, &start, &file).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let mut entries = Vec::new();
        for edit in &edits {
            let Some(line) = entry(edit, &engine.draft()) else { continue };
            let _ = engine
                .run(&mut scope, &line, &file)
                .map_err(|e| TestCaseError::fail(format!("{line}: {e}")))?;
            entries.push(line);
        }
        let (edited, _) = engine.scene(&file).map_err(|e| TestCaseError::fail(e.to_string()))?;
        // The text form: the original text followed by the entries.
        let script = format!("{start}\n{}\n", entries.join("\n"));
        let replayed = parse_scene(&script, &file, &temp_options())
            .map_err(|e| TestCaseError::fail(format!("{e}\n---\n{script}")))?;
        prop_assert_eq!(&replayed.scene, &edited, "{}", script);
        // The keys form, written for a file in the project's scenes/ folder: paths relative
        // to it name the same files.
        let folder = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let keys = edited.to_rhai_in(&folder);
        prop_assert!(!keys.contains(env!("CARGO_MANIFEST_DIR")), "{}", keys);
        let options = ScriptOptions { scene_dir: folder, ..temp_options() };
        let parsed = parse_scene(&keys, &file, &options)
            .map_err(|e| TestCaseError::fail(format!("{e}\n---\n{keys}")))?;
        prop_assert_eq!(canonical(parsed.scene), canonical(edited), "{}", keys);
    }
}
