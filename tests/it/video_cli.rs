//! Video in and out, end to end through the binary: footage backgrounds (numbered plates),
//! animated patch sources with one factorisation, Y4M against the PNG frames, MP4 through
//! ffmpeg (skipped with a printed reason when ffmpeg is absent), output format inference,
//! `--force`, slices equal to a whole render, and the refusals of bad footage.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::files;
use files::{asset, sorted_names};

const W: u32 = 96;
const H: u32 = 64;

pub(crate) fn lapclone(args: &[&OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(args)
        .output()
        .unwrap()
}

pub(crate) fn os(s: &str) -> &OsStr {
    OsStr::new(s)
}

pub(crate) fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub(crate) fn has_ffmpeg() -> bool {
    let found = lapclone::util::find_program("ffmpeg").is_some()
        && lapclone::util::find_program("ffprobe").is_some();
    if !found {
        eprintln!("skipped: ffmpeg/ffprobe not on PATH (apt-get install ffmpeg to run this test)");
    }
    found
}

/// Runs `ffmpeg -v error -y ARGS` through the shell in `dir` (so ARGS may redirect),
/// failing the test with what ffmpeg said.
pub(crate) fn run_ffmpeg(dir: &Path, args: &str) {
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("ffmpeg -v error -y {args}"))
        .current_dir(dir)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "ffmpeg {args}: {said}");
}

/// A plate whose every pixel differs from the other plates' (seeded by `k`).
pub(crate) fn plate(k: u32, width: u32, height: u32) -> image::RgbImage {
    image::RgbImage::from_fn(width, height, |x, y| {
        let v = x * 7 + y * 13 + k * 50;
        image::Rgb([
            (v % 251) as u8,
            ((v * 3 + k * 17) % 253) as u8,
            (k * 80 + 20) as u8,
        ])
    })
}

fn write_plates(dir: &Path, count: u32, first: u32) {
    std::fs::create_dir_all(dir.join("plates")).unwrap();
    for k in 0..count {
        let path = dir.join(format!("plates/frame_{:04}.png", first + k));
        plate(k, W, H).save(&path).unwrap();
    }
}

/// A small still patch at [70, 20]: a triangle of chelsea.png.
pub(crate) const PATCH: &str = "patch(\"p\", #{ source: SOURCE, polygons: [[[10, 10], [40, 12], [20, 36]]] }).at(0, [70, 20]);";

pub(crate) fn write_scene(dir: &Path, canvas: &str, patch: &str) -> PathBuf {
    let scene = dir.join("scene.rhai");
    let source = format!("\"{}\"", asset("chelsea.png"));
    std::fs::write(
        &scene,
        format!("{canvas}\n{}\n", patch.replace("SOURCE", &source)),
    )
    .unwrap();
    scene
}

pub(crate) fn render(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![os("render"), scene.as_os_str(), os("-o"), out.as_os_str()];
    args.extend(extra.iter().map(|s| os(s)));
    lapclone(&args)
}

pub(crate) fn rgba(path: &Path) -> image::RgbaImage {
    image::open(path).unwrap().to_rgba8()
}

#[test]
fn each_frame_lies_over_its_own_plate() {
    let dir = tempfile::tempdir().unwrap();
    write_plates(dir.path(), 3, 1);
    let canvas = "canvas(#{ fps: 3, duration: 1, background: \"plates/frame_%04d.png\" });";
    let scene = write_scene(dir.path(), canvas, PATCH);
    let out = dir.path().join("out");
    let o = render(&scene, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("1 factorisation"));
    assert_eq!(sorted_names(&out).len(), 3);
    for i in 0..3u32 {
        let frame = rgba(&out.join(format!("frame_{:04}.png", i + 1)));
        assert_eq!(
            frame.dimensions(),
            (W, H),
            "the canvas takes the plate's size"
        );
        let expected = plate(i, W, H);
        let mut compared = 0;
        for (x, y, px) in frame.enumerate_pixels() {
            // The patch's bounding box is about 30×26 around [70, 20].
            let near_patch = x + 4 >= 50 && y <= 40;
            if !near_patch {
                let e = expected.get_pixel(x, y).0;
                assert_eq!(px.0, [e[0], e[1], e[2], 255], "frame {i} pixel {x},{y}");
                compared += 1;
            }
        }
        assert!(compared > 4000);
    }
}

#[test]
fn start_number_and_hold_pick_the_plates() {
    let dir = tempfile::tempdir().unwrap();
    write_plates(dir.path(), 2, 7);
    // Three frames from two plates: the last plate holds.
    let canvas = "canvas(#{ fps: 3, duration: 1, background: \"plates/frame_%04d.png\", background_hold: true });";
    let scene = write_scene(dir.path(), canvas, PATCH);
    let out = dir.path().join("out");
    let o = render(&scene, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let corner = |n: u32| {
        rgba(&out.join(format!("frame_{n:04}.png")))
            .get_pixel(1, 60)
            .0
    };
    let plate_corner = |k: u32| plate(k, W, H).get_pixel(1, 60).0;
    assert_eq!(corner(1)[..3], plate_corner(0));
    assert_eq!(corner(2)[..3], plate_corner(1));
    assert_eq!(corner(3)[..3], plate_corner(1));
}

/// With the last plate held, a plate in the middle that is there but no file (a FIFO, a
/// folder) is an error naming it: it does not end the footage early, silently.
#[cfg(unix)]
#[test]
fn a_plate_that_is_no_file_is_an_error_even_when_the_last_one_holds() {
    for (kind, message) in [
        ("fifo", "is not a regular file (a FIFO)"),
        ("folder", "is a folder, not a file"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        write_plates(dir.path(), 2, 1);
        let odd = dir.path().join("plates/frame_0003.png");
        if kind == "fifo" {
            assert!(Command::new("mkfifo").arg(&odd).status().unwrap().success());
        } else {
            std::fs::create_dir(&odd).unwrap();
        }
        plate(3, W, H)
            .save(dir.path().join("plates/frame_0004.png"))
            .unwrap();
        let canvas = "canvas(#{ fps: 3, duration: 2, background: \"plates/frame_%04d.png\", background_hold: true });";
        let scene = write_scene(dir.path(), canvas, PATCH);
        let out = dir.path().join("out");
        let o = render(&scene, &out, &[]);
        assert_eq!(o.status.code(), Some(1), "{kind}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(&format!("frame_0003.png {message}")),
            "{kind}: {}",
            stderr(&o)
        );
        assert!(!out.exists(), "{kind}");
    }
}

#[test]
fn an_alternating_source_alternates_the_patch_with_one_factorisation() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("src")).unwrap();
    let chelsea = image::open(asset("chelsea.png")).unwrap().to_rgb8();
    let mut inverted = chelsea.clone();
    image::imageops::invert(&mut inverted);
    for n in 1..=4 {
        let frame = if n % 2 == 1 { &chelsea } else { &inverted };
        frame
            .save(dir.path().join(format!("src/f_{n}.png")))
            .unwrap();
    }
    let canvas = format!(
        "canvas({W}, {H}, #{{ fps: 4, duration: 1, background: \"{}\" }});",
        asset("coffee.png")
    );
    let patch = "patch(\"p\", #{ source: \"src/f_%d.png\", polygons: [[[10, 10], [40, 12], [20, 36]]] }).at(0, [50, 30]);";
    let scene = write_scene(dir.path(), &canvas, patch);
    let out = dir.path().join("out");
    let o = render(&scene, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("; 1 factorisation)"), "{stdout}");
    let bytes = |n: u32| rgba(&out.join(format!("frame_{n:04}.png"))).into_raw();
    assert_eq!(bytes(1), bytes(3));
    assert_eq!(bytes(2), bytes(4));
    // Frames 1 and 2 differ in the patch (its texture is inverted) and nowhere else.
    let (a, b) = (
        rgba(&out.join("frame_0001.png")),
        rgba(&out.join("frame_0002.png")),
    );
    let mut differing = 0;
    for (x, y, pa) in a.enumerate_pixels() {
        if pa != b.get_pixel(x, y) {
            differing += 1;
            assert!(
                (30..=72).contains(&x) && (12..=50).contains(&y),
                "{x},{y} outside the patch"
            );
        }
    }
    assert!(differing > 200, "only {differing} patch pixels differ");
}

/// Frames of a Y4M stream: (width, height, planes of each frame).
fn read_y4m(bytes: &[u8]) -> (u32, u32, Vec<Vec<u8>>) {
    let header_end = bytes.iter().position(|&b| b == b'\n').unwrap();
    let header = std::str::from_utf8(&bytes[..header_end]).unwrap();
    assert!(header.starts_with("YUV4MPEG2 "), "{header}");
    assert!(header.contains(" C444"), "{header}");
    let field = |tag: char| {
        header
            .split(' ')
            .find_map(|f| f.strip_prefix(tag))
            .unwrap()
            .to_string()
    };
    let (w, h): (u32, u32) = (field('W').parse().unwrap(), field('H').parse().unwrap());
    let frame_len = (w * h * 3) as usize;
    let mut frames = Vec::new();
    let mut at = header_end + 1;
    while at < bytes.len() {
        assert_eq!(&bytes[at..at + 6], b"FRAME\n");
        at += 6;
        frames.push(bytes[at..at + frame_len].to_vec());
        at += frame_len;
    }
    (w, h, frames)
}

/// BT.709 limited range, as the README documents, in f64.
fn ycbcr(px: [u8; 4]) -> [f64; 3] {
    let a = px[3] as f64 / 255.0;
    let [r, g, b] = [px[0], px[1], px[2]].map(|v| v as f64 / 255.0 * a);
    let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    [
        16.0 + 219.0 * y,
        128.0 + 224.0 * (b - y) / 1.8556,
        128.0 + 224.0 * (r - y) / 1.5748,
    ]
}

#[test]
fn y4m_matches_the_png_frames_within_one_level() {
    let dir = tempfile::tempdir().unwrap();
    let canvas = format!(
        "canvas({W}, {H}, #{{ fps: 24, duration: 0.125, background: \"{}\" }});",
        asset("coffee.png")
    );
    let patch = "let p = patch(\"p\", #{ source: SOURCE, polygons: [[[10, 10], [40, 12], [20, 36]]] }); p.at(0, [40, 30]).at(0.125, [60, 34]); p.rotate(0, 0).rotate(0.125, 30);";
    let scene = write_scene(dir.path(), &canvas, patch);
    let pngs = dir.path().join("pngs");
    let y4m = dir.path().join("out.y4m");
    assert!(render(&scene, &pngs, &[]).status.success());
    let o = render(&scene, &y4m, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (w, h, frames) = read_y4m(&std::fs::read(&y4m).unwrap());
    assert_eq!((w, h, frames.len()), (W, H, 3));
    let n = (W * H) as usize;
    for (i, planes) in frames.iter().enumerate() {
        let png = rgba(&pngs.join(format!("frame_{:04}.png", i + 1)));
        for (k, px) in png.pixels().enumerate() {
            let want = ycbcr(px.0);
            for c in 0..3 {
                let got = planes[c * n + k] as f64;
                assert!(
                    (got - want[c]).abs() <= 1.0,
                    "frame {i} pixel {k} channel {c}: {got} vs {}",
                    want[c]
                );
            }
        }
    }
    // The same stream on standard output.
    let o = lapclone(&[os("render"), scene.as_os_str(), os("-o"), os("-")]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(o.stdout, std::fs::read(&y4m).unwrap());
}

#[test]
fn slices_rendered_separately_equal_the_whole_render() {
    let dir = tempfile::tempdir().unwrap();
    let canvas = format!(
        "canvas({W}, {H}, #{{ fps: 4, duration: 1, background: \"{}\" }});",
        asset("coffee.png")
    );
    let patch = "let p = patch(\"p\", #{ source: SOURCE, polygons: [[[10, 10], [40, 12], [20, 36]]] }); p.at(0, [30, 30]).at(1, [66, 34]); p.scale(0, 1).scale(1, 1.4);";
    let scene = write_scene(dir.path(), &canvas, patch);
    let (whole, a, b) = (
        dir.path().join("whole"),
        dir.path().join("a"),
        dir.path().join("b"),
    );
    assert!(render(&scene, &whole, &[]).status.success());
    assert!(render(&scene, &a, &["--frames", "1..2"]).status.success());
    assert!(render(&scene, &b, &["--frames", "3..4"]).status.success());
    for (slice, names) in [
        (&a, ["frame_0001.png", "frame_0002.png"]),
        (&b, ["frame_0003.png", "frame_0004.png"]),
    ] {
        assert_eq!(sorted_names(slice), names);
        for name in names {
            assert_eq!(
                std::fs::read(slice.join(name)).unwrap(),
                std::fs::read(whole.join(name)).unwrap(),
                "{name}"
            );
        }
    }
}

#[test]
fn the_output_extension_names_the_format_and_old_frames_need_force() {
    let dir = tempfile::tempdir().unwrap();
    let canvas = format!(
        "canvas({W}, {H}, #{{ fps: 4, duration: 1, background: \"{}\" }});",
        asset("coffee.png")
    );
    let scene = write_scene(dir.path(), &canvas, PATCH);
    let gif = dir.path().join("cat.gif");
    assert!(render(&scene, &gif, &[]).status.success());
    assert_eq!(&std::fs::read(&gif).unwrap()[..6], b"GIF89a");
    let apng = dir.path().join("cat.apng");
    assert!(render(&scene, &apng, &[]).status.success());
    let bytes = std::fs::read(&apng).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    assert!(bytes.windows(4).any(|w| w == b"acTL"), ".apng is animated");
    let png = dir.path().join("cat.png");
    assert!(render(&scene, &png, &[]).status.success());
    assert!(
        png.join("frame_0004.png").is_file(),
        ".png is a frame folder"
    );
    // A folder with all four frames, then a 2-frame slice into it: refused, then forced.
    let folder = dir.path().join("frames");
    assert!(render(&scene, &folder, &[]).status.success());
    let o = render(&scene, &folder, &["--frames", "1..2"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("frame files of another render"),
        "{}",
        stderr(&o)
    );
    assert_eq!(sorted_names(&folder).len(), 4);
    let o = render(&scene, &folder, &["--frames", "1..2", "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(sorted_names(&folder), ["frame_0001.png", "frame_0002.png"]);
    // A background that is a folder says so.
    let scene2 = write_scene(
        dir.path(),
        "canvas(96, 64, #{ background: \"frames\" });",
        PATCH,
    );
    let o = lapclone(&[os("check"), scene2.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("is a folder"), "{}", stderr(&o));
}

/// Each bad input: a clear message, exit 1, nothing written.
pub(crate) fn assert_refused(dir: &Path, canvas: &str, patch: &str, message: &str) {
    let scene = write_scene(dir, canvas, patch);
    let out = dir.join("refused");
    let o = render(&scene, &out, &[]);
    assert_eq!(o.status.code(), Some(1), "{canvas} {patch}: {}", stderr(&o));
    assert!(
        stderr(&o).contains(message),
        "wanted `{message}` in: {}",
        stderr(&o)
    );
    assert!(!out.exists(), "{} was written", out.display());
}

#[test]
fn bad_footage_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    write_plates(dir.path(), 3, 1);
    let d = dir.path();
    assert_refused(
        d,
        "canvas(#{ fps: 3, background: \"plates/frame_0001.png\", background_start: 1 });",
        PATCH,
        "has no frame number",
    );
    assert_refused(
        d,
        "canvas(#{ fps: 3, background: \"plates/frame_%s.png\" });",
        PATCH,
        "must start %d",
    );
    assert_refused(
        d,
        "canvas(#{ fps: 3, background: \"plates/shot_%04d.png\" });",
        PATCH,
        "matches no files",
    );
    assert_refused(
        d,
        "canvas(#{ fps: 4, background: \"plates/frame_%04d.png\" });",
        PATCH,
        "frame_0004.png, which does not exist",
    );
    plate(9, W + 2, H)
        .save(d.join("plates/frame_0004.png"))
        .unwrap();
    assert_refused(
        d,
        "canvas(#{ fps: 4, background: \"plates/frame_%04d.png\" });",
        PATCH,
        "98×64, but the footage is 96×64",
    );
    // A source sequence shorter than the scene.
    std::fs::create_dir_all(d.join("src")).unwrap();
    std::fs::copy(asset("chelsea.png"), d.join("src/s_1.png")).unwrap();
    let short =
        "patch(\"p\", #{ source: \"src/s_%d.png\", polygons: [[[10, 10], [40, 12], [20, 36]]] });";
    assert_refused(
        d,
        "canvas(96, 64, #{ fps: 3 });",
        short,
        "s_2.png, which does not exist (add `source_hold: true`",
    );
    let held = "patch(\"p\", #{ source: \"src/s_%d.png\", source_hold: true, polygons: [[[10, 10], [40, 12], [20, 36]]] });";
    let scene = write_scene(d, "canvas(96, 64, #{ fps: 3 });", held);
    assert!(render(&scene, &d.join("held"), &[]).status.success());
    // A 0-byte video: refused by ffprobe, or for want of ffmpeg; either way clearly.
    std::fs::write(d.join("empty.mp4"), b"").unwrap();
    let expected = if has_ffmpeg() {
        "cannot read video"
    } else {
        "ffmpeg not found on PATH"
    };
    assert_refused(
        d,
        "canvas(#{ fps: 3, background: \"empty.mp4\" });",
        PATCH,
        expected,
    );
}

#[test]
fn mp4_has_the_frames_size_and_rate_and_video_footage_reads_back() {
    if !has_ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mp4 = dir.path().join("cat.mp4");
    let demo = root.join("scenes/cat_in_coffee.rhai");
    let o = render(&demo, &mp4, &["--frames", "1..12"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let probe = Command::new("ffprobe")
        .args(["-v", "error", "-count_frames", "-select_streams", "v:0"])
        .args([
            "-show_entries",
            "stream=width,height,r_frame_rate,nb_read_frames",
        ])
        .args(["-of", "default=noprint_wrappers=1"])
        .arg(&mp4)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&probe.stdout);
    let preview = lapclone(&[os("check"), demo.as_os_str()]);
    let check = String::from_utf8_lossy(&preview.stdout);
    // `check` prints e.g. "…: ok — 600×400, 24 fps, …".
    let size = check
        .split(" — ")
        .nth(1)
        .unwrap()
        .split(',')
        .next()
        .unwrap();
    let (w, h) = size.split_once('×').unwrap();
    let fps = check.split(", ").nth(1).unwrap().trim_end_matches(" fps");
    assert!(text.contains(&format!("width={w}")), "{text} vs {check}");
    assert!(text.contains(&format!("height={h}")), "{text} vs {check}");
    assert!(
        text.contains(&format!("r_frame_rate={fps}/1")),
        "{text} vs {check}"
    );
    assert!(text.contains("nb_read_frames=12"), "{text}");
    // The video as footage: its plates have its size, and a corrupt video is refused.
    let scene = write_scene(
        dir.path(),
        "canvas(#{ fps: 24, duration: 0.25, background: \"cat.mp4\" });",
        PATCH,
    );
    let out = dir.path().join("from_video");
    let o = render(&scene, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(sorted_names(&out).len(), 6);
    let mut bytes = std::fs::read(&mp4).unwrap();
    bytes.truncate(bytes.len() / 3);
    bytes[..64].fill(0x5a);
    std::fs::write(dir.path().join("bad.mp4"), bytes).unwrap();
    assert_refused(
        dir.path(),
        "canvas(#{ fps: 24, background: \"bad.mp4\" });",
        PATCH,
        "cannot read video",
    );
}

#[test]
fn without_ffmpeg_video_output_is_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let canvas = format!(
        "canvas(95, 63, #{{ fps: 4, duration: 1, background: \"{}\" }});",
        asset("coffee.png")
    );
    let scene = write_scene(dir.path(), &canvas, PATCH);
    let mp4 = dir.path().join("out.mp4");
    let o = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args([os("render"), scene.as_os_str(), os("-o"), mp4.as_os_str()])
        .env("PATH", dir.path().join("no-such-folder"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("ffmpeg not found on PATH: install it (for example: apt-get install ffmpeg) or use --format png|gif|apng|y4m"), "{}", stderr(&o));
    assert!(std::fs::read_dir(dir.path()).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .contains("mp4")));
    // With ffmpeg, the odd-sized canvas is padded to even sides, with a note.
    if has_ffmpeg() {
        let o = render(&scene, &mp4, &[]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stderr(&o).contains("padded to 96×64"), "{}", stderr(&o));
        let probe = Command::new("ffprobe")
            .args(["-v", "error", "-show_entries", "stream=width,height"])
            .args(["-of", "default=noprint_wrappers=1"])
            .arg(&mp4)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&probe.stdout);
        assert!(text.contains("width=96\nheight=64"), "{text}");
    }
}

/// Processes whose command line names `needle` (Linux: `/proc/*/cmdline`).
#[cfg(target_os = "linux")]
fn processes_naming(needle: &str) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .filter_map(|e| std::fs::read(e.ok()?.path().join("cmdline")).ok())
        .map(|bytes| String::from_utf8_lossy(&bytes).replace('\0', " "))
        .filter(|line| line.contains(needle))
        .collect()
}

/// ffmpeg starts before the scene is read; a scene that then fails must still leave no
/// video, no temporary file and no ffmpeg behind.
#[test]
fn a_scene_failing_after_ffmpeg_started_leaves_nothing() {
    if !has_ffmpeg() {
        eprintln!("skipped: ffmpeg is not installed");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let broken = [
        // A script error (reading), then a missing image (building the renderer).
        ("canvas(96, 64, #{ fps: 4 });\npatch(\"p\", #{ source: 12 });", "scene.rhai:2"),
        (
            "canvas(96, 64, #{ fps: 4 });\npatch(\"p\", #{ source: \"gone.png\", polygons: [[[1, 1], [9, 1], [1, 9]]] });",
            "gone.png",
        ),
    ];
    for (text, message) in broken {
        let scene = d.join("scene.rhai");
        std::fs::write(&scene, text).unwrap();
        let mp4 = d.join("out.mp4");
        let o = render(&scene, &mp4, &[]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(
            stderr(&o).contains(message),
            "wanted `{message}` in: {}",
            stderr(&o)
        );
        let left: Vec<_> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|name| name.contains("mp4"))
            .collect();
        assert!(left.is_empty(), "left behind: {left:?}");
        #[cfg(target_os = "linux")]
        {
            let running = processes_naming(&d.to_string_lossy());
            assert!(running.is_empty(), "still running: {running:?}");
        }
    }
}

/// A video stored turned a quarter (a phone's: a rotation in its display matrix) is read
/// upright at the size ffmpeg decodes it to, not as rows of the stored size (which gave
/// scrambled frames of the same byte count).
#[test]
fn a_video_with_a_quarter_turn_is_read_upright() {
    if !has_ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let stored = plate(0, 48, 32);
    stored.save(dir.path().join("plate.png")).unwrap();
    let ffmpeg = |args: &[&str]| {
        let status = Command::new("ffmpeg")
            .args(["-y", "-v", "error"])
            .args(args)
            .current_dir(dir.path())
            .status()
            .unwrap();
        assert!(status.success(), "ffmpeg {args:?}");
    };
    let lossless = ["-c:v", "libx264", "-crf", "0", "-pix_fmt", "yuv444p"];
    let mut args = vec![
        "-loop",
        "1",
        "-i",
        "plate.png",
        "-frames:v",
        "6",
        "-r",
        "24",
    ];
    args.extend(lossless);
    args.push("flat.mp4");
    ffmpeg(&args);
    ffmpeg(&[
        "-i",
        "flat.mp4",
        "-c",
        "copy",
        "-metadata:s:v:0",
        "rotate=90",
        "turned.mp4",
    ]);
    let scene = write_scene(
        dir.path(),
        "canvas(32, 48, #{ fps: 24, duration: 0.125, background: \"turned.mp4\" });",
        "",
    );
    let out = dir.path().join("p.png");
    let o = lapclone(&[os("preview"), scene.as_os_str(), os("-o"), out.as_os_str()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let frame = rgba(&out);
    assert_eq!(frame.dimensions(), (32, 48));
    // rotate=90 shows the stored picture turned a quarter counter-clockwise.
    let upright = image::imageops::rotate270(&stored);
    let worst = frame
        .pixels()
        .zip(upright.pixels())
        .flat_map(|(a, b)| (0..3).map(move |c| a[c].abs_diff(b[c])))
        .max()
        .unwrap();
    assert!(
        worst <= 8,
        "largest difference {worst} from the upright plate"
    );
}

/// ffmpeg exits 0 when it cannot finish the file (its trailer on a full disk): the render
/// fails with ffmpeg's words instead of reporting a cut-short video as rendered.
#[cfg(target_os = "linux")]
#[test]
fn a_video_ffmpeg_could_not_finish_is_a_failure() {
    if !has_ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(
        dir.path(),
        "canvas(96, 64, #{ fps: 4, duration: 1 });",
        PATCH,
    );
    let o = render(&scene, Path::new("/dev/full"), &["--format", "webm"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("No space left on device"),
        "{}",
        stderr(&o)
    );
}

/// A video shorter than a second is a patch source like any other: its first frame is read
/// at the scene's rate, as every later one is (at one frame a second, a clip of 11 frames
/// at 24 fps gave none). A one-frame clip held (`source_hold`) works too.
#[test]
fn a_short_video_is_an_animated_source() {
    if !has_ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let ffmpeg = |args: &str| run_ffmpeg(dir.path(), args);
    ffmpeg("-f lavfi -i testsrc2=s=96x64:r=24 -frames:v 11 -c:v ffv1 short.mkv");
    ffmpeg("-f lavfi -i testsrc2=s=96x64:r=24 -frames:v 1 -c:v ffv1 one.mkv");
    for (video, extra, duration) in [
        ("short.mkv", "", 0.4),
        ("one.mkv", ", source_hold: true", 0.5),
    ] {
        let scene = dir.path().join("clip.rhai");
        std::fs::write(
            &scene,
            format!(
                "canvas(120, 80, #{{ fps: 24, duration: {duration} }});\n\
                 let p = patch(\"p\", #{{ source: \"{video}\"{extra}, polygons: [[[10, 10], [60, 10], [60, 50], [10, 50]]] }});\n\
                 p.at(0, [60, 40]);\n"
            ),
        )
        .unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(dir.path().join("out.gif"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{video}: {stderr}");
        assert!(dir.path().join("out.gif").is_file(), "{video}");
    }
}

/// A video shorter than one frame at the scene's rate (1 s at 0.4 fps) still has frame 1,
/// its picture at t = 0: ffmpeg's rate filter gave none, so the scene was "too short" and
/// `background_hold` then failed with "ffmpeg decoded no frames".
#[test]
fn a_video_shorter_than_one_scene_frame_gives_its_first_frame() {
    if !has_ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    run_ffmpeg(
        dir.path(),
        "-f lavfi -i testsrc=size=64x48:rate=10:duration=1 -pix_fmt yuv420p vid.mp4",
    );
    // Its first frame, converted as lapclone has ffmpeg convert the frames it reads.
    run_ffmpeg(
        dir.path(),
        "-i vid.mp4 -frames:v 1 -f rawvideo -pix_fmt rgba first.rgba",
    );
    let first = std::fs::read(dir.path().join("first.rgba")).unwrap();
    for hold in ["", ", background_hold: true"] {
        let canvas =
            format!("canvas(#{{ fps: 0.4, duration: 2.5, background: \"vid.mp4\"{hold} }});");
        let scene = dir.path().join("short.rhai");
        std::fs::write(&scene, &canvas).unwrap();
        let out = dir.path().join(format!("out{}", hold.len()));
        let o = render(&scene, &out, &[]);
        assert!(o.status.success(), "{canvas}: {}", stderr(&o));
        assert_eq!(sorted_names(&out), ["frame_0001.png"]);
        let frame = rgba(&out.join("frame_0001.png")).into_raw();
        assert!(
            frame == first,
            "{canvas}: frame 1 is not the video's first frame"
        );
    }
}
