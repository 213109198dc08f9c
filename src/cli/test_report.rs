//! What `lapclone test` reports: takes the scenes' results and gives the per-frame lines (or
//! JSON objects), the summary, the `index.html` of failing and pending frames under `--out`,
//! the JUnit XML file, and the run's exit status (an error for exit 1 or 2).

use lapclone::util::ShowPath;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context as _;

use lapclone::golden::Figures;
use serde_json::json;

use super::test_args::{FrameResult, Outcome, SceneResult, Status, TestArgs};
use super::UsageError;

/// Prints a finished scene's results: a line (or, with `json`, an object) per frame.
pub fn print_scene(result: &SceneResult, json: bool) {
    if let Some(failure) = &result.failure {
        eprint_line!("ERROR {}", failure.message);
    }
    // A failed write here is reported by the summary line, written the same way.
    for frame in &result.frames {
        if json {
            let _ = super::say(frame_json(&result.scene, frame));
        } else {
            let _ = super::say(frame_line(&result.scene, frame));
            if let Some(detail) = detail_line(frame) {
                let _ = super::say(detail);
            }
        }
    }
}

/// Counts of a run, as the summary and the JUnit file state them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    pub passed: usize,
    pub warned: usize,
    pub failed: usize,
    pub new: usize,
    pub updated: usize,
    /// Scenes that did not load or render.
    pub errors: usize,
    pub load_errors: usize,
    pub frames: usize,
    pub scenes: usize,
}

pub fn count(results: &[SceneResult]) -> Counts {
    let mut counts = Counts {
        scenes: results.len(),
        ..Counts::default()
    };
    for result in results {
        if let Some(failure) = &result.failure {
            counts.errors += 1;
            counts.load_errors += usize::from(!failure.loads);
        }
        for frame in &result.frames {
            counts.frames += 1;
            match frame.outcome.status() {
                Status::Pass => counts.passed += 1,
                Status::Warn => counts.warned += 1,
                Status::Fail => counts.failed += 1,
                Status::New => counts.new += 1,
                Status::Updated => counts.updated += 1,
            }
        }
    }
    counts
}

/// Summary, reports and the exit status.
pub fn finish(args: &TestArgs, results: &[SceneResult], seconds: f64) -> anyhow::Result<()> {
    let counts = count(results);
    let shown: Vec<(&SceneResult, &FrameResult)> = results
        .iter()
        .flat_map(|r| r.frames.iter().map(move |f| (r, f)))
        .filter(|(_, f)| f.pictures.is_some())
        .collect();
    let report = args.report_dir();
    if let Some(dir) = &report {
        if !shown.is_empty() || dir.join("index.html").is_file() {
            write_index(dir, &shown, &counts)?;
        }
    }
    if let Some(path) = &args.junit {
        let xml = junit_xml(results, &counts, seconds);
        super::test_args::write_file(path, xml.as_bytes())?;
    }
    let summary = summary_line(&counts, seconds);
    let notes = notes(report.filter(|_| !shown.is_empty()), results);
    if args.json {
        eprint_line!("{summary}");
        notes.iter().for_each(|n| eprint_line!("{n}"));
    } else {
        super::say(&summary)?;
        for note in &notes {
            super::say(note)?;
        }
    }
    verdict(&counts)
}

/// The notes after the summary: where the report is, and what to do with pending frames.
fn notes(report: Option<std::path::PathBuf>, results: &[SceneResult]) -> Vec<String> {
    let pending = results
        .iter()
        .flat_map(|r| &r.frames)
        .filter(|f| f.pending_written.is_some())
        .count();
    let mut notes = Vec::new();
    if let Some(dir) = report {
        notes.push(format!("report: {}", dir.join("index.html").shown()));
    }
    if pending > 0 {
        notes.push(format!(
            "{pending} pending frame(s): lapclone test --review (or --accept / --reject)"
        ));
    }
    notes
}

/// The run's outcome: a usage error when a scene could not be checked, a failure when a
/// frame failed, had no golden or did not render.
fn verdict(counts: &Counts) -> anyhow::Result<()> {
    if counts.load_errors > 0 {
        return Err(UsageError(format!(
            "{} scene(s) could not be checked (see the ERROR lines)",
            counts.load_errors
        ))
        .into());
    }
    if counts.failed + counts.new + counts.errors > 0 {
        anyhow::bail!(
            "{} frame(s) failed, {} had no golden, {} scene(s) failed to render",
            counts.failed,
            counts.new,
            counts.errors
        );
    }
    Ok(())
}

fn summary_line(c: &Counts, seconds: f64) -> String {
    let verdict = if c.failed + c.new + c.errors > 0 {
        "FAILED"
    } else {
        "ok"
    };
    let mut line = format!(
        "test result: {verdict}. {} passed; {} warned; {} failed; {} new",
        c.passed, c.warned, c.failed, c.new
    );
    if c.updated > 0 {
        let _ = write!(line, "; {} updated", c.updated);
    }
    let _ = write!(
        line,
        "; {} scene error(s) — {} frames in {} scenes, {seconds:.2} s",
        c.errors, c.frames, c.scenes
    );
    line
}

fn status_word(status: Status) -> &'static str {
    match status {
        Status::Pass => "PASS",
        Status::Warn => "WARN",
        Status::Fail => "FAIL",
        Status::New => "NEW",
        Status::Updated => "UPDATED",
    }
}

/// A value in 8-bit units: whole numbers without decimals.
fn units(value: f64) -> String {
    if value.fract() == 0.0 {
        format!("{value:.0}")
    } else {
        format!("{value:.2}")
    }
}

fn figures_text(f: &Figures) -> String {
    let psnr = f
        .psnr
        .map_or_else(|| "inf".to_string(), |p| format!("{p:.2}"));
    format!(
        "PSNR {psnr} dB  SSIM {:.4}  mean {:.3}  RMS {:.3}  over fail {} px ({:.3}%)  max {} @ ({}, {}, {})",
        f.ssim,
        f.mean_error,
        f.rms_error,
        f.failing_pixels,
        f.failing_percent,
        units(f.max.value),
        f.max.x,
        f.max.y,
        f.max.channel
    )
}

/// What the outcome says beyond the verdict.
pub fn outcome_text(frame: &FrameResult) -> String {
    match &frame.outcome {
        Outcome::Compared(c) => figures_text(&c.figures),
        Outcome::Mismatch(m) => m.to_string(),
        Outcome::Missing { folder } => {
            let dir = frame.paths.golden.parent().unwrap_or(Path::new("."));
            if *folder {
                format!("no golden {}", frame.paths.golden.shown())
            } else {
                format!(
                    "no golden {} (no goldens folder {}; create it with --update)",
                    frame.paths.golden.shown(),
                    dir.shown()
                )
            }
        }
        Outcome::Unreadable(message) => message.clone(),
        Outcome::Updated => format!("wrote {}", frame.paths.golden.shown()),
    }
}

fn frame_line(scene: &Path, frame: &FrameResult) -> String {
    format!(
        "{:<7} {}  frame {}  {}",
        status_word(frame.outcome.status()),
        scene.shown(),
        frame.frame,
        outcome_text(frame)
    )
}

fn detail_line(frame: &FrameResult) -> Option<String> {
    let pictures = frame.pictures.as_ref()?;
    let mut line = format!("        triptych {}", pictures.triptych.shown());
    if let Some(pending) = &frame.pending_written {
        let _ = write!(line, "; pending {}", pending.shown());
    }
    Some(line)
}

fn frame_json(scene: &Path, frame: &FrameResult) -> serde_json::Value {
    let status = frame.outcome.status();
    let mut object = json!({
        "scene": scene.display().to_string(),
        "frame": frame.frame,
        "golden": frame.paths.golden.display().to_string(),
        "verdict": status_word(status).to_lowercase(),
        "pending": frame.pending_written.as_ref().map(|p| p.display().to_string()),
        "triptych": frame.pictures.as_ref().map(|p| p.triptych.display().to_string()),
    });
    if let Outcome::Compared(c) = &frame.outcome {
        let f = &c.figures;
        let figures = json!({
            "psnr": f.psnr,
            "ssim": f.ssim,
            "mean_error": f.mean_error,
            "rms_error": f.rms_error,
            "failing_pixels": f.failing_pixels,
            "failing_percent": f.failing_percent,
            "warning_pixels": f.warning_pixels,
            "max_error": f.max.value,
            "max_x": f.max.x,
            "max_y": f.max.y,
            "max_channel": f.max.channel.letter(),
        });
        if let (Some(o), Some(extra)) = (object.as_object_mut(), figures.as_object()) {
            o.extend(extra.clone());
        }
    } else if let Some(o) = object.as_object_mut() {
        o.insert("message".into(), json!(outcome_text(frame)));
    }
    object
}

/// A folder name for a scene's pictures: its path with separators as `_`.
pub fn scene_slug(scene: &Path) -> String {
    let text = scene.with_extension("").display().to_string();
    let trimmed = text.trim_start_matches("./").trim_start_matches("../");
    trimmed
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// `--junit PATH` replaces only an earlier report: an existing file that is not JUnit XML
/// (a scene, an asset, a golden named by mistake) is refused before anything is written.
pub fn refuse_replacing_other_than_junit(path: &Path) -> anyhow::Result<()> {
    use std::io::Read as _;
    if !path.is_file() {
        return Ok(());
    }
    let mut head = Vec::new();
    lapclone::util::open_input_file(path)
        .and_then(|f| f.take(256).read_to_end(&mut head))
        .with_context(|| format!("reading {}", path.shown()))?;
    let text = String::from_utf8_lossy(&head);
    let junit = text.trim_start().starts_with("<?xml") && text.contains("<testsuites");
    if head.is_empty() || junit {
        return Ok(());
    }
    Err(UsageError(format!(
        "--junit {}: the file exists and is not a JUnit report; lapclone replaces only its own \
         reports",
        path.shown()
    ))
    .into())
}

/// `text` as XML and HTML text: markup characters escaped, and control characters (which
/// XML 1.0 cannot hold at all, even escaped; a scene error can echo them from its source
/// line) shown as `U+001B`.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\t' | '\n' | '\r' => out.push(c),
            c if c.is_control() => out.push_str(&format!("U+{:04X}", c as u32)),
            c => out.push(c),
        }
    }
    out
}

/// The HTML report: each failing or pending frame's triptych (path relative to the report)
/// with its figures; a static file, no scripts.
fn write_index(
    out: &Path,
    shown: &[(&SceneResult, &FrameResult)],
    counts: &Counts,
) -> anyhow::Result<()> {
    let mut html = String::from(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>lapclone test</title>\n\
         <style>body{font-family:sans-serif;background:#222;color:#eee}\
         img{max-width:100%;image-rendering:pixelated}section{margin:2em 0}\
         .FAIL{color:#f66}.NEW{color:#6cf}</style></head><body>\n",
    );
    let _ = writeln!(
        html,
        "<h1>lapclone test</h1><p>{}</p>",
        escape(&summary_line(counts, 0.0).replace(", 0.00 s", ""))
    );
    if shown.is_empty() {
        html.push_str("<p>No failing or new frames.</p>\n");
    }
    for (scene, frame) in shown {
        let Some(pictures) = &frame.pictures else {
            continue;
        };
        let status = status_word(frame.outcome.status());
        let image = pictures
            .triptych
            .strip_prefix(out)
            .unwrap_or(&pictures.triptych);
        let _ = writeln!(
            html,
            "<section><h2 class=\"{status}\">{status} {} — frame {}</h2>\n<p>{}</p>\n\
             <p>golden {}{}</p>\n<p>expected | difference | actual</p>\
             <a href=\"{src}\"><img src=\"{src}\" alt=\"expected | difference | actual\"></a></section>",
            escape(&scene.scene.display().to_string()),
            frame.frame,
            escape(&outcome_text(frame)),
            escape(&frame.paths.golden.display().to_string()),
            frame
                .pending_written
                .as_ref()
                .map(|p| format!("; pending {}", escape(&p.display().to_string())))
                .unwrap_or_default(),
            src = escape(&image.display().to_string().replace('\\', "/")),
        );
    }
    html.push_str("</body></html>\n");
    super::test_args::write_file(&out.join("index.html"), html.as_bytes())
}

/// JUnit XML: a suite per scene, a case per frame; a scene that did not load or render is
/// an `<error>` case of its suite.
pub fn junit_xml(results: &[SceneResult], counts: &Counts, seconds: f64) -> String {
    let mut xml = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        xml,
        "<testsuites name=\"lapclone test\" tests=\"{}\" failures=\"{}\" errors=\"{}\" time=\"{seconds:.3}\">",
        counts.frames + counts.errors,
        counts.failed + counts.new,
        counts.errors
    );
    for result in results {
        let name = escape(&result.scene.display().to_string());
        let failures = result
            .frames
            .iter()
            .filter(|f| matches!(f.outcome.status(), Status::Fail | Status::New))
            .count();
        let errors = usize::from(result.failure.is_some());
        let _ = writeln!(
            xml,
            "  <testsuite name=\"{name}\" tests=\"{}\" failures=\"{failures}\" errors=\"{errors}\" skipped=\"0\" time=\"{:.3}\">",
            result.frames.len() + errors,
            result.seconds
        );
        for frame in &result.frames {
            junit_case(&mut xml, &name, frame);
        }
        if let Some(failure) = &result.failure {
            let message = escape(&failure.message);
            let _ = writeln!(
                xml,
                "    <testcase classname=\"{name}\" name=\"scene\" time=\"0\">\n      <error message=\"{message}\" type=\"SceneError\">{message}</error>\n    </testcase>"
            );
        }
        xml.push_str("  </testsuite>\n");
    }
    xml.push_str("</testsuites>\n");
    xml
}

fn junit_case(xml: &mut String, suite: &str, frame: &FrameResult) {
    let _ = write!(
        xml,
        "    <testcase classname=\"{suite}\" name=\"frame {}\" time=\"{:.3}\"",
        frame.frame, frame.seconds
    );
    let status = frame.outcome.status();
    if matches!(status, Status::Fail | Status::New) {
        let message = escape(&format!("{} {}", status_word(status), outcome_text(frame)));
        let body = escape(&format!(
            "{}\ngolden: {}\ntriptych: {}",
            outcome_text(frame),
            frame.paths.golden.display(),
            frame
                .pictures
                .as_ref()
                .map(|p| p.triptych.display().to_string())
                .unwrap_or_default()
        ));
        let _ = write!(
            xml,
            ">\n      <failure message=\"{message}\" type=\"{}\">{body}</failure>\n    </testcase>\n",
            status_word(status)
        );
    } else {
        xml.push_str("/>\n");
    }
}
