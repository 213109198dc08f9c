//! `lapclone render` and `preview` end to end on a tiny scene: file names, frame ranges,
//! GIF/APNG output, byte-identical frames for any job count, and the exit codes of bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::files;
use files::{asset, sorted_names};

/// A 96×64 scene of 4 frames (fps 4, 1 s): a dragged, moving triangle patch.
fn write_scene(dir: &Path) -> PathBuf {
    let scene = dir.join("tiny.rhai");
    let text = format!(
        "canvas(96, 64, #{{ fps: 4, duration: 1, background: \"{}\" }});\n\
         let p = patch(\"tri\", #{{ source: \"{}\", polygons: [[[10, 10], [80, 14], [30, 60]]] }});\n\
         p.at(0, [40, 30]).at(1, [60, 34], \"smooth\");\n\
         p.drag([60, 16], 20).key(0, [60, 16]).key(1, [66, 24]);\n",
        asset("coffee.png"),
        asset("chelsea.png")
    );
    std::fs::write(&scene, text).unwrap();
    scene
}

fn lapclone(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(args)
        .output()
        .unwrap()
}

fn os(s: &str) -> &std::ffi::OsStr {
    std::ffi::OsStr::new(s)
}

#[test]
fn png_sequence_is_numbered_from_one_and_identical_for_any_job_count() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    for (out, jobs) in [(&one, "1"), (&two, "2")] {
        let o = lapclone(&[
            os("render"),
            scene.as_os_str(),
            os("-o"),
            out.as_os_str(),
            os("--jobs"),
            os(jobs),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(String::from_utf8_lossy(&o.stdout).contains("rendered 4 frames"));
    }
    let names = sorted_names(&one);
    assert_eq!(
        names,
        [
            "frame_0001.png",
            "frame_0002.png",
            "frame_0003.png",
            "frame_0004.png"
        ]
    );
    assert_eq!(sorted_names(&two), names);
    for name in &names {
        assert_eq!(
            std::fs::read(one.join(name)).unwrap(),
            std::fs::read(two.join(name)).unwrap(),
            "{name}"
        );
    }
    // The patch moves: consecutive frames differ.
    assert_ne!(
        std::fs::read(one.join(&names[0])).unwrap(),
        std::fs::read(one.join(&names[3])).unwrap()
    );
}

#[test]
fn frame_range_renders_only_those_frames_and_matches_the_full_render() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let (all, part) = (dir.path().join("all"), dir.path().join("part"));
    let o = lapclone(&[os("render"), scene.as_os_str(), os("-o"), all.as_os_str()]);
    assert!(o.status.success());
    let o = lapclone(&[
        os("render"),
        scene.as_os_str(),
        os("-o"),
        part.as_os_str(),
        os("--frames"),
        os("3..4"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(sorted_names(&part), ["frame_0003.png", "frame_0004.png"]);
    for name in sorted_names(&part) {
        assert_eq!(
            std::fs::read(all.join(&name)).unwrap(),
            std::fs::read(part.join(&name)).unwrap()
        );
    }
}

#[test]
fn preview_of_a_frame_equals_that_rendered_frame() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let frames = dir.path().join("frames");
    assert!(lapclone(&[
        os("render"),
        scene.as_os_str(),
        os("-o"),
        frames.as_os_str()
    ])
    .status
    .success());
    let preview = dir.path().join("p.png");
    let o = lapclone(&[
        os("preview"),
        scene.as_os_str(),
        os("--frame"),
        os("2"),
        os("-o"),
        preview.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let decode = |p: &Path| image::open(p).unwrap().to_rgba8().into_raw();
    assert_eq!(decode(&preview), decode(&frames.join("frame_0002.png")));
}

#[test]
fn gif_and_apng_hold_every_frame() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let gif = dir.path().join("a.gif");
    let o = lapclone(&[
        os("render"),
        scene.as_os_str(),
        os("--format"),
        os("gif"),
        os("-o"),
        gif.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let decoder = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(&gif).unwrap(),
    ))
    .unwrap();
    use image::AnimationDecoder;
    assert_eq!(decoder.into_frames().count(), 4);
    let apng = dir.path().join("a.png");
    let o = lapclone(&[
        os("render"),
        scene.as_os_str(),
        os("--format"),
        os("apng"),
        os("-o"),
        apng.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let reader = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&apng).unwrap()))
        .read_info()
        .unwrap();
    assert_eq!(
        reader.info().animation_control().map(|a| a.num_frames),
        Some(4)
    );
}

#[test]
fn bad_input_gets_the_right_exit_code_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let out = dir.path().join("out");
    // Usage errors: exit 2.
    for extra in [["--frames", "3..9"], ["--jobs", "0"], ["--frames", "0..2"]] {
        let o = lapclone(&[
            os("render"),
            scene.as_os_str(),
            os("-o"),
            out.as_os_str(),
            os(extra[0]),
            os(extra[1]),
        ]);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    // A scene that fails at a position: exit 1 with file:line:col.
    let broken = dir.path().join("broken.rhai");
    std::fs::write(&broken, "canvas(96, 64);\nlet p = patch(\"x\", #{ source: \"missing.png\", polygons: [[[0, 0], [9, 0], [0, 9]]] });\n").unwrap();
    let o = lapclone(&[os("render"), broken.as_os_str(), os("-o"), out.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("broken.rhai:2:"), "{stderr}");
    // An output folder whose parent is missing: exit 1.
    let deep = dir.path().join("no").join("such").join("dir");
    let o = lapclone(&[os("render"), scene.as_os_str(), os("-o"), deep.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!out.exists() && !dir.path().join("no").exists());
}
