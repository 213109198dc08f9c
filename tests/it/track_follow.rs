//! Tracks driving scenes: `p.follow(...)` places the patch at the track plus its offset on
//! every frame (the frames' bytes equal a render of the same keys written by hand),
//! `track_keys` gives those keys, After Effects keyframe text and the CSV variants load to
//! the same keys, a track shorter than the scene is a `check` warning, a scene written back
//! keeps the `follow` call, and every malformed track file is a positioned error with exit
//! 1 and nothing written.

use std::path::Path;
use std::process::{Command, Output};

use lapclone::glam::DVec2;
use lapclone::script::load_scene;

use crate::files::{asset, sorted_names};

const FPS: f64 = 6.0;

/// Rows `(frame, x, y, rotate, scale)` of a two-point-style track, sub-pixel values.
fn rows() -> Vec<(u64, f64, f64, f64, f64)> {
    (1..=6u64)
        .map(|n| {
            let k = (n - 1) as f64;
            (
                n,
                40.25 + 3.125 * k,
                30.5 - 1.375 * k,
                2.5 * k,
                1.0 + 0.015 * k,
            )
        })
        .collect()
}

fn scene_text(body: &str) -> String {
    format!(
        "canvas(96, 64, #{{ fps: {FPS}, duration: 1, background: \"{}\" }});\n\
         let p = patch(\"tri\", #{{ source: \"{}\", polygons: [[[10, 10], [40, 14], [18, 36]]] }});\n{body}",
        asset("coffee.png"),
        asset("astronaut.png")
    )
}

fn lapclone(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(args)
        .output()
        .unwrap()
}

fn render(dir: &Path, name: &str, body: &str) -> Vec<Vec<u8>> {
    let scene = dir.join(format!("{name}.rhai"));
    std::fs::write(&scene, scene_text(body)).unwrap();
    let out_dir = dir.join(name);
    let out = lapclone(&[
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        out_dir.as_os_str(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    sorted_names(&out_dir)
        .iter()
        .map(|n| std::fs::read(out_dir.join(n)).unwrap())
        .collect()
}

fn write_csv(dir: &Path) {
    let mut text = String::from("frame,x,y,rotate,scale\n");
    for (n, x, y, r, s) in rows() {
        text.push_str(&format!("{n},{x:?},{y:?},{r:?},{s:?}\n"));
    }
    std::fs::write(dir.join("track.csv"), text).unwrap();
}

#[test]
fn follow_renders_the_same_frames_as_the_keys_written_by_hand() {
    let dir = tempfile::tempdir().unwrap();
    write_csv(dir.path());
    let offset = DVec2::new(3.5, -2.25);
    let followed = render(
        dir.path(),
        "followed",
        "p.follow(\"track.csv\", #{ offset: [3.5, -2.25] });\n",
    );
    let mut by_hand = String::new();
    for (n, x, y, r, s) in rows() {
        let t = (n - 1) as f64 / FPS;
        let at = DVec2::new(x, y) + DVec2::from_angle(r.to_radians()).rotate(offset) * s;
        by_hand.push_str(&format!(
            "p.key({t:?}, #{{ at: [{:?}, {:?}], rotate: {r:?}, scale: {s:?} }});\n",
            at.x, at.y
        ));
    }
    let hand = render(dir.path(), "hand", &by_hand);
    assert_eq!(followed.len(), 6);
    assert!(
        followed == hand,
        "a followed track renders other frames than its keys"
    );
    // Without rotate and scale the patch only moves: at = track + offset.
    let moved = render(
        dir.path(),
        "moved",
        "p.follow(\"track.csv\", #{ offset: [3.5, -2.25], rotate: false, scale: false });\n",
    );
    let mut by_hand = String::new();
    for (n, x, y, _, _) in rows() {
        let t = (n - 1) as f64 / FPS;
        by_hand.push_str(&format!("p.at({t:?}, [{:?}, {:?}]);\n", x + 3.5, y - 2.25));
    }
    assert!(moved == render(dir.path(), "moved_hand", &by_hand));
}

/// The patch's placement after running `body` in the test scene in `dir`.
fn placement(dir: &Path, body: &str) -> lapclone::animation::ScenePlacement {
    let scene = dir.join("probe.rhai");
    std::fs::write(&scene, scene_text(body)).unwrap();
    let loaded = load_scene(&scene).unwrap_or_else(|e| panic!("{e}"));
    loaded.scene.patches[0].placement.clone()
}

#[test]
fn after_effects_text_and_csv_variants_load_to_the_same_keys() {
    let dir = tempfile::tempdir().unwrap();
    write_csv(dir.path());
    let mut seconds = String::from("t,x,y,rotate,scale\n");
    let mut ae = String::from(
        "Adobe After Effects 8.0 Keyframe Data\n\n\tUnits Per Second\t6\n\tSource Width\t96\n\tSource Height\t64\n\tSource Pixel Aspect Ratio\t1\n\tComp Pixel Aspect Ratio\t1\n\nTransform\tPosition\n\tFrame\tX pixels\tY pixels\tZ pixels\t\n",
    );
    for (n, x, y, _, _) in rows() {
        let f = n - 1;
        ae.push_str(&format!("\t{f}\t{x:?}\t{y:?}\t0\t\n"));
    }
    ae.push_str("\nTransform\tRotation\n\tFrame\tdegrees\t\n");
    for (n, _, _, r, _) in rows() {
        ae.push_str(&format!("\t{}\t{r:?}\t\n", n - 1));
    }
    ae.push_str("\nTransform\tScale\n\tFrame\tX percent\tY percent\tZ percent\t\n");
    for (n, _, _, _, s) in rows() {
        let p = s * 100.0;
        ae.push_str(&format!("\t{}\t{p:?}\t{p:?}\t100\t\n", n - 1));
    }
    ae.push_str("\nEnd of Keyframe Data\n");
    for (n, x, y, r, s) in rows() {
        let t = (n - 1) as f64 / FPS;
        seconds.push_str(&format!("{t:?},{x:?},{y:?},{r:?},{s:?}\n"));
    }
    std::fs::write(dir.path().join("seconds.csv"), seconds).unwrap();
    std::fs::write(dir.path().join("track.txt"), ae).unwrap();
    let from_csv = placement(dir.path(), "p.follow(\"track.csv\");");
    assert_eq!(from_csv.position.keys().len(), 6);
    assert_eq!(from_csv.scale.keys().len(), 6);
    assert_eq!(
        placement(dir.path(), "p.follow(\"seconds.csv\");"),
        from_csv
    );
    let from_ae = placement(dir.path(), "p.follow(\"track.txt\");");
    // Percent → factor may differ in the last bit; positions and times are exact.
    assert_eq!(from_ae.position, from_csv.position);
    assert_eq!(from_ae.rotation, from_csv.rotation);
    for (a, b) in from_ae.scale.keys().iter().zip(from_csv.scale.keys()) {
        assert_eq!(a.time, b.time);
        assert!((a.value - b.value).abs() < 1e-12);
    }
    assert_eq!(
        placement(dir.path(), "p.keys(track_keys(\"track.csv\"));"),
        from_csv
    );
}

#[test]
fn a_followed_track_is_written_back_as_one_call() {
    let dir = tempfile::tempdir().unwrap();
    write_csv(dir.path());
    let scene = dir.path().join("probe.rhai");
    let body = "p.follow(\"track.csv\", #{ offset: [1, 2], from_frame: 2 });\n";
    std::fs::write(&scene, scene_text(body)).unwrap();
    let loaded = load_scene(&scene).unwrap();
    assert_eq!(loaded.scene.patches[0].placement.position.keys().len(), 5);
    let text = loaded.scene.to_rhai_in(dir.path());
    let call = "tri.follow(\"track.csv\", #{ point: 1, offset: [1.0, 2.0], from_frame: 2 });";
    assert!(text.contains(call), "{text}");
    assert!(
        !text.contains("tri.at(") && !text.contains("tri.key("),
        "{text}"
    );
    let again = dir.path().join("again.rhai");
    std::fs::write(&again, &text).unwrap();
    assert_eq!(
        same_files(load_scene(&again).unwrap().scene),
        same_files(loaded.scene.clone())
    );
    // A handle follows too: its target keys are the track's, written back as one call.
    let handle_body =
        "let h = p.drag([20, 20], 10);\nh.follow(\"track.csv\", #{ rotate: false });\n";
    std::fs::write(&scene, scene_text(handle_body)).unwrap();
    let handled = load_scene(&scene).unwrap().scene;
    let to = &handled.patches[0].handles[0].to;
    let expected: Vec<(f64, DVec2)> = rows()
        .iter()
        .map(|&(n, x, y, _, _)| ((n - 1) as f64 / FPS, DVec2::new(x, y)))
        .collect();
    let got: Vec<(f64, DVec2)> = to.keys().iter().map(|k| (k.time, k.value)).collect();
    assert_eq!(got, expected);
    assert!(handled.patches[0].handles[0].rotation.is_empty());
    let text = handled.to_rhai_in(dir.path());
    assert!(
        text.contains("tri_h1.follow(\"track.csv\", #{ point: 1, rotate: false });"),
        "{text}"
    );
    std::fs::write(&again, &text).unwrap();
    assert_eq!(
        same_files(load_scene(&again).unwrap().scene),
        same_files(handled)
    );
    std::fs::write(&scene, scene_text(body)).unwrap();
    // `check` warns that the first frame holds the track's first position.
    let out = lapclone(&["check".as_ref(), scene.as_os_str()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("follows track.csv from frame 2 (t ≈ 0.1667 s) only"),
        "{stderr}"
    );
}

#[test]
fn malformed_track_files_are_positioned_errors_and_nothing_is_written() {
    let cases: [(&str, &str, usize, &str); 5] = [
        ("missing header", "1,2,3\n", 1, "missing header"),
        (
            "a non-number",
            "frame,x,y\n1,2,3\n2,4,five\n",
            3,
            "`five` is not a number",
        ),
        (
            "frames out of order",
            "frame,x,y\n2,2,3\n1,4,5\n",
            3,
            "frame 1 comes after frame 2",
        ),
        ("an empty file", "frame,x,y\n", 2, "no rows"),
        ("a 0-byte file", "", 1, "empty (0 bytes)"),
    ];
    for (what, text, line, message) in cases {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("track.csv"), text).unwrap();
        let scene = dir.path().join("scene.rhai");
        std::fs::write(&scene, scene_text("p.follow(\"track.csv\");\n")).unwrap();
        let out_dir = dir.path().join("out");
        let out = lapclone(&[
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            out_dir.as_os_str(),
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{what}: {stderr}");
        assert!(
            stderr.contains(&format!("track.csv:{line}: ")),
            "{what}: {stderr}"
        );
        assert!(stderr.contains(message), "{what}: {stderr}");
        assert!(!out_dir.exists(), "{what}: wrote {out_dir:?}");
        let out = lapclone(&["check".as_ref(), scene.as_os_str()]);
        assert_eq!(out.status.code(), Some(1), "{what}");
    }
}

/// The scene with its image paths canonical: a scene written back names the assets
/// relative to its folder (`../…` where the checkout lies beside the temporary folder),
/// which loads as another spelling of the same files.
fn same_files(mut scene: lapclone::animation::Scene) -> lapclone::animation::Scene {
    let canonical = |path: &mut std::path::PathBuf| *path = path.canonicalize().unwrap();
    if let lapclone::animation::Background::Image(path) = &mut scene.canvas.background {
        canonical(path);
    }
    for patch in &mut scene.patches {
        canonical(&mut patch.source);
    }
    scene
}

/// One huge line (16 MB of separators) is refused in about the file's own size: before,
/// each separator became a list entry and 200 MB of address space was not enough.
#[cfg(unix)]
#[test]
fn one_huge_track_line_is_refused_in_little_memory() {
    let huge = 8_000_000;
    let ae_head = "Adobe After Effects 8.0 Keyframe Data\n\n\tUnits Per Second\t6\n\n\
                   Transform\tPosition\n\tFrame\tX pixels\tY pixels\tZ pixels\n\t";
    let found = format!("expected 3 values, found {}", huge + 1);
    let cases: [(&str, String, usize, &str); 3] = [
        (
            "a header of commas",
            format!("{}\n1,2,3\n", ",".repeat(2 * huge)),
            1,
            "unknown column ``",
        ),
        (
            "a row of values",
            format!("frame,x,y\n{}\n", "1,".repeat(huge)),
            2,
            &found,
        ),
        (
            "a keyframe line",
            format!("{ae_head}{}", "1\t".repeat(huge)),
            7,
            "more than 64 values",
        ),
    ];
    for (what, text, line, message) in cases {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("track.csv"), text).unwrap();
        let scene = dir.path().join("scene.rhai");
        std::fs::write(&scene, scene_text("p.follow(\"track.csv\");\n")).unwrap();
        // 200 MB of address space: the binary and a 16 MB file fit, a list per separator not.
        let out = Command::new("sh")
            .arg("-c")
            .arg("ulimit -v 200000 && exec \"$0\" check \"$1\"")
            .arg(env!("CARGO_BIN_EXE_lapclone"))
            .arg(&scene)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{what}: {stderr}");
        assert!(
            stderr.contains(&format!("track.csv:{line}: {message}")),
            "{what}: {stderr}"
        );
    }
}
