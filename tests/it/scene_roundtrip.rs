//! `Scene::to_rhai` round trip: parsing the written scene gives back an equal scene, over
//! random scenes (fixed seed) with every feature, awkward floats and awkward names.

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
        Just(1e20),
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
        Just("we\"ird \\ name\n\t✓".to_string()),
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
                },
                handles,
                pins,
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
        .prop_map(|(canvas, patches)| Scene { canvas, patches })
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
        let options = ScriptOptions {
            scene_dir: std::env::temp_dir(),
            scripts_dir: None,
            limits: Limits::default(),
            cancel: Default::default(),
        };
        let parsed = parse_scene(&text, &PathBuf::from("saved.rhai"), &options)
            .map_err(|e| TestCaseError::fail(format!("{e}\n---\n{text}")))?;
        prop_assert_eq!(&parsed.scene, &original, "{}", text);
        // Writing again is a fixed point.
        prop_assert_eq!(parsed.scene.to_rhai(), text);
    }
}
