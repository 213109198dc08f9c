//! `lapclone track` on footage the tests make: a photograph moved along a known sub-pixel
//! path (translation; translation, rotation and scale for a two-point track) with noise and
//! JPEG compression, 100 frames of 320×240. The tracked path must stay within 0.3 px RMS
//! and 1 px at the last frame, the pair's rotation within 0.5° and scale within 0.5 %; a
//! point covered by a flat grey box for 10 frames is reported lost there (confidence and a
//! warning naming the frames) and found again after.

use std::path::Path;
use std::process::{Command, Output};

use lapclone::glam::DVec2;
use lapclone::track::{TrackFile, TrackRow, LOST_BELOW};
use lapclone::FloatImage;

use crate::files::asset;
use crate::track_footage::{frame, jpeg, Motion, Noise};

const SIZE: (u32, u32) = (320, 240);
const FRAMES: u32 = 100;

/// Writes `f_0001.jpg` … (quality 90, noise σ = 2 levels); `cover(k)` gives a grey box
/// (centre, half-side) to paint over frame k.
fn write_footage(dir: &Path, motion: &Motion, cover: impl Fn(u32) -> Option<(DVec2, f64)>) {
    let photo = FloatImage::load(Path::new(&asset("chelsea.png"))).unwrap();
    let mut noise = Noise::new(41);
    for k in 0..FRAMES {
        let mut image = frame(&photo, SIZE, motion, k, 2.0, &mut noise);
        if let Some((c, half)) = cover(k) {
            for (x, y, p) in image.enumerate_pixels_mut() {
                let d = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5) - c;
                if d.x.abs() <= half && d.y.abs() <= half {
                    *p = image::Rgb([128, 128, 128]);
                }
            }
        }
        std::fs::write(dir.join(format!("f_{:04}.jpg", k + 1)), jpeg(&image, 90)).unwrap();
    }
}

fn track(dir: &Path, points: &[DVec2], extra: &[&str]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lapclone"));
    command.arg("track").arg(dir.join("f_%04d.jpg"));
    for p in points {
        command.arg("--point").arg(format!("{},{}", p.x, p.y));
    }
    command.args(extra).arg("-o").arg(dir.join("track.csv"));
    command.output().unwrap()
}

/// RMS and last-frame error of `rows` against `motion`'s truth for `start`.
fn errors(rows: &[TrackRow], motion: &Motion, start: DVec2) -> (f64, f64) {
    assert_eq!(rows.len(), FRAMES as usize);
    let error = |k: usize| rows[k].at.distance(motion.truth(SIZE, k as u32, start));
    let rms = ((0..rows.len()).map(|k| error(k).powi(2)).sum::<f64>() / rows.len() as f64).sqrt();
    (rms, error(rows.len() - 1))
}

#[test]
fn a_translating_point_is_followed_to_a_third_of_a_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let motion = Motion::translation();
    write_footage(dir.path(), &motion, |_| None);
    let start = DVec2::new(150.0, 112.0);
    let out = track(dir.path(), &[start], &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.path().join("track.csv")).unwrap();
    assert!(
        text.starts_with("frame,x,y,confidence\n1,150.0000,112.0000,1.000\n"),
        "{text}"
    );
    // `-o -` puts the same CSV on standard output, as `render -o -` puts its frames, and
    // writes no file named `-`.
    let piped = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .arg("track")
        .arg(dir.path().join("f_%04d.jpg"))
        .args(["--point", "150,112", "-o", "-"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(piped.status.success());
    assert_eq!(String::from_utf8_lossy(&piped.stdout), text);
    assert!(!dir.path().join("-").exists());
    let file = TrackFile::load(&dir.path().join("track.csv")).unwrap();
    let (rms, last) = errors(&file.points[0], &motion, start);
    println!("translation: RMS {rms:.3} px, last frame {last:.3} px");
    assert!(rms <= 0.3, "RMS error {rms} px");
    assert!(last <= 1.0, "last frame off by {last} px");
    assert!(file.points[0]
        .iter()
        .all(|r| r.confidence.unwrap() >= LOST_BELOW));
}

#[test]
fn two_points_give_rotation_and_scale() {
    let dir = tempfile::tempdir().unwrap();
    let motion = Motion::similarity();
    write_footage(dir.path(), &motion, |_| None);
    let (a, b) = (DVec2::new(118.0, 96.0), DVec2::new(206.0, 138.0));
    let out = track(dir.path(), &[a, b], &["--size", "31", "--search", "40"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let file = TrackFile::load(&dir.path().join("track.csv")).unwrap();
    assert_eq!(file.points.len(), 2);
    for (rows, start) in file.points.iter().zip([a, b]) {
        let (rms, last) = errors(rows, &motion, start);
        println!("similarity, point {start}: RMS {rms:.3} px, last frame {last:.3} px");
        assert!(
            rms <= 0.3 && last <= 1.0,
            "point {start}: RMS {rms}, last {last}"
        );
    }
    let (mut worst_turn, mut worst_scale) = (0.0f64, 0.0f64);
    for (k, row) in file.points[0].iter().enumerate() {
        let turn = row.rotate.unwrap() - (motion.degrees)(k as u32);
        let scale = row.scale.unwrap() / (motion.scale)(k as u32) - 1.0;
        worst_turn = worst_turn.max(turn.abs());
        worst_scale = worst_scale.max(scale.abs());
    }
    println!(
        "similarity: rotation within {worst_turn:.3}°, scale within {:.3} %",
        worst_scale * 100.0
    );
    assert!(worst_turn <= 0.5, "rotation off by {worst_turn}°");
    assert!(worst_scale <= 0.005, "scale off by {worst_scale}");
}

#[test]
fn a_covered_point_is_reported_lost_and_found_again() {
    let dir = tempfile::tempdir().unwrap();
    let motion = Motion::translation();
    let start = DVec2::new(150.0, 112.0);
    // Frames 41–50 (k = 40..50) cover the point with a flat grey box.
    let covered = |k: u32| {
        (40..50)
            .contains(&k)
            .then(|| (motion.truth(SIZE, k, start), 30.0))
    };
    write_footage(dir.path(), &motion, covered);
    // A second point beside it: while the first is lost, the pair's motion holds (pure
    // translation: no turn, no scale) instead of following the first's stale position.
    let other = DVec2::new(230.0, 150.0);
    let pair = track(dir.path(), &[start, other], &[]);
    assert!(
        pair.status.success(),
        "{}",
        String::from_utf8_lossy(&pair.stderr)
    );
    let file = TrackFile::load(&dir.path().join("track.csv")).unwrap();
    for row in &file.points[1] {
        let (rotate, scale) = (row.rotate.unwrap(), row.scale.unwrap());
        assert!(rotate.abs() < 0.5 && (scale - 1.0).abs() < 0.005, "{row:?}");
    }
    let out = track(dir.path(), &[start], &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let text = std::fs::read_to_string(dir.path().join("track.csv")).unwrap();
    let around: Vec<&str> = text.lines().skip(38).take(15).collect();
    assert!(
        stderr.contains("point 1 lost at frames 41–50"),
        "{stderr}\n{around:#?}"
    );
    let file = TrackFile::load(&dir.path().join("track.csv")).unwrap();
    let rows = &file.points[0];
    for (k, row) in rows.iter().enumerate() {
        let confidence = row.confidence.unwrap();
        let error = row.at.distance(motion.truth(SIZE, k as u32, start));
        if (40..50).contains(&k) {
            assert!(
                confidence < LOST_BELOW,
                "frame {}: confidence {confidence}",
                k + 1
            );
        } else {
            assert!(
                confidence >= LOST_BELOW,
                "frame {}: confidence {confidence}",
                k + 1
            );
            assert!(error < 0.5, "frame {}: {error} px off", k + 1);
        }
    }
}

#[test]
fn bad_points_and_ranges_are_usage_errors_that_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let photo = FloatImage::load(Path::new(&asset("chelsea.png"))).unwrap();
    let mut noise = Noise::new(7);
    for k in 0..3 {
        let image = frame(&photo, SIZE, &Motion::translation(), k, 0.0, &mut noise);
        std::fs::write(
            dir.path().join(format!("f_{:04}.jpg", k + 1)),
            jpeg(&image, 90),
        )
        .unwrap();
    }
    let cases: [(&[&str], &str); 7] = [
        // A negative coordinate is a value, not a flag: the point is refused for where it is.
        (&["--point", "-5,10"], "outside the first frame"),
        (&["--point", "nan,3"], "not a finite number"),
        (
            &["--point", "100,100", "--frames", "3..2"],
            "must have 1 ≤ A ≤ B",
        ),
        (&["--point", "100,100", "--size", "0"], "between 5 and 255"),
        (&["--point", "1e8,5"], "outside the first frame"),
        (&["--point", "1e12,5"], "1e12 is past ±1e9 px"),
        // Plate numbers counted on from it would wrap around (all frames read one file).
        (
            &["--point", "100,100", "--start", "18446744073709551615"],
            "is not in 0..=1000000000000000",
        ),
    ];
    for (args, message) in cases {
        let mut command = Command::new(env!("CARGO_BIN_EXE_lapclone"));
        command
            .arg("track")
            .arg(dir.path().join("f_%04d.jpg"))
            .args(args);
        let out = command
            .arg("-o")
            .arg(dir.path().join("track.csv"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
        assert!(!dir.path().join("track.csv").exists(), "{args:?}");
    }
}

/// A gap in the plates is an error naming the missing one (not a silent end of the
/// footage), unless `--frames` stays before it; flag values are checked before the footage
/// is opened.
#[test]
fn a_gap_in_the_plates_is_named_and_flags_are_checked_first() {
    let dir = tempfile::tempdir().unwrap();
    for k in (1..=8).filter(|k| *k != 5) {
        let shade = |x: u32, y: u32| ((x * 7 + y * 13 + k) % 251) as u8;
        let plate = image::RgbImage::from_fn(64, 48, |x, y| image::Rgb([shade(x, y), 90, 40]));
        plate
            .save(dir.path().join(format!("f_{k:04}.png")))
            .unwrap();
    }
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .args([
                "track",
                "f_%04d.png",
                "--point",
                "32,24",
                "--size",
                "9",
                "--search",
                "4",
            ])
            .args(extra)
            .args(["-o", "t.csv"])
            .current_dir(dir.path())
            .output()
            .unwrap()
    };
    let out = run(&[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("frame 5 (f_0005.png) is missing, but plates up to number 8"));
    assert!(!dir.path().join("t.csv").exists());
    assert!(run(&["--frames", "1..4"]).status.success());
    let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args([
            "track",
            "missing/f_%04d.png",
            "--point",
            "1,1",
            "--size",
            "0",
            "-o",
            "x.csv",
        ])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--size 0 must be between 5"));
}

/// A plate or video path that holds something other than a file says what it holds: the
/// first plate a folder, a video a FIFO (a FIFO could also never be read to its end).
#[cfg(unix)]
#[test]
fn a_plate_or_video_that_is_no_file_says_what_it_is() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("f_0001.jpg")).unwrap();
    std::fs::copy(asset("chelsea.png"), dir.path().join("f_0002.jpg")).unwrap();
    let fifo = dir.path().join("clip.mp4");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    for (footage, message) in [
        (
            dir.path().join("f_%04d.jpg"),
            "f_0001.jpg is a folder, not a file",
        ),
        (fifo, "clip.mp4 is not a regular file (a FIFO)"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .arg("track")
            .arg(&footage)
            .args(["--point", "10,10", "-o"])
            .arg(dir.path().join("track.csv"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains(message), "{stderr}");
        assert!(!dir.path().join("track.csv").exists());
    }
}
