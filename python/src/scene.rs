//! `lapclone.Scene`: takes a `.rhai` scene file, opens it as `lapclone render` does (errors
//! become `lapclone.SceneError` with the file, line and column, or `FileNotFoundError`) and
//! gives its frames as arrays: H×W×4 RGBA (or BGRA), `uint8`, or `uint16` for a 16-bit
//! canvas, the samples `lapclone render` writes to its PNG frames; `.render(path, format)`
//! writes them to files through the library's output stage, as `lapclone render` does.
//! Ctrl-C (any exception a signal handler raises) stops a render after the frame in
//! progress, its output removed, and stops iterating between frames.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use lapclone::{Depth, LoadedScene, OutputKind, RenderOptions, Renderer};
use pyo3::exceptions::{
    PyFileNotFoundError, PyIndexError, PyIsADirectoryError, PyOSError, PyRuntimeError, PyValueError,
};
use pyo3::prelude::*;

use crate::arrays::{self, Dtype, Layout};
use crate::errors::{output_error, scene_error, FrameIndex};

/// Scene(path, *, bgr=False)
///
/// A `.rhai` scene file, opened as `lapclone render` opens it: `len()`, `.fps`, `.size`,
/// `.frame(i)` (an H×W×4 RGBA array, BGRA with `bgr=True`), indexing, iteration and
/// `.render(path, format=None)` (files, as `lapclone render -o path` writes them).
/// FileNotFoundError for a missing file, lapclone.SceneError (file, line, column) for an
/// error in it.
#[pyclass(module = "lapclone", frozen)]
pub struct Scene {
    renderer: Mutex<Renderer>,
    loaded: LoadedScene,
    /// The module files the scene imported: inputs an output must not replace.
    imports: Vec<PathBuf>,
    path: PathBuf,
    frames: u64,
    fps: f64,
    width: u32,
    height: u32,
    bgr: bool,
}

#[pymethods]
impl Scene {
    #[new]
    #[pyo3(signature = (path, *, bgr=false))]
    fn new(py: Python<'_>, path: PathBuf, bgr: bool) -> PyResult<Self> {
        if path.is_dir() {
            return Err(PyIsADirectoryError::new_err((
                21,
                format!("{} is a folder, not a scene file", path.display()),
                path.display().to_string(),
            )));
        }
        if !path.exists() {
            return Err(PyFileNotFoundError::new_err((
                2,
                format!("no scene file {}", path.display()),
                path.display().to_string(),
            )));
        }
        if let Some(kind) = lapclone::not_a_file(&path) {
            return Err(PyValueError::new_err(format!("{} {kind}", path.display())));
        }
        // A scene file can run for a long while (up to its time limit): Ctrl-C stops it.
        let cancel = Arc::new(AtomicBool::new(false));
        let (opened, interrupt) = until_signal(py, &cancel, || {
            let (loaded, imports) = lapclone::load_scene_cancellable(&path, cancel.clone())?;
            let renderer = lapclone::build_renderer(&loaded)?;
            Ok::<_, lapclone::SceneError>((loaded, imports, renderer))
        })?;
        if let Some(interrupt) = interrupt {
            return Err(interrupt);
        }
        let (loaded, imports, renderer) = match opened {
            Ok(opened) => opened,
            Err(error) => return Err(scene_error(py, &error)?),
        };
        let canvas = &loaded.scene.canvas;
        Ok(Scene {
            frames: renderer.frame_count(),
            fps: canvas.fps,
            width: canvas.width,
            height: canvas.height,
            renderer: Mutex::new(renderer),
            loaded,
            imports,
            path,
            bgr,
        })
    }

    /// Number of frames: ⌈duration · fps⌉.
    fn __len__(&self) -> usize {
        self.frames as usize
    }

    /// Frames per second.
    #[getter]
    fn fps(&self) -> f64 {
        self.fps
    }

    /// (width, height) in pixels.
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The scene file.
    #[getter]
    fn path(&self) -> String {
        self.path.display().to_string()
    }

    /// Frame `index` (from 0; negative counts from the end) as an H×W×4 array.
    fn frame<'py>(&self, py: Python<'py>, index: FrameIndex) -> PyResult<Bound<'py, PyAny>> {
        let index = index.0;
        let frames = self.frames as i64;
        let i = if index < 0 { index + frames } else { index };
        if !(0..frames).contains(&i) {
            return Err(PyIndexError::new_err(format!(
                "frame {index} is out of range: the scene has {frames} frames"
            )));
        }
        // A renderer's error is a SceneError at its call, as `render` raises it.
        let rendered = py.allow_threads(|| {
            let mut renderer = self.renderer()?;
            let format = renderer.output_format();
            Ok::<_, PyErr>(match renderer.render_frame(i as u64) {
                Ok(canvas) => Ok((canvas.samples(format), canvas.depth())),
                Err(e) => Err(lapclone::scene_render_error(&self.loaded, &e)),
            })
        })?;
        let (samples, depth) = rendered.map_err(|e| scene_error(py, &e).unwrap_or_else(|e| e))?;
        let layout = Layout {
            height: self.height as usize,
            width: self.width as usize,
            channels: Some(4),
            dtype: match depth {
                Depth::Eight => Dtype::U8,
                Depth::Sixteen => Dtype::U16,
            },
        };
        arrays::new_array(py, samples, &layout, self.bgr)
    }

    /// Renders every frame to `path` as `lapclone render -o path [--format format]` does,
    /// byte for byte, and returns the path written. `format` is "png" (a folder of
    /// frame_NNNN.png), "gif", "apng", "y4m", "mp4", "webm" or "mov" (the last three through
    /// ffmpeg); without it, the path's extension names the format (no extension, or .png: a
    /// folder). The GIL is released while it renders. Ctrl-C stops it after the frame in
    /// progress: KeyboardInterrupt is raised and nothing is written (one that comes once the
    /// output is finished carries a note naming it).
    #[pyo3(signature = (path, format=None, *, force=false))]
    fn render(
        &self,
        py: Python<'_>,
        path: PathBuf,
        format: Option<&str>,
        force: bool,
    ) -> PyResult<String> {
        if path.as_os_str().is_empty() {
            return Err(PyValueError::new_err("the output path is empty"));
        }
        if path.as_os_str() == "-" {
            python_stdout_is_fd_1(py)?;
        }
        let format = format
            .map(OutputKind::from_name)
            .transpose()
            .map_err(|e| output_error(py, e))?;
        let cancel = Arc::new(AtomicBool::new(false));
        let mut options = RenderOptions {
            format,
            cancel: Some(cancel.clone()),
            ..RenderOptions::default()
        };
        options.settings.force = force;
        let (rendered, interrupt) = until_signal(py, &cancel, || {
            let mut renderer = self.renderer()?;
            Ok::<_, PyErr>(lapclone::render_scene(
                &self.loaded,
                &self.imports,
                &mut renderer,
                &path,
                &options,
                &mut (),
            ))
        })?;
        match (rendered?, interrupt) {
            (Ok(rendered), None) => Ok(rendered.path.display().to_string()),
            (Err(error), None) => Err(output_error(py, error)),
            // The render had finished when Ctrl-C came: the output is whole and kept, and
            // the interrupt says so rather than leave the user to think it went.
            (Ok(rendered), Some(interrupt)) => {
                let note = format!(
                    "the render had already finished: {} was written",
                    rendered.path.display()
                );
                let _ = interrupt.value(py).call_method1("add_note", (note,));
                Err(interrupt)
            }
            (Err(_), Some(interrupt)) => Err(interrupt),
        }
    }

    fn __getitem__<'py>(&self, py: Python<'py>, index: FrameIndex) -> PyResult<Bound<'py, PyAny>> {
        self.frame(py, index)
    }

    fn __iter__(slf: Py<Self>) -> SceneFrames {
        SceneFrames {
            scene: slf,
            next: AtomicU64::new(0),
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "lapclone.Scene({:?}, frames={}, fps={}, size=({}, {}))",
            self.path.display().to_string(),
            self.frames,
            self.fps,
            self.width,
            self.height
        )
    }
}

/// The frames of a scene, in order. Threads sharing one iterator each get the next frame
/// not yet given out, as a queue would.
#[pyclass(module = "lapclone", frozen)]
pub struct SceneFrames {
    scene: Py<Scene>,
    next: AtomicU64,
}

impl Scene {
    /// The scene's renderer. A frame that panicked may have left its incremental state (its
    /// factor updates, its dirty rectangles) half-done: refuse rather than draw wrong.
    fn renderer(&self) -> PyResult<std::sync::MutexGuard<'_, Renderer>> {
        self.renderer.lock().map_err(|_| {
            PyRuntimeError::new_err(
                "an earlier frame of this scene failed part-way: open the scene again",
            )
        })
    }
}

#[pymethods]
impl SceneFrames {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let scene = self.scene.get();
        // `list(scene)` runs no Python between frames, so nothing else would look for Ctrl-C.
        py.check_signals()?;
        // Taken before the frame is drawn (the GIL is released meanwhile); a frame that
        // fails is not given again, as a failed `next` of a generator is not.
        let taken = self
            .next
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| {
                (n < scene.frames).then_some(n + 1)
            });
        match taken {
            Ok(index) => scene.frame(py, FrameIndex(index as i64)).map(Some),
            Err(_) => Ok(None),
        }
    }
}

/// `render("-")` writes to file descriptor 1: refused unless Python's `sys.stdout` is that
/// descriptor (with it closed at start, `sys.stdout` is None and the next file opened takes
/// descriptor 1; a notebook's `sys.stdout` is no descriptor at all), else flushed first, so
/// what Python printed comes before the frames.
fn python_stdout_is_fd_1(py: Python<'_>) -> PyResult<()> {
    let stdout = py.import("sys")?.getattr("stdout")?;
    let descriptor = match stdout.is_none() {
        true => None,
        false => stdout
            .call_method0("fileno")
            .and_then(|fd| fd.extract::<i64>())
            .ok(),
    };
    if descriptor != Some(1) {
        return Err(PyValueError::new_err(
            "render(\"-\"): Python's standard output (sys.stdout) is not file descriptor 1 \
             (it is closed, or replaced): the frames would go elsewhere; render to a file",
        ));
    }
    stdout.call_method0("flush")?;
    Ok(())
}

/// How often a render's caller looks for a signal while the render runs.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Runs `work` on a thread of its own, with the GIL released, while this thread runs
/// Python's signal handlers every [`SIGNAL_POLL`] (they only run on the main thread, and
/// only while it holds the GIL), and once more when `work` is done. When a handler raises
/// (KeyboardInterrupt for Ctrl-C), `cancel` is raised and `work` is waited for (a render
/// stops after the frame in progress and removes its output). Gives `work`'s result and the
/// handler's exception, if one raised: the caller tells a render stopped from one that had
/// finished when the signal came.
fn until_signal<T: Send>(
    py: Python<'_>,
    cancel: &AtomicBool,
    work: impl FnOnce() -> T + Send,
) -> PyResult<(T, Option<PyErr>)> {
    std::thread::scope(|scope| {
        // The sender is dropped when `work` returns or unwinds: the wait below then ends.
        let (running, finished) = mpsc::channel::<()>();
        let worker = std::thread::Builder::new()
            .name("lapclone render".into())
            .spawn_scoped(scope, move || {
                let _running = running;
                work()
            })
            .map_err(|e| PyOSError::new_err(format!("cannot start the render thread: {e}")))?;
        let mut interrupt = None;
        let mut finished = finished;
        loop {
            // The receiver goes to the GIL-free wait and back (it cannot be shared).
            let waited = py.allow_threads(move || {
                let waited = finished.recv_timeout(SIGNAL_POLL);
                (finished, waited)
            });
            finished = waited.0;
            let done = waited.1 != Err(RecvTimeoutError::Timeout);
            if interrupt.is_none() {
                if let Err(error) = py.check_signals() {
                    cancel.store(true, Ordering::Relaxed);
                    interrupt = Some(error);
                }
            }
            if done {
                break;
            }
        }
        // `work` has returned or unwound: the join waits only for its thread to end.
        let result = worker
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        Ok((result, interrupt))
    })
}
