//! Pending golden frames: takes scene paths (files or folders) and gives `--accept`
//! (each `frame_NNNN.new.png` renamed onto its `frame_NNNN.png`), `--reject` (each deleted)
//! and `--review` (each shown with its figures and triptych — inline where the terminal can
//! show images — and accepted, rejected or skipped as the user answers).

use lapclone::util::ShowPath;
use std::io::{BufRead, IsTerminal as _, Write as _};
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use lapclone::golden::{compare, triptych, GoldenFrame, Thresholds};

use super::test_args::{
    check_golden_dirs, check_own_file, find_scenes, golden_dir, is_link, remove_if_present,
    write_file, TestArgs,
};
use super::test_report::scene_slug;

pub fn run(args: &TestArgs, paths: &[PathBuf]) -> anyhow::Result<()> {
    act(args, paths)?;
    super::stdout_failure()
}

fn act(args: &TestArgs, paths: &[PathBuf]) -> anyhow::Result<()> {
    let pending = find_pending(args, paths)?;
    if pending.is_empty() {
        super::print_line(format_args!("no pending frames under {}", list(paths)));
        return Ok(());
    }
    if args.review {
        // A pending frame lies in `<goldens>/<scene>/`.
        let roots = pending
            .iter()
            .filter_map(|f| Some(f.parent()?.parent()?.to_path_buf()));
        super::test_args::check_out_beside_goldens(args, roots)?;
        return review(args, &pending);
    }
    // A file that cannot be taken is reported and the others are still taken.
    let mut failed = 0;
    for file in &pending {
        let done = if args.accept {
            accept(file).map(|()| format!("accepted {}", golden_of(file).shown()))
        } else {
            remove_if_present(file).map(|()| format!("rejected {}", file.shown()))
        };
        match done {
            Ok(line) => super::print_line(line),
            Err(error) => {
                eprint_line!("{}", super::describe(&error));
                failed += 1;
            }
        }
    }
    match failed {
        0 => Ok(()),
        n => anyhow::bail!("{n} of {} pending frame(s) not taken", pending.len()),
    }
}

fn list(paths: &[PathBuf]) -> String {
    let names: Vec<String> = paths.iter().map(|p| p.shown().to_string()).collect();
    names.join(", ")
}

/// `frame_NNNN.new.png` → `frame_NNNN.png`.
pub fn golden_of(pending: &Path) -> PathBuf {
    let name = pending.file_name().unwrap_or_default().to_string_lossy();
    pending.with_file_name(name.replace(".new.png", ".png"))
}

fn is_pending_name(name: &str) -> bool {
    name.strip_prefix("frame_")
        .and_then(|rest| rest.strip_suffix(".new.png"))
        .is_some_and(|digits| !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()))
}

/// Pending files in the golden folders of the scenes under `paths` and in any other
/// `goldens/<name>/` folder under the folders given (a renamed scene's), sorted. Nowhere
/// else: a `frame_0001.new.png` among a scene's assets is not lapclone's to accept.
fn find_pending(args: &TestArgs, paths: &[PathBuf]) -> anyhow::Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    for path in paths.iter().filter(|p| p.is_dir()) {
        walk(path, &args.out_dir(), &mut found)?;
    }
    let scenes = find_scenes(paths, &args.out_dir())?;
    check_golden_dirs(&scenes, args.goldens.as_deref())?;
    for scene in scenes {
        let dir = golden_dir(&scene, args.goldens.as_deref());
        if dir.is_dir() {
            collect_in(&dir, &mut found)?;
        }
    }
    found.sort();
    found.dedup();
    Ok(found)
}

fn collect_in(dir: &Path, found: &mut Vec<PathBuf>) -> anyhow::Result<()> {
    for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.shown()))? {
        let path = entry?.path();
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        if path.is_file() && is_pending_name(&name) {
            found.push(tidy(&path));
        }
    }
    Ok(())
}

fn walk(dir: &Path, out: &Path, found: &mut Vec<PathBuf>) -> anyhow::Result<()> {
    let parent = dir.parent().and_then(Path::file_name);
    if parent.is_some_and(|p| p == "goldens") {
        collect_in(dir, found)?;
    }
    for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.shown()))? {
        let path = entry?.path();
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        let skipped =
            name.starts_with('.') || name == "target" || is_link(&path) || tidy(&path) == tidy(out);
        if path.is_dir() && !skipped {
            walk(&path, out, found)?;
        }
    }
    Ok(())
}

/// The path without `.` components, so one file found two ways is listed once.
fn tidy(path: &Path) -> PathBuf {
    path.components()
        .filter(|c| !matches!(c, std::path::Component::CurDir))
        .collect()
}

fn accept(pending: &Path) -> anyhow::Result<()> {
    let golden = golden_of(pending);
    check_own_file(pending)?;
    check_own_file(&golden)?;
    // A golden must be a frame: a pending file that does not decode is not promoted.
    GoldenFrame::load(pending).with_context(|| format!("not accepted: {}", pending.shown()))?;
    std::fs::rename(pending, &golden)
        .with_context(|| format!("renaming {} to {}", pending.shown(), golden.shown()))
}

/// Asks about each pending frame in turn; end of input skips the rest.
fn review(args: &TestArgs, pending: &[PathBuf]) -> anyhow::Result<()> {
    let stdin = std::io::stdin();
    let mut lines = stdin.lock().lines();
    let (mut accepted, mut rejected, mut skipped) = (0, 0, 0);
    for (index, file) in pending.iter().enumerate() {
        super::print_line(format_args!(
            "[{}/{}] {}",
            index + 1,
            pending.len(),
            file.shown()
        ));
        if let Err(error) = show(args, file) {
            // One unreadable pending file is reported and passed over, not the end of the
            // review: the others may still be looked at.
            super::print_line(format_args!("  skipped: {}", super::describe(&error)));
            skipped += 1;
            continue;
        }
        let answer = ask(&mut lines)?;
        match answer.as_str() {
            "a" => {
                accept(file)?;
                accepted += 1;
                super::print_line(format_args!("accepted {}", golden_of(file).shown()));
            }
            "r" => {
                remove_if_present(file)?;
                rejected += 1;
                super::print_line(format_args!("rejected {}", file.shown()));
            }
            "s" => skipped += 1,
            _ => {
                skipped += pending.len() - index;
                super::print_line("");
                break;
            }
        }
    }
    super::print_line(format_args!(
        "review: {accepted} accepted, {rejected} rejected, {skipped} skipped"
    ));
    Ok(())
}

/// The next answer (`a`, `r`, `s` or `q`) read from `lines`, asking until one comes; `q` at
/// the end of the input.
fn ask(lines: &mut impl Iterator<Item = std::io::Result<String>>) -> anyhow::Result<String> {
    loop {
        print!("accept, reject or skip? [a/r/s/q] ");
        let _ = std::io::stdout().flush();
        let Some(line) = lines.next() else {
            return Ok("q".to_string());
        };
        let line = match line {
            Ok(line) => line,
            // An answer that is not UTF-8 is no answer (its bytes are read): ask again.
            Err(e) if e.kind() == std::io::ErrorKind::InvalidData => continue,
            Err(e) => return Err(e).context("reading the answer"),
        };
        if !std::io::stdin().is_terminal() {
            super::print_line(format_args!("{}", line.trim()));
        }
        let word = line.trim().to_lowercase();
        if ["a", "r", "s", "q"].contains(&word.as_str()) {
            return Ok(word);
        }
    }
}

/// Prints the figures against the current golden and shows (or names) the triptych.
fn show(args: &TestArgs, file: &Path) -> anyhow::Result<()> {
    let actual = GoldenFrame::load(file)?;
    let golden_path = golden_of(file);
    let expected = if golden_path.is_file() {
        match GoldenFrame::load(&golden_path) {
            Ok(frame) => Some(frame),
            Err(error) => {
                super::print_line(format_args!("  golden unreadable: {error}"));
                None
            }
        }
    } else {
        super::print_line(format_args!("  new: no golden {}", golden_path.shown()));
        None
    };
    let thresholds = super::test_args::overrides(args, Thresholds::default());
    if let Some(expected) = &expected {
        match compare(expected, &actual, &thresholds) {
            Ok(c) => super::print_line(format_args!(
                "  max {} @ ({}, {}, {}), {} px over {} ({:.3}%), PSNR {}, SSIM {:.4}",
                c.figures.max.value,
                c.figures.max.x,
                c.figures.max.y,
                c.figures.max.channel,
                c.figures.failing_pixels,
                thresholds.fail,
                c.figures.failing_percent,
                c.figures
                    .psnr
                    .map_or_else(|| "inf".into(), |p| format!("{p:.2} dB")),
                c.figures.ssim
            )),
            Err(mismatch) => super::print_line(format_args!("  {mismatch}")),
        }
    }
    let sheet = triptych(expected.as_ref(), &actual, &thresholds);
    if super::repl::show_picture(&sheet) {
        return Ok(());
    }
    let Some(dir) = args.report_dir() else {
        super::print_line("  (no picture: CI is set and --out was not given)");
        return Ok(());
    };
    let name = format!("{}.png", scene_slug(&file.with_extension("")));
    let path = dir.join("review").join(name);
    write_file(&path, &lapclone::golden::encode_rgba_png(&sheet))?;
    super::print_line(format_args!(
        "  expected | difference | actual: {}",
        path.shown()
    ));
    Ok(())
}
