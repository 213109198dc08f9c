//! The library's `render_scene` (the output stage a Rust or Python user calls): the files it
//! writes equal `lapclone render`'s byte for byte, progress is reported per frame, and what
//! the CLI refuses comes back as typed `OutputError`s with nothing written.

use std::path::{Path, PathBuf};
use std::process::Command;

use lapclone::{
    load_scene_and_imports, render_scene, FrameRange, OutputError, OutputKind, RenderOptions,
    RenderProgress,
};

use crate::files::{asset, sorted_names};

/// A 96×64 scene of 4 frames (fps 4, 1 s): a moving triangle patch.
fn write_scene(dir: &Path) -> PathBuf {
    let scene = dir.join("tiny.rhai");
    let text = format!(
        "canvas(96, 64, #{{ fps: 4, duration: 1, background: \"{}\" }});\n\
         let p = patch(\"tri\", #{{ source: \"{}\", polygons: [[[10, 10], [80, 14], [30, 60]]] }});\n\
         p.at(0, [40, 30]).at(1, [60, 34], \"smooth\");\n",
        asset("coffee.png"),
        asset("chelsea.png")
    );
    std::fs::write(&scene, text).unwrap();
    scene
}

fn cli_render(scene: &Path, output: &Path, extra: &[&str]) {
    let done = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(output)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
}

#[derive(Default)]
struct Counted {
    frames: Vec<u64>,
}

impl RenderProgress for Counted {
    fn frame_done(&mut self, number: u64) {
        self.frames.push(number);
    }
}

fn render(scene: &Path, output: &Path, options: &RenderOptions) -> Result<Counted, OutputError> {
    let (loaded, imports) = load_scene_and_imports(scene).unwrap();
    let mut renderer = lapclone::build_renderer(&loaded).unwrap();
    let mut counted = Counted::default();
    let rendered = render_scene(
        &loaded,
        &imports,
        &mut renderer,
        output,
        options,
        &mut counted,
    )?;
    assert_eq!(rendered.path, output);
    assert_eq!(rendered.frames, counted.frames.len() as u64);
    Ok(counted)
}

#[test]
fn files_equal_lapclone_render_and_progress_counts_frames() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    for name in ["frames", "clip.gif", "clip.apng", "clip.y4m"] {
        let (ours, theirs) = (
            dir.path().join(format!("lib_{name}")),
            dir.path().join(name),
        );
        let counted = render(&scene, &ours, &RenderOptions::default()).unwrap();
        assert_eq!(counted.frames, [1, 2, 3, 4], "{name}");
        cli_render(&scene, &theirs, &[]);
        if ours.is_dir() {
            let names = sorted_names(&ours);
            assert_eq!(names, sorted_names(&theirs));
            assert_eq!(names.len(), 4);
            for file in names {
                let read = |d: &Path| std::fs::read(d.join(&file)).unwrap();
                assert_eq!(read(&ours), read(&theirs), "{file}");
            }
        } else {
            assert_eq!(
                std::fs::read(&ours).unwrap(),
                std::fs::read(&theirs).unwrap(),
                "{name}"
            );
        }
    }
}

#[test]
fn format_and_frames_options_match_the_cli_flags() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let (ours, theirs) = (dir.path().join("ours.bin"), dir.path().join("theirs.bin"));
    let options = RenderOptions {
        format: Some(OutputKind::Gif),
        frames: Some(FrameRange { first: 2, last: 3 }),
        ..RenderOptions::default()
    };
    assert_eq!(render(&scene, &ours, &options).unwrap().frames, [2, 3]);
    cli_render(&scene, &theirs, &["--format", "gif", "--frames", "2..3"]);
    assert_eq!(
        std::fs::read(&ours).unwrap(),
        std::fs::read(&theirs).unwrap()
    );
}

#[test]
fn refusals_are_typed_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let text = std::fs::read(&scene).unwrap();
    let y4m = RenderOptions {
        format: Some(OutputKind::Y4m),
        ..RenderOptions::default()
    };
    let error = render(&scene, &scene, &y4m).err().unwrap();
    assert!(matches!(&error, OutputError::ReplacesInput { output, .. } if output == &scene));
    assert_eq!(std::fs::read(&scene).unwrap(), text);

    let bmp = dir.path().join("x.bmp");
    let error = render(&scene, &bmp, &RenderOptions::default())
        .err()
        .unwrap();
    assert!(
        matches!(&error, OutputError::UnknownExtension { extension, .. } if extension == "bmp")
    );

    let missing = dir.path().join("nowhere").join("x.gif");
    let error = render(&scene, &missing, &RenderOptions::default())
        .err()
        .unwrap();
    assert!(matches!(
        error,
        OutputError::MissingFolder { exists: false, .. }
    ));

    let beyond = RenderOptions {
        frames: Some(FrameRange { first: 3, last: 9 }),
        ..RenderOptions::default()
    };
    let out = dir.path().join("beyond.gif");
    let error = render(&scene, &out, &beyond).err().unwrap();
    assert!(matches!(
        error,
        OutputError::FramesOutOfRange { total: 4, .. }
    ));
    assert!(!out.exists() && !bmp.exists());
    assert_eq!(sorted_names(dir.path()), ["tiny.rhai"]);
}

/// Raises the cancel flag as frame `at` is done, as a Ctrl-C arriving while it rendered
/// would.
struct CancelAt {
    at: u64,
    cancel: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl RenderProgress for CancelAt {
    fn frame_done(&mut self, number: u64) {
        if number == self.at {
            self.cancel
                .store(true, std::sync::atomic::Ordering::Relaxed);
        }
    }
}

/// A cancel that comes while the last frame renders stops the render as one during any
/// other frame does: an error and nothing written, not the whole output.
#[test]
fn a_cancel_during_the_last_frame_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let (loaded, imports) = load_scene_and_imports(&scene).unwrap();
    for name in ["frames", "clip.gif", "clip.apng", "clip.y4m"] {
        for at in [2, 4] {
            let output = dir.path().join(format!("{at}_{name}"));
            let cancel = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
            let options = RenderOptions {
                cancel: Some(cancel.clone()),
                ..RenderOptions::default()
            };
            let mut renderer = lapclone::build_renderer(&loaded).unwrap();
            let mut progress = CancelAt { at, cancel };
            let rendered = render_scene(
                &loaded,
                &imports,
                &mut renderer,
                &output,
                &options,
                &mut progress,
            );
            assert!(
                matches!(rendered, Err(OutputError::Interrupted { after }) if after == at),
                "{name} at {at}: {rendered:?}"
            );
            assert!(!output.exists(), "{name} at {at}: written");
        }
        let left: Vec<_> = sorted_names(dir.path());
        assert_eq!(left, ["tiny.rhai"], "{name}: left behind");
    }
}
