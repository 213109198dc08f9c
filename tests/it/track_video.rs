//! `lapclone track` on a video (decoded through ffmpeg, streamed): the tests' synthetic
//! footage (a photograph moved along a known sub-pixel path, noise, JPEG) encoded as H.264
//! at high quality (CRF 12, 4:2:0) at 12 fps and tracked at 24 fps. The tracked path keeps
//! the PNG-footage bounds (≤ 0.3 px RMS, ≤ 1 px at the last frame) against frame
//! ⌊(n − 1) / 2⌋'s truth; the frames are numbered as `render` numbers a video background
//! (tracking `render`'s frames of a scene over that video gives the same CSV byte for
//! byte); a missing file and a file that is not a video are errors (exit 1) that write
//! nothing. Skipped, with the reason printed, where ffmpeg is absent.

use std::path::Path;
use std::process::{Command, Output};

use lapclone::glam::DVec2;
use lapclone::track::{TrackFile, TrackTime};
use lapclone::FloatImage;

use crate::files::asset;
use crate::track_footage::{frame, jpeg, Motion, Noise};
use crate::video_cli::{has_ffmpeg, run_ffmpeg};

const SIZE: (u32, u32) = (320, 240);
const FRAMES: u32 = 100;
const START: DVec2 = DVec2::new(150.0, 112.0);

fn lapclone(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `clip.mp4` in `dir`: the translation footage, 100 frames at 12 fps.
fn write_video(dir: &Path) -> std::path::PathBuf {
    let photo = FloatImage::load(Path::new(&asset("chelsea.png"))).unwrap();
    let mut noise = Noise::new(41);
    let motion = Motion::translation();
    for k in 0..FRAMES {
        let image = frame(&photo, SIZE, &motion, k, 2.0, &mut noise);
        std::fs::write(dir.join(format!("f_{:04}.jpg", k + 1)), jpeg(&image, 90)).unwrap();
    }
    let video = dir.join("clip.mp4");
    let out = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-framerate", "12", "-i"])
        .arg(dir.join("f_%04d.jpg"))
        .args(["-c:v", "libx264", "-crf", "12", "-pix_fmt", "yuv420p"])
        .arg(&video)
        .output()
        .unwrap();
    assert!(out.status.success(), "ffmpeg: {}", stderr(&out));
    video
}

fn track(footage: &Path, output: &Path) -> Output {
    let point = format!("{},{}", START.x, START.y);
    lapclone(&[
        "track".as_ref(),
        footage.as_os_str(),
        "--point".as_ref(),
        point.as_ref(),
        "--fps".as_ref(),
        "24".as_ref(),
        "-o".as_ref(),
        output.as_os_str(),
    ])
}

#[test]
fn a_video_is_tracked_to_a_third_of_a_pixel_with_render_s_frame_numbers() {
    if !has_ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let video = write_video(dir.path());
    let csv = dir.path().join("video.csv");
    let out = track(&video, &csv);
    assert!(out.status.success(), "{}", stderr(&out));
    let file = TrackFile::load(&csv).unwrap();
    let rows = &file.points[0];
    // 100 frames at 12 fps last 25/3 s: 200 frames at 24 fps, each video frame shown twice.
    assert_eq!(rows.len(), 2 * FRAMES as usize);
    let motion = Motion::translation();
    let mut squares = 0.0;
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(row.time, TrackTime::Frame(i as u64 + 1));
        let truth = motion.truth(SIZE, i as u32 / 2, START);
        squares += row.at.distance_squared(truth);
    }
    let rms = (squares / rows.len() as f64).sqrt();
    let last = rows[rows.len() - 1]
        .at
        .distance(motion.truth(SIZE, FRAMES - 1, START));
    println!("video: RMS {rms:.3} px, last frame {last:.3} px");
    assert!(rms <= 0.3, "RMS error {rms} px");
    assert!(last <= 1.0, "last frame off by {last} px");

    // The same video as a scene's background, rendered to PNG frames and tracked: the
    // same decoded pixels under the same numbers give the same CSV.
    let scene = dir.path().join("plate.rhai");
    std::fs::write(
        &scene,
        "canvas(#{ fps: 24, duration: 200 / 24.0, background: \"clip.mp4\" });\n",
    )
    .unwrap();
    let frames = dir.path().join("frames");
    let out = lapclone(&[
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        frames.as_os_str(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let rendered = dir.path().join("rendered.csv");
    let out = track(&frames.join("frame_%04d.png"), &rendered);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        std::fs::read_to_string(&rendered).unwrap(),
        std::fs::read_to_string(&csv).unwrap(),
        "tracking the video and tracking render's frames of it differ"
    );
}

#[test]
fn a_missing_or_broken_video_is_an_error_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let broken = dir.path().join("notes.mp4");
    std::fs::write(&broken, "these are notes, not a video\n").unwrap();
    for (footage, expected) in [
        (dir.path().join("missing.mp4"), "missing.mp4"),
        (broken, "notes.mp4"),
    ] {
        let csv = dir.path().join("track.csv");
        let out = track(&footage, &csv);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{message}");
        assert!(message.contains(expected), "{message}");
        assert!(!message.contains("panicked"), "{message}");
        assert!(!csv.exists(), "{message}");
        let mut left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        left.sort();
        assert_eq!(left, ["notes.mp4"], "{message}");
        println!("{}: {}", footage.display(), message.trim());
    }
}

/// Without `--frames`, a track runs to the video's last decoded frame, whether its container
/// states a length that rounds one frame too many (3.3 s at 25 fps: 83 estimated, 82
/// decoded) or none at all (a piped Matroska); with `--frames` past the end, a usage error
/// naming the frames there are.
#[test]
fn a_whole_video_is_tracked_to_its_last_decoded_frame() {
    if !has_ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let ffmpeg = |args: &str| run_ffmpeg(dir.path(), args);
    ffmpeg("-f lavfi -i testsrc2=s=96x64:d=3.3:r=60 -c:v ffv1 r60.mkv");
    ffmpeg("-f lavfi -i testsrc2=s=96x64:d=1:r=24 -c:v ffv1 -f matroska - > piped.mkv");
    let run = |video: &str, extra: &[&str]| {
        let mut args = vec![
            "track", video, "--point", "48,32", "--size", "9", "--search", "8",
        ];
        args.extend(extra);
        args.extend(["-o", "t.csv"]);
        Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .args(&args)
            .current_dir(dir.path())
            .output()
            .unwrap()
    };
    for (video, fps, frames) in [("r60.mkv", "25", 82), ("piped.mkv", "24", 24)] {
        let out = run(video, &["--fps", fps]);
        assert!(out.status.success(), "{video}: {}", stderr(&out));
        assert!(
            stderr(&out).contains(&format!("frames 1..{frames}")),
            "{}",
            stderr(&out)
        );
        let file = TrackFile::load(&dir.path().join("t.csv")).unwrap();
        assert_eq!(file.points[0].len(), frames, "{video}");
    }
    let out = run("piped.mkv", &["--frames", "1..30"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("the video has 24 frames"),
        "{}",
        stderr(&out)
    );
}

/// A video's frame size takes the image limits a plate's does, from ffprobe's answer before
/// anything is decoded (a 68 kB video of 12000×12000 frames took 2.5 GB), for `track` and
/// for a scene's footage alike.
#[test]
fn a_video_past_the_image_limits_is_refused_before_decoding() {
    if !has_ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let args = "-f lavfi -i color=c=gray:s=16400x16:r=24 -frames:v 2 -c:v ffv1 wide.mkv";
    run_ffmpeg(dir.path(), args);
    let wide = dir.path().join("wide.mkv");
    let csv = dir.path().join("track.csv");
    let out = track(&wide, &csv);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("exceeds the size limit"),
        "{}",
        stderr(&out)
    );
    assert!(!csv.exists());
    let scene = dir.path().join("wide.rhai");
    std::fs::write(
        &scene,
        "canvas(#{ fps: 24, duration: 0.1, background: \"wide.mkv\" });\n",
    )
    .unwrap();
    let out = lapclone(&["check".as_ref(), scene.as_os_str()]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("exceeds the size limit"),
        "{}",
        stderr(&out)
    );
}
