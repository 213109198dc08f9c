//! Small helpers shared by every stage: the one rule for output files ([`TempOutput`]: a
//! temporary file in the destination folder, then a rename, so a failure never leaves a
//! partial file; streams written through, nothing else replaced, a FIFO's reader waited for
//! only until the program is interrupted), whether two paths name one
//! file, a lock that survives poisoning, finding an external program (ffmpeg) on `PATH`, and
//! the number of cores this process may use.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, Weak};
#[cfg(unix)]
use std::time::Duration;

/// Locks `mutex`, also when a panicking thread poisoned it: every user here keeps its data
/// whole under the lock (a queue position, a finished entry, a hand-off state).
pub(crate) fn lock<T: ?Sized>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// What to tell a user who asked for something that needs ffmpeg when it is not installed.
pub const FFMPEG_MISSING: &str = "ffmpeg not found on PATH: install it (for example: apt-get install ffmpeg) or use --format png|gif|apng|y4m";

/// What to tell a user whose scene reads video footage when ffmpeg or ffprobe is missing.
pub const FFMPEG_MISSING_FOR_FOOTAGE: &str = "ffmpeg and ffprobe not found on PATH: reading video footage needs them; install ffmpeg (for example: apt-get install ffmpeg) or use numbered image files (frame_%04d.png)";

/// Cores available to this process (1 if unknown), looked up once.
pub fn available_cores() -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// The first executable file called `name` in a folder of `PATH` (on Windows also `name`
/// with an extension of `PATHEXT`, such as `ffmpeg.exe`).
pub fn find_program(name: &str) -> Option<PathBuf> {
    find_program_in(name, &std::env::var_os("PATH")?)
}

/// [`find_program`] over the folders of `search`, a `PATH`-style list.
pub fn find_program_in(name: &str, search: &std::ffi::OsStr) -> Option<PathBuf> {
    let cwd = std::env::current_dir().ok()?;
    which::which_in(name, Some(search), cwd).ok()
}

/// Writes `line` and a newline to standard error, dropping them when it is closed or full:
/// a message is not worth a crash. Called through `eprint_line!`. Control characters a
/// message quotes (a scene's `throw` text, a file name) are shown escaped, so quoting them
/// cannot move the cursor, clear the terminal or retitle its window.
pub fn stderr_line(line: std::fmt::Arguments) {
    let _ = writeln!(std::io::stderr().lock(), "{}", visible_controls(&line.to_string()));
}

/// How messages name a path: `path.shown()` where `path.display()` would split a message.
pub trait ShowPath {
    /// The path as a message shows it: as it is, or, when it holds a newline or another
    /// control character, as a quoted string with Rust's escapes (`"bad\nname.rhai"`), so
    /// that the message stays on its line (`file:line:col: …` included) and the name can be
    /// read back.
    fn shown(&self) -> ShownPath<'_>;
}

impl ShowPath for Path {
    fn shown(&self) -> ShownPath<'_> {
        ShownPath(self)
    }
}

/// A path as messages show it ([`ShowPath::shown`]).
pub struct ShownPath<'a>(&'a Path);

impl std::fmt::Display for ShownPath<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let text = self.0.to_string_lossy();
        if text.contains(char::is_control) {
            write!(f, "{text:?}")
        } else {
            f.write_str(&text)
        }
    }
}

/// Whether a message shows `c` escaped: a control character but newline and tab, or one
/// that changes the direction of the text after it (which would reorder the rest of the
/// line on a terminal).
pub fn is_hidden_char(c: char) -> bool {
    let bidi = matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}' | '\u{200e}' | '\u{200f}' | '\u{061c}');
    (c.is_control() && c != '\n' && c != '\t') || bidi
}

/// `text` with every [`is_hidden_char`] written as `\u{..}`.
pub fn visible_controls(text: &str) -> std::borrow::Cow<'_, str> {
    let hidden = is_hidden_char;
    if !text.contains(hidden) {
        return text.into();
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if hidden(c) {
            out.push_str(&c.escape_unicode().to_string());
        } else {
            out.push(c);
        }
    }
    out.into()
}

/// Writes `bytes` to `path` by the one output rule ([`TempOutput`]).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomic_with(path, |file| file.write_all(bytes))
}

/// Calls `fill` with the file [`TempOutput`] gives for `path`, then commits it. On any error
/// the temporary file is removed and `path` is untouched.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> std::io::Result<()> {
    write_staged(path, fill)?.commit()
}

/// Calls `fill` with the file [`TempOutput`] gives for `path` and syncs it, leaving the
/// commit to the caller (a command writing several files renames them only once all are
/// written). Dropped uncommitted, the temporary file is removed.
pub fn write_staged(
    path: &Path,
    fill: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> std::io::Result<TempOutput> {
    let output = TempOutput::new(path)?;
    let mut file = output.open()?;
    fill(&mut file)?;
    if output.is_temporary() {
        file.sync_all()?;
    }
    Ok(output)
}

/// What an output path names, decided once before anything is written.
enum Destination {
    /// Missing, or a regular file (also through a symbolic link): written to a temporary
    /// file in the same folder, renamed over it at the end.
    Replace(PathBuf),
    /// A FIFO or a character device (`/dev/null`, a terminal): the user asked for a stream,
    /// so it is written through and never unlinked.
    Through(PathBuf),
}

/// Whether `path` may be written as an output (missing, a regular file, a FIFO or a
/// character device), for a command that writes it only after long work: the error says
/// what it is otherwise, as [`TempOutput::new`] would at the end.
pub fn check_destination(path: &Path) -> std::io::Result<()> {
    destination(path).map(drop)
}

/// Why an output path is refused before anything is written.
fn refuse(what: &str) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!(
            "it is {what}; lapclone writes only regular files, FIFOs and character devices, and never replaces anything else"
        ),
    )
}

/// Classifies `path`. A symbolic link is followed: its target is what gets written (the
/// link itself stays); a link to nothing is refused, since writing would create a file at
/// a place the command line does not show.
fn destination(path: &Path) -> std::io::Result<Destination> {
    let link = std::fs::symlink_metadata(path);
    let meta = match (&link, std::fs::metadata(path)) {
        (Err(e), _) if e.kind() == std::io::ErrorKind::NotFound => {
            return Ok(Destination::Replace(path.to_path_buf()))
        }
        (Err(e), _) => return Err(std::io::Error::new(e.kind(), e.to_string())),
        (Ok(_), Err(_)) => return Err(refuse("a symbolic link to nothing")),
        (Ok(_), Ok(meta)) => meta,
    };
    let is_link = link.is_ok_and(|m| m.file_type().is_symlink());
    match kind_of(&meta) {
        // The file the link names is replaced, not the link.
        Kind::File if is_link => Ok(Destination::Replace(path.canonicalize()?)),
        Kind::File => Ok(Destination::Replace(path.to_path_buf())),
        // Opened by the path given, which the system follows: `/dev/stdout` on a pipe
        // links to `pipe:[N]`, which names nothing a path could.
        Kind::Fifo | Kind::CharDevice => Ok(Destination::Through(path.to_path_buf())),
        Kind::Folder => Err(refuse("a folder")),
        Kind::BlockDevice => Err(refuse("a block device")),
        Kind::Socket => Err(refuse("a socket")),
        Kind::Other => Err(refuse("not a regular file")),
    }
}

/// What a path names, as the output and input rules tell them apart.
#[cfg_attr(not(unix), allow(dead_code))]
enum Kind {
    File,
    Folder,
    Fifo,
    CharDevice,
    BlockDevice,
    Socket,
    Other,
}

fn kind_of(meta: &std::fs::Metadata) -> Kind {
    let kind = meta.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let special = [
            (kind.is_fifo(), Kind::Fifo),
            (kind.is_char_device(), Kind::CharDevice),
            (kind.is_block_device(), Kind::BlockDevice),
            (kind.is_socket(), Kind::Socket),
        ];
        if let Some((_, special)) = special.into_iter().find(|(is, _)| *is) {
            return special;
        }
    }
    if kind.is_file() {
        Kind::File
    } else if kind.is_dir() {
        Kind::Folder
    } else {
        Kind::Other
    }
}

/// The one way lapclone writes an output file. A regular (or missing) destination gets a
/// temporary file in its folder (`tempfile`'s unique name, so two writes of one path never
/// collide) that [`TempOutput::commit`] renames over it, and dropping it uncommitted removes
/// it: no reader ever sees a half-written output. A FIFO or character device is written
/// through, never unlinked; folders, block devices, sockets and dangling links are refused.
/// A missing parent folder is an error: lapclone never creates one.
#[derive(Debug)]
pub struct TempOutput {
    inner: Inner,
}

#[derive(Debug)]
enum Inner {
    Temporary {
        file: tempfile::NamedTempFile,
        dest: PathBuf,
    },
    Through(PathBuf),
}

impl TempOutput {
    /// Prepares writing `dest` (creates the temporary file for a regular destination).
    pub fn new(dest: &Path) -> std::io::Result<Self> {
        let inner = match destination(dest)? {
            Destination::Through(path) => Inner::Through(path),
            Destination::Replace(dest) => {
                let prefix = temp_prefix(&dest);
                let mut builder = tempfile::Builder::new();
                builder.prefix(&prefix).suffix(TEMP_SUFFIX);
                // An output is an ordinary file: the umask decides, as for any new file.
                #[cfg(unix)]
                {
                    use std::os::unix::fs::PermissionsExt;
                    builder.permissions(std::fs::Permissions::from_mode(0o666));
                }
                // Made and listed under one lock, so a stop removes every one it lets exist.
                let file = pending(|list| {
                    if list.closed {
                        let stopped = std::io::ErrorKind::Interrupted;
                        return Err(std::io::Error::new(stopped, "the program is stopping"));
                    }
                    let file = builder.tempfile_in(folder_of(&dest));
                    let file = file.map_err(|e| std::io::Error::new(e.kind(), e.to_string()))?;
                    list.files.push(file.path().to_path_buf());
                    Ok(file)
                })?;
                Inner::Temporary { file, dest }
            }
        };
        Ok(TempOutput { inner })
    }

    /// The path to write: the temporary file, or the FIFO / device itself.
    pub fn temp_path(&self) -> &Path {
        match &self.inner {
            Inner::Temporary { file, .. } => file.path(),
            Inner::Through(path) => path,
        }
    }

    /// Whether writes go to a temporary file (false: through a FIFO or device).
    pub fn is_temporary(&self) -> bool {
        matches!(self.inner, Inner::Temporary { .. })
    }

    /// Opens [`TempOutput::temp_path`] for writing.
    pub fn open(&self) -> std::io::Result<std::fs::File> {
        match &self.inner {
            Inner::Temporary { file, .. } => file.reopen(),
            Inner::Through(path) => open_through(path),
        }
    }

    /// Renames the temporary file over the destination (nothing to do for a stream).
    pub fn commit(mut self) -> std::io::Result<()> {
        let inner = std::mem::replace(&mut self.inner, Inner::Through(PathBuf::new()));
        match inner {
            Inner::Temporary { file, dest } => {
                let temp = file.path().to_path_buf();
                let result = file.persist(&dest);
                forget_pending(&temp);
                result
                    .map(drop)
                    .map_err(|e| std::io::Error::new(e.error.kind(), e.error.to_string()))
            }
            Inner::Through(_) => Ok(()),
        }
    }
}

impl Drop for TempOutput {
    fn drop(&mut self) {
        if let Inner::Temporary { file, .. } = &self.inner {
            forget_pending(file.path());
        }
    }
}

/// Opens a FIFO or device to write through. A FIFO's open waits for a program to read it,
/// as a shell's `>` does, but looks every [`FIFO_WAIT`] whether the program was interrupted
/// ([`interrupted`]): a blocking open cannot be interrupted, and a FIFO nobody reads would
/// hang the program (a REPL's `:save`) for good.
fn open_through(path: &Path) -> std::io::Result<std::fs::File> {
    #[cfg(unix)]
    {
        use rustix::fs::{fcntl_getfl, fcntl_setfl, Mode, OFlags};
        let flags = OFlags::WRONLY | OFlags::NONBLOCK | OFlags::CLOEXEC;
        loop {
            match rustix::fs::open(path, flags, Mode::empty()) {
                Ok(fd) => {
                    // Written as any file is: a full pipe waits for its reader.
                    fcntl_setfl(&fd, fcntl_getfl(&fd)? - OFlags::NONBLOCK)?;
                    return Ok(std::fs::File::from(fd));
                }
                // No reader yet (only a FIFO opened this way says so).
                Err(rustix::io::Errno::NXIO) if !interrupted() => std::thread::sleep(FIFO_WAIT),
                Err(rustix::io::Errno::NXIO) => {
                    let kind = std::io::ErrorKind::Interrupted;
                    let message = "interrupted while waiting for a program to read the FIFO";
                    return Err(std::io::Error::new(kind, message));
                }
                Err(e) => return Err(e.into()),
            }
        }
    }
    #[cfg(not(unix))]
    std::fs::OpenOptions::new().write(true).open(path)
}

/// How often a wait for a FIFO's reader looks whether the program was interrupted.
#[cfg(unix)]
const FIFO_WAIT: Duration = Duration::from_millis(20);

/// The flags that, raised, interrupt the program's waits for a FIFO's reader (a render's
/// cancel, a REPL's Ctrl-C); held weakly, so a flag dropped is forgotten.
static INTERRUPTS: Mutex<Vec<Weak<AtomicBool>>> = Mutex::new(Vec::new());

/// Lets `flag`, raised, interrupt a wait for a FIFO's reader (as long as the flag lives).
pub fn interrupt_waits_with(flag: &Arc<AtomicBool>) {
    let mut flags = lock(&INTERRUPTS);
    flags.retain(|f| f.strong_count() > 0);
    flags.push(Arc::downgrade(flag));
}

/// Whether a flag given to [`interrupt_waits_with`] is raised, or the program is stopping
/// ([`remove_pending_outputs`]).
#[cfg_attr(not(unix), allow(dead_code))]
fn interrupted() -> bool {
    let raised = lock(&INTERRUPTS)
        .iter()
        .any(|f| f.upgrade().is_some_and(|f| f.load(Ordering::Relaxed)));
    raised || pending(|list| list.closed)
}

/// The end of every temporary output's name.
pub const TEMP_SUFFIX: &str = ".tmp";

/// The start of a temporary output's name beside `dest`: `.NAME.`, the name cut (on a
/// character boundary) so that it, the random part and [`TEMP_SUFFIX`] fit the 255 bytes
/// file systems allow in a name, as `dest`'s own name does.
pub fn temp_prefix(dest: &Path) -> String {
    const MOST: usize = 200;
    let name = dest.file_name().unwrap_or_default().to_string_lossy();
    let mut end = name.len().min(MOST);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    format!(".{}.", &name[..end])
}

/// The temporary files [`TempOutput`]s are writing, so a program stopped by a signal can
/// remove them ([`remove_pending_outputs`]) instead of leaving them in the user's folders.
static PENDING: std::sync::Mutex<Pending> = std::sync::Mutex::new(Pending {
    files: Vec::new(),
    folders: Vec::new(),
    closed: false,
});

struct Pending {
    files: Vec<PathBuf>,
    /// Temporary folders ([`TempFolder`]), removed with what they hold.
    folders: Vec<PathBuf>,
    /// Set by [`remove_pending_outputs`]: no temporary file may be made after it.
    closed: bool,
}

fn pending<R>(f: impl FnOnce(&mut Pending) -> R) -> R {
    f(&mut PENDING.lock().unwrap_or_else(std::sync::PoisonError::into_inner))
}

fn forget_pending(temp: &Path) {
    pending(|list| list.files.retain(|p| p != temp));
}

/// Removes every temporary file a [`TempOutput`] is still writing and every [`TempFolder`]
/// with what it holds, and refuses new ones from then on: for a program about to exit on a
/// signal, whose writers will not finish. Gives how many were removed.
pub fn remove_pending_outputs() -> usize {
    let (files, folders) = pending(|list| {
        list.closed = true;
        (std::mem::take(&mut list.files), std::mem::take(&mut list.folders))
    });
    let files = files.iter().filter(|p| std::fs::remove_file(p).is_ok());
    // A writer finishing its frame may add a file while the folder goes: a few tries.
    let folder_gone = |p: &&PathBuf| {
        (0..FOLDER_TRIES).any(|_| {
            let gone = std::fs::remove_dir_all(p).is_ok() || !p.exists();
            if !gone {
                std::thread::sleep(std::time::Duration::from_millis(2));
            }
            gone
        })
    };
    files.count() + folders.iter().filter(folder_gone).count()
}

/// How many times a stop tries to remove a temporary folder.
const FOLDER_TRIES: usize = 20;

/// A temporary folder beside an output (a PNG sequence staged whole), listed so that a
/// program stopped by a signal removes it ([`remove_pending_outputs`]); dropped, it is
/// removed with what it holds, as `tempfile`'s `TempDir` is.
#[derive(Debug)]
pub struct TempFolder {
    dir: Option<tempfile::TempDir>,
}

impl TempFolder {
    /// Makes the folder beside `output`, named as [`TempOutput`]'s files are.
    pub fn beside(output: &Path) -> std::io::Result<Self> {
        let prefix = temp_prefix(output);
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(TEMP_SUFFIX);
        // Made and listed under one lock, so a stop removes every one it lets exist.
        let dir = pending(|list| {
            if list.closed {
                let stopped = std::io::ErrorKind::Interrupted;
                return Err(std::io::Error::new(stopped, "the program is stopping"));
            }
            let dir = builder.tempdir_in(folder_of(output))?;
            list.folders.push(dir.path().to_path_buf());
            Ok(dir)
        })?;
        Ok(TempFolder { dir: Some(dir) })
    }

    pub fn path(&self) -> &Path {
        // invariant: `dir` is taken only by `keep`, which consumes the folder.
        self.dir.as_ref().expect("a temporary folder").path()
    }

    /// Keeps the folder (no longer removed when dropped or on a stop) and gives its path.
    pub fn keep(mut self) -> PathBuf {
        // invariant: as in `path`.
        let path = self.dir.take().expect("a temporary folder").keep();
        pending(|list| list.folders.retain(|p| *p != path));
        path
    }
}

impl Drop for TempFolder {
    fn drop(&mut self) {
        if let Some(dir) = self.dir.take() {
            // Removed before it is unlisted: a stop meanwhile removes it too, instead of
            // exiting with it half gone.
            let path = dir.path().to_path_buf();
            drop(dir);
            pending(|list| list.folders.retain(|p| *p != path));
        }
    }
}

/// A number for a message: as written when short, in exponent form when huge or tiny (a
/// scene's `1e308` is not shown as 309 digits).
pub fn number_text(v: f64) -> String {
    let magnitude = v.abs();
    if magnitude != 0.0 && !(1e-4..1e7).contains(&magnitude) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// What kind of thing `path` is, for a message about an input that cannot be read as a
/// file: `None` for a regular file (also through links), else "does not exist", "is a
/// folder, not a file" or "is not a regular file (a FIFO)" and the like.
pub fn not_a_file(path: &Path) -> Option<&'static str> {
    let Ok(meta) = path.metadata() else {
        return Some(if path.symlink_metadata().is_ok() {
            "is a symbolic link to nothing"
        } else {
            "does not exist"
        });
    };
    Some(match kind_of(&meta) {
        Kind::File => return None,
        Kind::Folder => "is a folder, not a file",
        Kind::Fifo => "is not a regular file (a FIFO)",
        Kind::CharDevice | Kind::BlockDevice => "is not a regular file (a device)",
        Kind::Socket => "is not a regular file (a socket)",
        Kind::Other => "is not a regular file",
    })
}

/// An input must be a regular file: reading a FIFO or a device could wait forever, and a
/// folder is no file. The error says which of these `path` is.
pub fn check_input_file(path: &Path) -> std::io::Result<()> {
    match not_a_file(path) {
        None => Ok(()),
        Some(what) => {
            let kind = if what == "does not exist" {
                std::io::ErrorKind::NotFound
            } else {
                std::io::ErrorKind::InvalidInput
            };
            Err(std::io::Error::new(kind, format!("it {what}")))
        }
    }
}

/// Reads the regular file `path`, at most `limit` bytes: `None` when it holds more, read no
/// further than that even if it grows meanwhile. The kind of file is checked on the file
/// opened, so a FIFO or device put in its place after [`check_input_file`] cannot make the
/// read wait forever.
pub fn read_input_file(path: &Path, limit: u64) -> std::io::Result<Option<Vec<u8>>> {
    use std::io::Read as _;
    let mut bytes = Vec::new();
    open_input_file(path)?
        .take(limit.saturating_add(1))
        .read_to_end(&mut bytes)?;
    Ok((bytes.len() as u64 <= limit).then_some(bytes))
}

/// Opens the regular file `path` for reading, refusing anything else as
/// [`check_input_file`] does, also when it is swapped in between that check and the open.
pub fn open_input_file(path: &Path) -> std::io::Result<std::fs::File> {
    check_input_file(path)?;
    open_regular(path)
}

/// Opens `path` for reading if what it opens is a regular file. On Unix the open does not
/// wait for a FIFO's writer (it is refused once open instead).
fn open_regular(path: &Path) -> std::io::Result<std::fs::File> {
    #[cfg(unix)]
    let file = {
        use rustix::fs::{fcntl_getfl, fcntl_setfl, Mode, OFlags};
        let flags = OFlags::RDONLY | OFlags::NONBLOCK | OFlags::CLOEXEC;
        let fd = rustix::fs::open(path, flags, Mode::empty())?;
        // Reads block as on any file opened plainly (some file systems heed the flag).
        fcntl_setfl(&fd, fcntl_getfl(&fd)? - OFlags::NONBLOCK)?;
        std::fs::File::from(fd)
    };
    #[cfg(not(unix))]
    let file = std::fs::File::open(path)?;
    if !file.metadata()?.is_file() {
        let message = "it is not a regular file (it was replaced while being opened)";
        return Err(std::io::Error::new(std::io::ErrorKind::InvalidInput, message));
    }
    Ok(file)
}

/// The folder `path` is in (`.` for a bare file name).
pub fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

/// Whether two output paths name one file: the same existing file, or the same name in
/// the same folder (`out.png` and `./out.png`) when it does not exist yet.
pub fn same_destination(a: &Path, b: &Path) -> bool {
    if a == b || same_file(a, b) {
        return true;
    }
    let folder = |p: &Path| folder_of(p).canonicalize().ok();
    a.file_name().is_some() && a.file_name() == b.file_name() && folder(a).is_some() && folder(a) == folder(b)
}

/// Whether `a` and `b` name one existing file: after following links, and on Unix also
/// through hard links (same device and inode).
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (a.metadata(), b.metadata()) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
        false
    }
    #[cfg(not(unix))]
    {
        matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
    }
}

#[cfg(test)]
mod tests {
    use super::{number_text, open_regular, read_input_file, temp_prefix};

    /// A FIFO that slipped past the check (swapped in after it) is refused once open; a
    /// blocking open would wait for a writer that never comes.
    #[cfg(unix)]
    #[test]
    fn a_fifo_opened_as_input_is_refused_at_once() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("track.csv");
        rustix::fs::mknodat(
            rustix::fs::CWD,
            &fifo,
            rustix::fs::FileType::Fifo,
            rustix::fs::Mode::from_raw_mode(0o600),
            0,
        )
        .unwrap();
        let (done, finished) = std::sync::mpsc::channel();
        let opener = fifo.clone();
        std::thread::spawn(move || done.send(open_regular(&opener).map(drop)));
        let opened = finished
            .recv_timeout(std::time::Duration::from_secs(10))
            .expect("opening the FIFO waited for a writer");
        let error = opened.expect_err("a FIFO was opened as an input file");
        assert!(error.to_string().contains("not a regular file"), "{error}");
        assert!(read_input_file(&fifo, 10).is_err());
    }

    /// Up to the limit the bytes come back; one more and the file is refused.
    #[test]
    fn an_input_file_is_read_up_to_its_limit() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("in.txt");
        std::fs::write(&path, b"0123456789").unwrap();
        assert_eq!(read_input_file(&path, 10).unwrap().unwrap(), b"0123456789");
        assert_eq!(read_input_file(&path, 9).unwrap(), None);
        assert!(read_input_file(&dir.path().join("none"), 9).is_err());
        assert!(read_input_file(dir.path(), 9).is_err());
    }

    #[test]
    fn messages_show_control_characters_escaped() {
        let shown = super::visible_controls("a\u{1b}[2J\rb\u{7}\u{9b}c\n\td");
        assert_eq!(shown, "a\\u{1b}[2J\\u{d}b\\u{7}\\u{9b}c\n\td");
        assert!(matches!(super::visible_controls("plain é"), std::borrow::Cow::Borrowed(_)));
    }

    #[test]
    fn temporary_names_fit_beside_the_longest_names() {
        for name in ["a".repeat(255), "é".repeat(127), format!("a{}", "€".repeat(84))] {
            let prefix = temp_prefix(std::path::Path::new(&format!("out/{name}")));
            // tempfile adds 6 random characters, then the suffix.
            assert!(prefix.len() + 6 + super::TEMP_SUFFIX.len() <= 255, "{prefix}");
            assert!(prefix.starts_with('.') && prefix.ends_with('.'));
            assert!(name.starts_with(&prefix[1..prefix.len() - 1]));
        }
        assert_eq!(temp_prefix(std::path::Path::new("dir/x.png")), ".x.png.");
    }

    #[test]
    fn numbers_in_messages_stay_short() {
        for (v, text) in [(1e308, "1e308"), (-2e9, "-2e9"), (0.5, "0.5"), (0.0, "0"), (1e-9, "1e-9")] {
            assert_eq!(number_text(v), text);
        }
        assert_eq!(number_text(1234567.0), "1234567");
        assert_eq!(number_text(f64::INFINITY), "inf");
    }
}
