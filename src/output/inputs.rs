//! The files a command reads, and the refusal of an output that is one of them: takes a
//! loaded scene (with its imports) or a command's input paths and an output path, and
//! gives an error naming the input when writing the output would replace it. Files are
//! compared by identity (links and hard links followed, `util::same_file`), so an output
//! path cannot reach an input through another spelling of it.

use crate::util::ShowPath;
use std::path::{Path, PathBuf};

use super::{foreign_frames, OutputError, OutputKind};
use crate::pixels::footage::Pattern;
use crate::scene::{Background, Footage, FootageSource, Scene, Shape};
use crate::script::LoadedScene;
use crate::util::{folder_of, same_file};

/// Something a command reads: a file, or the files of a numbered sequence (every file its
/// pattern names is footage, including plates outside the frames one command reads).
enum Input {
    File(PathBuf),
    Sequence(Pattern),
}

impl Input {
    /// Whether writing `path` would replace this input or one of its files: for a sequence,
    /// also a plate it names that does not exist yet, and the plate a link leads to (an
    /// output is written through a link to its target).
    fn covers(&self, path: &Path) -> bool {
        match self {
            Input::File(file) => same_file(file, path),
            Input::Sequence(pattern) => {
                let target = path.canonicalize().ok();
                std::iter::once(path)
                    .chain(target.as_deref())
                    .any(|p| names_plate(pattern, p))
            }
        }
    }

    fn describe(&self) -> String {
        match self {
            Input::File(file) => file.shown().to_string(),
            Input::Sequence(pattern) => pattern.text().to_string(),
        }
    }
}

/// Whether `path` is a plate of `pattern`: a name it numbers, in its folder.
fn names_plate(pattern: &Pattern, path: &Path) -> bool {
    let Some(name) = path.file_name() else {
        return false;
    };
    pattern.number_of(&name.to_string_lossy()).is_some()
        && same_file(folder_of(&pattern.path(0)), folder_of(path))
}

/// What `footage` reads: its video, or every plate its pattern names.
fn footage_input(footage: &Footage) -> Input {
    match &footage.source {
        FootageSource::Sequence { pattern, .. } => Input::Sequence(pattern.clone()),
        FootageSource::Video(path) => Input::File(path.clone()),
    }
}

/// Every file the scene's render reads: the scene file, then [`script_reads`].
fn scene_inputs(loaded: &LoadedScene, imports: &[PathBuf]) -> Vec<Input> {
    let mut inputs = vec![Input::File(loaded.file.clone())];
    inputs.extend(script_reads(loaded, imports));
    inputs
}

/// What running the scene's text reads besides the text itself: the files `track_keys`
/// read, then [`scene_reads`].
fn script_reads(loaded: &LoadedScene, imports: &[PathBuf]) -> Vec<Input> {
    let mut inputs: Vec<Input> = loaded.origins.read.iter().cloned().map(Input::File).collect();
    inputs.extend(scene_reads(&loaded.scene, imports));
    inputs
}

/// The files `scene` reads and its `imports`: images, plates, videos and the track files
/// patches follow.
fn scene_reads(scene: &Scene, imports: &[PathBuf]) -> Vec<Input> {
    let mut inputs: Vec<Input> = imports.iter().cloned().map(Input::File).collect();
    match &scene.canvas.background {
        Background::Image(path) => inputs.push(Input::File(path.clone())),
        Background::Footage(f) => inputs.push(footage_input(f)),
        Background::Colour(_) => {}
    }
    for patch in &scene.patches {
        inputs.push(Input::File(patch.source.clone()));
        if let Some(f) = &patch.footage {
            inputs.push(footage_input(f));
        }
        if let Shape::Mask(mask) = &patch.shape {
            inputs.push(Input::File(mask.clone()));
        }
        inputs.extend(patch.follows.iter().map(|f| Input::File(f.file.clone())));
    }
    inputs
}

/// Refuses a render's output (of `kind`) that is one of its scene's inputs: a file, or for
/// a PNG folder a frame file in it that an input sequence shows (a render would replace it,
/// or `--force` remove it). `render` and the REPL's `:render` both ask here.
pub fn refuse_render_input(
    kind: OutputKind,
    output: &Path,
    loaded: &LoadedScene,
    imports: &[PathBuf],
) -> Result<(), OutputError> {
    if kind != OutputKind::PngFolder {
        return refuse_scene_input(output, loaded, imports);
    }
    if !output.is_dir() {
        return Ok(());
    }
    let frames = foreign_frames(output, |_| false).unwrap_or_default();
    refuse_replacing(&frames, loaded, imports)
}

/// Refuses a file output (`-o`) that is one of the scene's inputs.
pub fn refuse_scene_input(
    output: &Path,
    loaded: &LoadedScene,
    imports: &[PathBuf],
) -> Result<(), OutputError> {
    if output.as_os_str() == "-" {
        return Ok(());
    }
    refuse_replacing(&[output.to_path_buf()], loaded, imports)
}

fn refuse_replacing(
    files: &[PathBuf],
    loaded: &LoadedScene,
    imports: &[PathBuf],
) -> Result<(), OutputError> {
    let inputs = scene_inputs(loaded, imports);
    for file in files {
        if let Some(input) = inputs.iter().find(|input| input.covers(file)) {
            return Err(overwrite(file, &input.describe()));
        }
    }
    Ok(())
}

/// Refuses an output that is a file the `loaded` scene reads (an image, a plate, a video,
/// a track file, one read by `track_keys`) or one of its `imports`. The scene text's own
/// file is not among them: a session saving its scene writes that file.
pub fn refuse_scene_reads(
    output: &Path,
    loaded: &LoadedScene,
    imports: &[PathBuf],
) -> Result<(), OutputError> {
    match script_reads(loaded, imports).iter().find(|i| i.covers(output)) {
        Some(input) => Err(overwrite(output, &input.describe())),
        None => Ok(()),
    }
}

/// Refuses an output that is `footage`'s video or any plate its pattern names.
pub fn refuse_footage_input(output: &Path, footage: &Footage) -> Result<(), OutputError> {
    let input = footage_input(footage);
    match input.covers(output) {
        true => Err(overwrite(output, &input.describe())),
        false => Ok(()),
    }
}

/// Refuses an output that is one of `inputs` (a command's input files).
pub fn refuse_input(output: &Path, inputs: &[&Path]) -> Result<(), OutputError> {
    match inputs.iter().find(|input| same_file(input, output)) {
        Some(input) => Err(overwrite(output, &input.shown().to_string())),
        None => Ok(()),
    }
}

fn overwrite(output: &Path, input: &str) -> OutputError {
    OutputError::ReplacesInput {
        output: output.to_path_buf(),
        input: input.to_string(),
    }
}
