//! The scene language's renamed spellings: takes scenes written with the old and the new
//! names and gives the same scene, with a positioned warning for each old name; `ease` in a
//! `key` map; and `pin` giving a `Pin` that removes itself.

use std::path::PathBuf;

use lapclone::scene::{BoundaryData, BoundaryPlacement, Easing, FootageSource};
use lapclone::script::{parse_scene, LoadedScene, SceneError, ScriptOptions};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn load(text: &str) -> Result<LoadedScene, SceneError> {
    parse_scene(
        text,
        &root().join("renames.rhai"),
        &ScriptOptions::for_scene_file(&root().join("renames.rhai")),
    )
}

const PATCH: &str =
    "let p = patch(\"p\", #{ source: \"assets/astronaut.png\", mask: \"assets/horse_mask.png\"";

#[test]
fn old_and_new_patch_option_names_give_the_same_scene_and_old_ones_warn() {
    let head = "canvas(64, 48);\n";
    let new = load(&format!(
        "{head}{PATCH}, mesh_boundary: \"cracks\", boundary_sampling: \"vertex\" }});\n"
    ))
    .unwrap();
    let old = load(&format!(
        "{head}{PATCH}, boundary: \"cracks\", boundary_data: \"vertex\" }});\n"
    ))
    .unwrap();
    assert_eq!(new.scene, old.scene);
    assert_eq!(new.scene.patches[0].boundary, BoundaryPlacement::Cracks);
    assert_eq!(new.scene.patches[0].boundary_data, BoundaryData::Vertex);
    assert!(new.warnings().is_empty(), "{:?}", new.warnings());
    let file = root().join("renames.rhai");
    assert_eq!(
        old.warnings(),
        [
            format!(
                "{}:2:9: `boundary` is now `mesh_boundary` (the old name still works)",
                file.display()
            ),
            format!(
                "{}:2:9: `boundary_data` is now `boundary_sampling` (the old name still works)",
                file.display()
            ),
        ]
    );
    let both = load(&format!(
        "{head}{PATCH}, boundary: \"cracks\", mesh_boundary: \"cracks\" }});\n"
    ));
    let message = both.unwrap_err().to_string();
    assert!(
        message.contains("give `mesh_boundary` only (`boundary` is its old name)"),
        "{message}"
    );
}

#[test]
fn footage_start_numbers_keep_their_old_names_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    for n in 7..10 {
        image::RgbImage::new(8, 6)
            .save(dir.path().join(format!("f_{n}.png")))
            .unwrap();
    }
    let plates = dir.path().join("f_%d.png");
    let scene = |key: &str| {
        load(&format!(
            "canvas(#{{ fps: 1, duration: 2, background: {plates:?}, {key}: 8 }});\n"
        ))
        .unwrap()
    };
    let (new, old) = (scene("background_start_number"), scene("background_start"));
    assert_eq!(new.scene, old.scene);
    let lapclone::scene::Background::Footage(footage) = &new.scene.canvas.background else {
        panic!("footage background");
    };
    assert!(matches!(
        footage.source,
        FootageSource::Sequence { start: 8, .. }
    ));
    assert!(new.warnings().is_empty());
    assert_eq!(old.warnings().len(), 1);
    assert!(old.warnings()[0].contains("`background_start` is now `background_start_number`"));
}

#[test]
fn a_key_map_takes_its_easing_as_ease_or_as_a_last_argument_but_not_both() {
    let head = format!("canvas(64, 48);\n{PATCH} }});\n");
    let in_map = load(&format!(
        "{head}p.key(1, #{{ at: [3, 4], ease: \"smooth\" }});"
    ))
    .unwrap();
    let trailing = load(&format!("{head}p.key(1, #{{ at: [3, 4] }}, \"smooth\");")).unwrap();
    assert_eq!(in_map.scene, trailing.scene);
    let position = &in_map.scene.patches[0].placement.position;
    assert_eq!(position.keys()[0].easing, Easing::Smooth);
    let twice = load(&format!(
        "{head}p.key(1, #{{ at: [3, 4], ease: \"smooth\" }}, \"linear\");"
    ));
    assert!(twice
        .unwrap_err()
        .to_string()
        .contains("give the easing once"));
}

#[test]
fn pin_gives_a_pin_that_removes_itself_and_pins_chain_on_its_patch() {
    let head = format!("canvas(64, 48);\n{PATCH} }});\n");
    let chained = load(&format!(
        "{head}p.pin([1, 2]).pin([3, 4], #{{ start: 1 }});"
    ))
    .unwrap();
    let pins: Vec<_> = chained.scene.patches[0]
        .pins
        .iter()
        .map(|q| (q.at.x, q.at.y, q.start))
        .collect();
    assert_eq!(pins, [(1.0, 2.0, 0.0), (3.0, 4.0, 1.0)]);
    let removed = load(&format!(
        "{head}let q = p.pin([1, 2]);\np.pin([3, 4]);\nq.remove();"
    ))
    .unwrap();
    let pins: Vec<_> = removed.scene.patches[0]
        .pins
        .iter()
        .map(|q| (q.at.x, q.at.y))
        .collect();
    assert_eq!(pins, [(3.0, 4.0)]);
    let again = load(&format!(
        "{head}let q = p.pin([1, 2]);\nq.remove();\nq.remove();"
    ));
    assert!(again.unwrap_err().to_string().contains("no pin at [1, 2]"));
}
