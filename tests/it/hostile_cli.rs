//! Hostile input, second catalogue (docs/robustness.md): the real `lapclone` binary over
//! what a suspicious user tries against footage, modules, outputs and flags. Every case
//! must end in seconds with its exit code (0 ok, 1 failure, 2 usage), say what was wrong,
//! never print panic text or abort, and leave no partial, misplaced or replaced output.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

#[cfg(unix)]
use crate::files::make_fifo;
use crate::files::sorted_names;

const W: u32 = 40;
const H: u32 = 30;

/// A temporary folder holding small images and the scenes of one test.
struct World {
    root: tempfile::TempDir,
}

impl World {
    fn new() -> Self {
        let root = tempfile::tempdir().unwrap();
        let world = World { root };
        image::RgbImage::from_fn(W, H, |x, y| image::Rgb([(x * 6) as u8, (y * 8) as u8, 90]))
            .save(world.path("bg.png"))
            .unwrap();
        image::RgbImage::from_fn(W, H, |x, y| image::Rgb([200, (x * 5) as u8, (y * 7) as u8]))
            .save(world.path("src.png"))
            .unwrap();
        image::GrayImage::from_fn(W, H, |x, y| {
            image::Luma([if (10..30).contains(&x) && (8..22).contains(&y) {
                255
            } else {
                0
            }])
        })
        .save(world.path("mask.png"))
        .unwrap();
        world
    }

    fn path(&self, relative: &str) -> PathBuf {
        self.root.path().join(relative)
    }

    fn write(&self, relative: &str, text: &str) -> PathBuf {
        let path = self.path(relative);
        std::fs::write(&path, text).unwrap();
        path
    }

    /// A valid 3-frame scene over the world's images, with `extra` appended.
    fn scene(&self, name: &str, extra: &str) -> PathBuf {
        self.write(
            name,
            &format!(
                "canvas({W}, {H}, #{{ fps: 3, duration: 1, background: \"bg.png\" }});\n\
                 let p = patch(\"p\", #{{ source: \"src.png\", mask: \"mask.png\" }});\n\
                 p.at(0, [20, 15]).at(1, [22, 16]);\n{extra}"
            ),
        )
    }

    fn run(&self, args: &[&str]) -> Output {
        Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .args(args)
            .current_dir(self.root.path())
            .env("RUST_BACKTRACE", "0")
            .output()
            .unwrap()
    }

    /// `lapclone repl ARGS --preview …` in the world, fed `input`, its stdout to `stdout`;
    /// a session still running after 60 s is killed and the test fails (a hang, not a
    /// stuck test run).
    fn repl(&self, args: &[&str], input: &[u8], stdout: Stdio) -> Output {
        let mut child = Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .arg("repl")
            .args(args)
            .arg("--preview")
            .arg(self.path("preview.png"))
            .current_dir(self.root.path())
            .env("RUST_BACKTRACE", "0")
            .stdin(Stdio::piped())
            .stdout(stdout)
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        use std::io::Write as _;
        // A session may stop reading before the end (an error that ends it): no test error.
        let _ = child.stdin.take().unwrap().write_all(input);
        let pid = child.id().to_string();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || tx.send(child.wait_with_output()));
        match rx.recv_timeout(std::time::Duration::from_secs(60)) {
            Ok(output) => output.unwrap(),
            Err(_) => {
                let _ = Command::new("kill").args(["-9", &pid]).status();
                panic!("`lapclone repl {args:?}` still waits after 60 s");
            }
        }
    }

    /// A piped `lapclone repl` session with no scene, fed `input`: its exit code, and its
    /// standard output and error together.
    fn session(&self, input: &[u8]) -> (Option<i32>, String) {
        let output = self.repl(&[], input, Stdio::piped());
        let stdout = String::from_utf8_lossy(&output.stdout);
        let all = format!("{stdout}{}", String::from_utf8_lossy(&output.stderr));
        (output.status.code(), all)
    }

    fn names(&self) -> Vec<String> {
        sorted_names(self.root.path())
    }
}

/// Asserts the exit code, a message substring and the absence of panic text; gives stderr.
#[track_caller]
fn expect(output: &Output, code: i32, message: &str) -> String {
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(code), "stderr: {stderr}");
    assert!(stderr.contains(message), "no `{message}` in: {stderr}");
    assert!(
        !stderr.contains("panicked") && !stderr.contains("overflowed"),
        "{stderr}"
    );
    stderr
}

#[test]
fn import_cycles_are_positioned_errors_naming_the_chain() {
    let world = World::new();
    world.write("a.rhai", "import \"b\" as b;\n");
    world.write("b.rhai", "import \"a\" as a;\n");
    world.write("me.rhai", "import \"me\" as me;\n");
    let cycle = world.scene("cycle.rhai", "import \"a\" as a;\n");
    let own = world.scene("own.rhai", "import \"me\" as me;\n");
    let cycle = cycle.to_str().unwrap();
    for args in [
        vec!["check", cycle],
        vec!["render", cycle, "-o", "frames"],
        vec!["preview", cycle, "-o", "p.png"],
    ] {
        let stderr = expect(
            &world.run(&args),
            1,
            "import cycle: a.rhai → b.rhai → a.rhai",
        );
        assert!(stderr.contains("b.rhai:1:8:"), "{stderr}");
    }
    let test = world.run(&["test", cycle]);
    let stderr = String::from_utf8_lossy(&test.stderr);
    assert!(matches!(test.status.code(), Some(1 | 2)), "{stderr}");
    assert!(
        stderr.contains("import cycle: a.rhai → b.rhai → a.rhai"),
        "{stderr}"
    );
    expect(
        &world.run(&["check", own.to_str().unwrap()]),
        1,
        "import cycle: me.rhai → me.rhai",
    );
    assert!(!world.names().iter().any(|n| n == "frames" || n == "p.png"));
}

#[test]
fn a_long_acyclic_import_chain_loads() {
    let world = World::new();
    for i in 0..40 {
        world.write(
            &format!("m{i}.rhai"),
            &format!("import \"m{}\" as next;\n", i + 1),
        );
    }
    world.write("m40.rhai", "fn depth() { 40 }\n");
    let scene = world.scene("chain.rhai", "import \"m0\" as m;\n");
    expect(&world.run(&["check", scene.to_str().unwrap()]), 0, "");
}

#[test]
fn jobs_are_clamped_to_the_cores_and_absurd_values_refused() {
    let world = World::new();
    let scene = world.scene("s.rhai", "");
    let scene = scene.to_str().unwrap();
    for jobs in ["40000", "1025"] {
        expect(
            &world.run(&["render", scene, "-o", "frames", "--jobs", jobs]),
            2,
            "at most 1024",
        );
        expect(
            &world.run(&["test", scene, "--jobs", jobs]),
            2,
            "at most 1024",
        );
    }
    assert!(!world.names().contains(&"frames".to_string()));
    let output = world.run(&["render", scene, "-o", "frames", "--jobs", "1024"]);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if cores < 1024 {
        expect(&output, 0, "lowered to");
    }
    assert_eq!(sorted_names(&world.path("frames")).len(), 3);
}

#[test]
fn keys_added_one_call_at_a_time_stay_linear_and_late_keys_are_counted() {
    let world = World::new();
    // 60 000 keys after the scene's end: quadratic appends took minutes here, and the
    // warning listed every key.
    let scene = world.scene(
        "keys.rhai",
        "for i in 0..60000 { p.scale(2 + i * 0.001, 1.0); }\n",
    );
    let stderr = expect(
        &world.run(&["check", scene.to_str().unwrap()]),
        0,
        "60000 keys at t = 2, ",
    );
    assert!(stderr.len() < 2000, "{} bytes of stderr", stderr.len());
    // A million keys end at the operation limit, with a position.
    let scene = world.scene(
        "million.rhai",
        "for i in 0..1000000 { p.at(i * 0.001, [20, 15]); }\n",
    );
    expect(
        &world.run(&["check", scene.to_str().unwrap()]),
        1,
        "million.rhai:4:",
    );
}

#[test]
fn scene_memory_is_bounded_by_one_budget() {
    let world = World::new();
    let half_mib = "let s = \"x\"; for i in 0..19 { s += s; }\n";
    for (name, body) in [
        (
            "map",
            "let m = #{}; let i = 0; loop { m[`k${i}`] = s + i; i += 1; }\n",
        ),
        (
            "array",
            "let a = []; a.pad(90000, \"\"); for i in 0..90000 { a[i] = s + i; }\n",
        ),
        (
            "nested",
            "let a = []; a.pad(1000, []); for i in 0..1000 { a[i] = [s + i]; }\n",
        ),
    ] {
        let scene = world.scene(&format!("{name}.rhai"), &format!("{half_mib}{body}"));
        let output = world.run(&["check", scene.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{name}: {stderr}");
        assert!(
            stderr.contains("scene memory budget of 256 MiB"),
            "{name}: {stderr}"
        );
        assert!(
            stderr.contains(&format!("{name}.rhai:")),
            "{name}: {stderr}"
        );
    }
}

/// Numbered plates `plates/plate_0001.png …`, the middle one corrupt.
fn plates_with_a_corrupt_one(world: &World) -> PathBuf {
    std::fs::create_dir(world.path("plates")).unwrap();
    for i in 1..=3 {
        std::fs::copy(
            world.path("bg.png"),
            world.path(&format!("plates/plate_000{i}.png")),
        )
        .unwrap();
    }
    let bytes = std::fs::read(world.path("bg.png")).unwrap();
    std::fs::write(
        world.path("plates/plate_0002.png"),
        &bytes[..bytes.len() / 2],
    )
    .unwrap();
    world.write(
        "plates.rhai",
        "canvas(#{ fps: 3, duration: 1, background: \"plates/plate_%04d.png\" });\n\
         let p = patch(\"p\", #{ source: \"src.png\", mask: \"mask.png\" });\n",
    )
}

#[test]
fn a_failed_png_render_leaves_no_new_folder_and_an_old_one_as_it_was() {
    let world = World::new();
    let scene = plates_with_a_corrupt_one(&world);
    let scene = scene.to_str().unwrap();
    expect(
        &world.run(&["render", scene, "-o", "frames"]),
        1,
        "plate_0002.png",
    );
    let names = world.names();
    assert!(!names.iter().any(|n| n.contains("frames")), "{names:?}");
    // An existing folder with an earlier render's frames keeps them, byte for byte.
    let good = world.scene("good.rhai", "");
    expect(
        &world.run(&["render", good.to_str().unwrap(), "-o", "frames"]),
        0,
        "",
    );
    let before: Vec<Vec<u8>> = sorted_names(&world.path("frames"))
        .iter()
        .map(|n| std::fs::read(world.path("frames").join(n)).unwrap())
        .collect();
    expect(
        &world.run(&["render", scene, "-o", "frames"]),
        1,
        "plate_0002.png",
    );
    let after: Vec<Vec<u8>> = sorted_names(&world.path("frames"))
        .iter()
        .map(|n| std::fs::read(world.path("frames").join(n)).unwrap())
        .collect();
    assert_eq!(before, after);
    assert!(!world.names().iter().any(|n| n.ends_with(".tmp")));
}

#[test]
fn an_output_that_is_an_input_is_refused() {
    let world = World::new();
    world.write("lib.rhai", "fn width() { 40 }\n");
    let scene = world.scene("victim.rhai", "import \"lib\" as lib;\n");
    let original = std::fs::read(&scene).unwrap();
    world.write("face.csv", "frame,x,y\n1,20,15\n2,21,15\n3,22,16\n");
    world.scene("follows.rhai", "p.follow(\"face.csv\");\n");
    world.write("keys.csv", "frame,x,y\n1,20,15\n2,21,15\n");
    world.scene("reads.rhai", "let keys = track_keys(\"keys.csv\");\n");
    // A track file stays an input after a later `follow` replaces the keys it gave.
    world.write("old.csv", "frame,x,y\n1,20,15\n2,21,15\n");
    world.scene(
        "refollows.rhai",
        "p.follow(\"old.csv\");\np.follow(\"face.csv\");\n",
    );
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(world.path("lib.rhai"), world.path("lib_link.gif")).unwrap();
        std::fs::hard_link(world.path("bg.png"), world.path("hard.png")).unwrap();
    }
    let mut cases = vec![
        vec![
            "render",
            "victim.rhai",
            "-o",
            "victim.rhai",
            "--format",
            "gif",
        ],
        vec![
            "render",
            "victim.rhai",
            "-o",
            "lib.rhai",
            "--format",
            "apng",
        ],
        vec!["render", "victim.rhai", "-o", "src.png", "--format", "apng"],
        vec!["render", "victim.rhai", "-o", "mask.png", "--format", "y4m"],
        vec!["preview", "victim.rhai", "-o", "bg.png"],
        vec!["preview", "victim.rhai", "-o", "./src.png"],
        vec![
            "clone", "--source", "src.png", "--mask", "mask.png", "--target", "bg.png", "--at",
            "20,15", "-o", "bg.png",
        ],
        vec!["mesh", "mask.png", "-o", "mask.png"],
        // A followed track file is an input too.
        vec![
            "render",
            "follows.rhai",
            "-o",
            "face.csv",
            "--format",
            "gif",
        ],
        vec!["render", "reads.rhai", "-o", "keys.csv", "--format", "apng"],
        vec![
            "render",
            "refollows.rhai",
            "-o",
            "old.csv",
            "--format",
            "gif",
        ],
    ];
    #[cfg(unix)]
    cases.extend([
        vec!["render", "victim.rhai", "-o", "lib_link.gif"],
        vec!["preview", "victim.rhai", "-o", "hard.png"],
    ]);
    let snapshot = |w: &World| -> Vec<(String, Vec<u8>)> {
        w.names()
            .into_iter()
            .filter(|n| !w.path(n).is_dir())
            .map(|n| (n.clone(), std::fs::read(w.path(&n)).unwrap()))
            .collect()
    };
    let before = snapshot(&world);
    for args in &cases {
        expect(&world.run(args), 1, "would replace an input");
    }
    expect(
        &world.run(&["preview", "follows.rhai", "-o", "face.csv"]),
        2,
        "preview writes PNG",
    );
    assert_eq!(snapshot(&world), before);
    assert_eq!(std::fs::read(&scene).unwrap(), original);
    // Plates rendered into their own folder would be replaced (or removed by --force).
    std::fs::create_dir(world.path("out")).unwrap();
    std::fs::copy(world.path("bg.png"), world.path("out/frame_0001.png")).unwrap();
    std::fs::copy(world.path("bg.png"), world.path("out/frame_0002.png")).unwrap();
    let plates = world.write(
        "plates.rhai",
        "canvas(#{ fps: 2, duration: 1, background: \"out/frame_%04d.png\" });\n",
    );
    for extra in [None, Some("--force")] {
        let mut args = vec!["render", plates.to_str().unwrap(), "-o", "out"];
        args.extend(extra);
        expect(&world.run(&args), 1, "would replace an input");
    }
    assert_eq!(
        sorted_names(&world.path("out")),
        ["frame_0001.png", "frame_0002.png"]
    );
    // Every plate a pattern names is footage, also outside the frames one run reads.
    std::fs::copy(world.path("bg.png"), world.path("out/frame_0009.png")).unwrap();
    let plate = std::fs::read(world.path("out/frame_0009.png")).unwrap();
    let track = [
        "track",
        "out/frame_%04d.png",
        "--point",
        "20,15",
        "--frames",
        "1..2",
        "-o",
    ];
    // Also a plate the pattern names that does not exist yet, and a plate reached through a
    // link (an output is written through a link to its target).
    let mut outputs = vec![
        "out/frame_0009.png",
        "out/frame_0002.png",
        "out/frame_0031.png",
    ];
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("out/frame_0002.png", world.path("plate_link.csv")).unwrap();
        outputs.push("plate_link.csv");
        let args = [
            plates.to_str().unwrap(),
            "-o",
            "plate_link.csv",
            "--format",
            "gif",
        ];
        expect(
            &world.run(&[&["render"][..], &args].concat()),
            1,
            "would replace an input",
        );
    }
    for output in outputs {
        let args: Vec<&str> = track.iter().copied().chain([output]).collect();
        expect(&world.run(&args), 1, "would replace an input");
    }
    assert!(!world.path("out/frame_0031.png").exists());
    assert_eq!(
        std::fs::read(world.path("out/frame_0002.png")).unwrap(),
        std::fs::read(world.path("bg.png")).unwrap()
    );
    let args = [
        "preview",
        plates.to_str().unwrap(),
        "-o",
        "out/frame_0009.png",
    ];
    expect(&world.run(&args), 1, "would replace an input");
    assert_eq!(
        std::fs::read(world.path("out/frame_0009.png")).unwrap(),
        plate
    );
}

#[cfg(unix)]
#[test]
fn streams_are_written_through_and_other_special_files_never_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let world = World::new();
    let scene = world.scene("s.rhai", "");
    let scene = scene.to_str().unwrap();
    // /dev/null is a sink: written, never replaced.
    expect(
        &world.run(&["render", scene, "-o", "/dev/null", "--format", "gif"]),
        0,
        "",
    );
    expect(&world.run(&["preview", scene, "-o", "/dev/null"]), 0, "");
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
    // A FIFO is written through: its reader gets the whole GIF and it stays a FIFO.
    let fifo = world.path("pipe.gif");
    make_fifo(&fifo);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(fifo).unwrap())
    };
    expect(&world.run(&["render", scene, "-o", "pipe.gif"]), 0, "");
    let gif = reader.join().unwrap();
    assert!(
        gif.starts_with(b"GIF89a") && gif.ends_with(&[0x3b]),
        "{} bytes",
        gif.len()
    );
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
    // A link to a regular file: the file is written, the link stays.
    std::fs::write(world.path("old.gif"), b"old").unwrap();
    std::os::unix::fs::symlink(world.path("old.gif"), world.path("link.gif")).unwrap();
    expect(&world.run(&["render", scene, "-o", "link.gif"]), 0, "");
    assert!(std::fs::symlink_metadata(world.path("link.gif"))
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(std::fs::read(world.path("old.gif"))
        .unwrap()
        .starts_with(b"GIF89a"));
    // A link to nothing is refused and stays as it was.
    std::os::unix::fs::symlink(world.path("nowhere.gif"), world.path("dangling.gif")).unwrap();
    expect(
        &world.run(&["render", scene, "-o", "dangling.gif"]),
        1,
        "a symbolic link to nothing",
    );
    assert!(std::fs::symlink_metadata(world.path("dangling.gif")).is_ok());
    assert!(!world.path("nowhere.gif").exists());
    assert!(!world.names().iter().any(|n| n.ends_with(".tmp")));
}

#[cfg(unix)]
#[test]
fn special_files_as_inputs_fail_at_once_instead_of_waiting() {
    let world = World::new();
    make_fifo(&world.path("fifo.png"));
    make_fifo(&world.path("fifo.rhai"));
    std::fs::create_dir(world.path("folder.png")).unwrap();
    let clone = |source: &str| {
        world.run(&[
            "clone", "--source", source, "--mask", "mask.png", "--target", "bg.png", "--at",
            "20,15", "-o", "o.png",
        ])
    };
    expect(
        &clone("fifo.png"),
        1,
        "fifo.png: it is not a regular file (a FIFO)",
    );
    expect(
        &clone("folder.png"),
        1,
        "folder.png: it is a folder, not a file",
    );
    expect(
        &world.run(&["mesh", "fifo.png"]),
        1,
        "not a regular file (a FIFO)",
    );
    expect(
        &world.run(&["check", "fifo.rhai"]),
        1,
        "not a regular file (a FIFO)",
    );
    let scene = world.write(
        "bgfifo.rhai",
        "canvas(40, 30, #{ background: \"fifo.png\" });\n",
    );
    expect(
        &world.run(&["check", scene.to_str().unwrap()]),
        1,
        "background `fifo.png` is not a regular file (a FIFO)",
    );
    world.write("pipe.rhai", "");
    std::fs::remove_file(world.path("pipe.rhai")).unwrap();
    make_fifo(&world.path("pipe.rhai"));
    let scene = world.scene("imp.rhai", "import \"pipe\" as pipe;\n");
    expect(
        &world.run(&["check", scene.to_str().unwrap()]),
        1,
        "module `pipe` is not a regular file (a FIFO)",
    );
    let scene = world.scene("dirbg.rhai", "");
    std::fs::write(&scene, "canvas(40, 30, #{ background: \"folder.png\" });\n").unwrap();
    expect(
        &world.run(&["check", scene.to_str().unwrap()]),
        1,
        "is a folder, not a file",
    );
    expect(
        &clone_into(&world, "bg.png/o.png"),
        1,
        "the output folder bg.png is not a folder",
    );
}

fn clone_into(world: &World, output: &str) -> Output {
    world.run(&[
        "clone", "--source", "src.png", "--mask", "mask.png", "--target", "bg.png", "--at",
        "20,15", "-o", output,
    ])
}

#[cfg(unix)]
#[test]
fn a_failed_write_to_standard_output_is_exit_1() {
    let world = World::new();
    let scene = world.scene("s.rhai", "");
    let scene = scene.to_str().unwrap();
    let closed = |args: &[&str]| {
        Command::new("sh")
            .arg("-c")
            .arg("exec \"$0\" \"$@\" >&-")
            .arg(env!("CARGO_BIN_EXE_lapclone"))
            .args(args)
            .current_dir(world.root.path())
            .output()
            .unwrap()
    };
    expect(
        &closed(&["render", scene, "-o", "-", "--format", "y4m"]),
        1,
        "standard output is closed",
    );
    // Summary lines into a closed standard output are dropped: it cannot be told from
    // `/dev/null` opened read-write (Python's `subprocess.DEVNULL`), a legitimate sink.
    expect(&closed(&["check", scene]), 0, "");
    let read_write_null = |args: &[&str]| {
        let null = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open("/dev/null")
            .unwrap();
        Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .args(args)
            .current_dir(world.root.path())
            .stdout(null)
            .output()
            .unwrap()
    };
    expect(&read_write_null(&["check", scene]), 0, "");
    // `/dev/stdout` on a pipe links to `pipe:[N]`: written through by the path given.
    let piped = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["preview", scene, "-o", "/dev/stdout"])
        .current_dir(world.root.path())
        .output()
        .unwrap();
    expect(&piped, 0, "");
    assert!(
        piped.stdout.starts_with(b"\x89PNG\r\n"),
        "not a PNG on the pipe"
    );
    expect(&read_write_null(&["render", scene, "-o", "o.gif"]), 0, "");
    assert!(world.root.path().join("o.gif").is_file());
    if Path::new("/dev/full").exists() {
        let full = |args: &[&str]| {
            Command::new(env!("CARGO_BIN_EXE_lapclone"))
                .args(args)
                .current_dir(world.root.path())
                .stdout(std::fs::File::create("/dev/full").unwrap())
                .stderr(Stdio::piped())
                .output()
                .unwrap()
        };
        expect(
            &full(&["render", scene, "-o", "-", "--format", "y4m"]),
            1,
            "standard output",
        );
        expect(&full(&["check", scene]), 1, "writing to standard output");
        expect(
            &full(&["mesh", "mask.png"]),
            1,
            "writing to standard output",
        );
        // The help and the version are output too: unwritten, they are not a success.
        for asked in [
            &["--help"][..],
            &["--version"],
            &["render", "--help"],
            &["help"],
        ] {
            expect(&full(asked), 1, "writing to standard output");
        }
    }
    // Standard output sent to /dev/null on purpose is a legitimate sink.
    let null = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["render", scene, "-o", "-", "--format", "y4m"])
        .current_dir(world.root.path())
        .stdout(Stdio::null())
        .output()
        .unwrap();
    expect(&null, 0, "rendered 3 frames");
}

#[test]
fn no_command_creates_a_missing_parent_folder() {
    let world = World::new();
    let scene = world.scene("s.rhai", "");
    let scene = scene.to_str().unwrap();
    let before = world.names();
    expect(
        &world.run(&["test", scene, "--update", "--junit", "missing/j.xml"]),
        1,
        "missing/j.xml: the output folder missing does not exist",
    );
    expect(
        &world.run(&["test", scene, "--update", "--out", "missing/out"]),
        1,
        "the output folder missing does not exist",
    );
    expect(
        &world.run(&["test", scene, "--update", "--goldens", "missing/goldens"]),
        1,
        "the output folder missing does not exist",
    );
    assert_eq!(world.names(), before);
}

#[test]
fn messages_say_what_is_wrong() {
    let world = World::new();
    std::fs::create_dir(world.path("plates")).unwrap();
    for i in 1..=3 {
        std::fs::copy(
            world.path("bg.png"),
            world.path(&format!("plates/plate_000{i}.png")),
        )
        .unwrap();
    }
    // A scene longer than its footage: the first frame past the plates is named, on loading,
    // at the `canvas(...)` call that named the footage.
    let plates = world.write(
        "plates.rhai",
        "canvas(#{ fps: 3, duration: 200, background: \"plates/plate_%04d.png\" });\n",
    );
    let plates = plates.to_str().unwrap();
    expect(
        &world.run(&["preview", plates, "--t", "1", "-o", "p.png"]),
        1,
        "plates.rhai:1:1: background footage: frame 4 needs",
    );
    expect(
        &world.run(&["preview", plates, "--t", "1e300", "-o", "p.png"]),
        1,
        "plates.rhai:1:1: background footage: frame 4 needs",
    );
    // A mask whose only piece is too small: the mask is named, no setting the command lacks.
    image::GrayImage::from_fn(W, H, |x, y| {
        image::Luma([if (x, y) == (5, 5) { 255 } else { 0 }])
    })
    .save(world.path("speck.png"))
    .unwrap();
    for output in [
        world.run(&["mesh", "speck.png"]),
        world.run(&[
            "clone",
            "--source",
            "src.png",
            "--mask",
            "speck.png",
            "--target",
            "bg.png",
            "--at",
            "20,15",
            "-o",
            "o.png",
        ]),
    ] {
        let stderr = expect(&output, 1, "mask speck.png: every piece");
        assert!(!stderr.contains("lower min_piece_area"), "{stderr}");
    }
    // Already holding: the hint does not say to hold.
    let held = world.write(
        "held.rhai",
        "canvas(40, 30, #{ background: \"bg.png\" });\n\
         patch(\"p\", #{ source: \"plates/plate_%04d.png\", mask: \"mask.png\", source_start: 7, source_hold: true });\n",
    );
    let stderr = expect(
        &world.run(&["check", held.to_str().unwrap()]),
        1,
        "plate_0007.png",
    );
    assert!(!stderr.contains("add `source_hold: true`"), "{stderr}");
    // A pin and a drag far outside the patch are named.
    let points = world.scene(
        "points.rhai",
        "p.pin([2, 2]);\np.drag([38, 28], 5).key(1, [30, 20]);\n",
    );
    let stderr = expect(
        &world.run(&["check", points.to_str().unwrap()]),
        0,
        "the pin at [2, 2] lies",
    );
    assert!(stderr.contains("the drag grabs [38, 28]"), "{stderr}");
    let inside = world.scene(
        "inside.rhai",
        "p.pin([15, 12]);\np.drag([20, 15], 5).key(1, [22, 16]);\n",
    );
    let stderr = expect(&world.run(&["check", inside.to_str().unwrap()]), 0, "");
    assert!(!stderr.contains("outside the patch"), "{stderr}");
}

#[cfg(unix)]
#[test]
fn a_video_background_without_ffmpeg_names_ffmpeg_not_output_formats() {
    let world = World::new();
    std::fs::write(world.path("bg.mp4"), b"not a video").unwrap();
    let scene = world.write(
        "video.rhai",
        "canvas(#{ fps: 3, duration: 1, background: \"bg.mp4\" });\n",
    );
    let output = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["check", scene.to_str().unwrap()])
        .env("PATH", world.path("no-such-folder"))
        .output()
        .unwrap();
    let stderr = expect(&output, 1, "reading video footage needs them");
    assert!(!stderr.contains("--format"), "{stderr}");
}

#[test]
fn more_hostile_scenes_fail_cleanly_or_work() {
    let world = World::new();
    std::fs::write(world.path("zero.png"), b"").unwrap();
    let head = "canvas(40, 30, #{ fps: 3, duration: 1, background: \"bg.png\" });\n";
    let long_line = format!("let x = 1{};\n", " + 1".repeat(200_000));
    let big_literal = format!("let s = \"{}\";\n", "y".repeat(2 << 20));
    let nested = format!("let a = {}1{};\n", "[".repeat(5000), "]".repeat(5000));
    // Past the 16 MiB limit for scene and module files.
    let oversized = format!("{head}// {}\n", "z".repeat(17 << 20));
    world.write("big_module.rhai", &oversized);
    let table: Vec<(&str, String, i32, &str)> = vec![
        ("negative_fps", "canvas(40, 30, #{ fps: -5 });\n".into(), 1, "fps"),
        ("nan_fps", "canvas(40, 30, #{ fps: 0.0 / 0.0 });\n".into(), 1, "fps"),
        ("huge_canvas", "canvas(1e10, 1);\n".into(), 1, "canvas width"),
        ("zero_byte_background", "canvas(40, 30, #{ background: \"zero.png\" });\n".into(), 1, "zero.png"),
        ("deep_arrays", format!("{head}{nested}"), 1, "nested_arrays.rhai:"),
        ("long_line", format!("{head}{long_line}"), 1, "long_line.rhai:"),
        ("big_literal", format!("{head}{big_literal}"), 1, "big_literal.rhai:"),
        ("oversized", oversized.clone(), 1, "larger than 16 MiB"),
        ("oversized_module", format!("{head}import \"big_module\" as m;\n"), 1, "larger than 16 MiB"),
        ("huge_time", format!("{head}let p = patch(\"p\", #{{ source: \"src.png\", mask: \"mask.png\" }});\np.at(1e300, [1, 1]);\n"), 0, ""),
    ];
    for (name, text, code, message) in &table {
        let file = if *name == "deep_arrays" {
            "nested_arrays"
        } else {
            name
        };
        let scene = world.write(&format!("{file}.rhai"), text);
        let output = world.run(&["check", scene.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(*code), "{name}: {stderr}");
        assert!(
            stderr.contains(message),
            "{name}: no `{message}` in {stderr}"
        );
        assert!(
            !stderr.contains("panicked") && !stderr.contains("overflowed"),
            "{name}: {stderr}"
        );
        // A megabyte line is shown around its column, not whole.
        assert!(
            stderr.len() < 2_000,
            "{name}: {} bytes of errors",
            stderr.len()
        );
    }
}

#[test]
fn unicode_paths_render() {
    let world = World::new();
    let folder = world.path("szène 🎬 ünï");
    std::fs::create_dir(&folder).unwrap();
    std::fs::copy(world.path("bg.png"), folder.join("fond é.png")).unwrap();
    std::fs::write(
        folder.join("場面.rhai"),
        "canvas(40, 30, #{ fps: 3, duration: 1, background: \"fond é.png\" });\n",
    )
    .unwrap();
    let scene = folder.join("場面.rhai");
    let out = folder.join("帧 ✓");
    let output = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    expect(&output, 0, "");
    assert_eq!(sorted_names(&out).len(), 3);
}

/// A FIFO or a device named as the REPL's scene, or loaded into a session, is refused at once
/// like `check` refuses it, and the session goes on (it would otherwise read until the
/// FIFO's writer or the device ends, which may be never).
#[cfg(unix)]
#[test]
fn the_repl_refuses_special_files_as_scenes_at_once() {
    let world = World::new();
    make_fifo(&world.path("fifo.rhai"));
    world.scene("fine.rhai", "");
    for scene in ["fifo.rhai", "/dev/zero"] {
        let output = world.repl(&[scene], b"", Stdio::piped());
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{scene}: {stderr}");
        assert!(
            stderr.contains("cannot read scene: it is not a regular file"),
            "{stderr}"
        );
    }
    let (code, all) = world.session(b":load fifo.rhai\n:load /dev/zero\n:load fine.rhai\n:list\n");
    assert_eq!(code, Some(1), "{all}");
    assert!(
        all.contains("fifo.rhai: cannot read scene: it is not a regular file (a FIFO)"),
        "{all}"
    );
    assert!(
        all.contains("/dev/zero: cannot read scene: it is not a regular file (a device)"),
        "{all}"
    );
    assert!(all.contains("2 failed entries"), "{all}");
    assert!(
        all.contains("fine.rhai") && all.contains("patch \"p\""),
        "the session did not go on: {all}"
    );
}

#[test]
fn the_repl_survives_loading_an_import_cycle() {
    let world = World::new();
    world.write("a.rhai", "import \"b\" as b;\n");
    world.write("b.rhai", "import \"a\" as a;\n");
    world.scene("cycle.rhai", "import \"a\" as a;\n");
    world.scene("fine.rhai", "");
    let (code, all) = world.session(b":load cycle.rhai\n:load fine.rhai\n:list\n");
    // Exit 1 only because a piped session reports its failed entry at the end.
    assert_eq!(code, Some(1), "{all}");
    assert!(all.contains("1 failed entry"), "{all}");
    assert!(
        all.contains("import cycle: a.rhai → b.rhai → a.rhai"),
        "{all}"
    );
    assert!(
        all.contains("loaded") && all.contains("patch \"p\""),
        "the session did not go on: {all}"
    );
    assert!(!all.contains("overflowed"), "{all}");
}

#[test]
fn the_repl_refuses_to_render_over_its_own_inputs() {
    let world = World::new();
    world.write("lib.rhai", "fn width() { 40 }\n");
    let scene = world.scene("victim.rhai", "import \"lib\" as lib;\n");
    let (scene_before, lib_before) = (
        std::fs::read(&scene).unwrap(),
        std::fs::read(world.path("lib.rhai")).unwrap(),
    );
    let src_before = std::fs::read(world.path("src.png")).unwrap();
    let keys = "frame,x,y\n1,20,15\n2,21,15\n";
    world.write("keys.csv", keys);
    // `:save` may write the loaded scene file (here: the same text), nothing it reads, not
    // even a file an entry read through `track_keys`.
    let output = world.repl(
        &["victim.rhai"],
        b":gif victim.rhai\n:gif lib.rhai\n:save src.png\n:save lib.rhai\n:gif out.gif\n\
          :save victim.rhai\nlet k = track_keys(\"keys.csv\");\n:gif keys.csv\n:save keys.csv\n",
        Stdio::piped(),
    );
    let all = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    assert_eq!(output.status.code(), Some(1), "{all}");
    assert!(all.contains("6 failed entries"), "{all}");
    assert_eq!(all.matches("would replace an input").count(), 6, "{all}");
    assert!(all.contains("saved victim.rhai"), "{all}");
    assert_eq!(
        std::fs::read_to_string(world.path("keys.csv")).unwrap(),
        keys
    );
    assert_eq!(std::fs::read(&scene).unwrap(), scene_before);
    assert_eq!(std::fs::read(world.path("lib.rhai")).unwrap(), lib_before);
    assert!(world.path("out.gif").is_file(), "{all}");
    // A preview file that is the scene or something it reads ends the session at once: a
    // PNG by the input rule, another name already by the rule that a preview is a PNG.
    for (preview, code, message) in [
        (
            "victim.rhai",
            2,
            "--preview victim.rhai: the REPL writes PNG",
        ),
        ("src.png", 1, "would replace an input"),
        ("lib.rhai", 2, "--preview lib.rhai: the REPL writes PNG"),
    ] {
        let output = Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .args(["repl", "victim.rhai", "--preview", preview])
            .current_dir(world.root.path())
            .stdin(Stdio::null())
            .output()
            .unwrap();
        expect(&output, code, "--preview");
        expect(&output, code, message);
    }
    assert_eq!(std::fs::read(&scene).unwrap(), scene_before);
    assert_eq!(std::fs::read(world.path("src.png")).unwrap(), src_before);
    assert_eq!(std::fs::read(world.path("lib.rhai")).unwrap(), lib_before);
}

/// The session's own `--script` is an input too: neither `--preview` nor `:save` nor `:gif`
/// replaces it (the session would go on reading the picture as entries).
#[test]
fn the_repl_never_writes_over_its_own_script() {
    let world = World::new();
    world.scene("victim.rhai", "");
    let text = ":load victim.rhai\n:save session.txt\n:gif session.txt\n:t 0.5\n";
    world.write("session.txt", text);
    let repl = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .args(["repl", "--script", "session.txt"])
            .args(extra)
            .current_dir(world.root.path())
            .stdin(Stdio::null())
            .output()
            .unwrap()
    };
    let output = repl(&["--preview", "session.txt"]);
    expect(&output, 2, "--preview session.txt: the REPL writes PNG");
    // A script with a PNG's name is still an input the preview may not replace.
    world.write("session.png", text);
    let output = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args([
            "repl",
            "--script",
            "session.png",
            "--preview",
            "session.png",
        ])
        .current_dir(world.root.path())
        .stdin(Stdio::null())
        .output()
        .unwrap();
    expect(&output, 1, "would replace an input");
    assert_eq!(
        std::fs::read_to_string(world.path("session.png")).unwrap(),
        text
    );
    let output = repl(&[]);
    expect(&output, 1, "2 failed entries");
    let all = String::from_utf8_lossy(&output.stderr);
    assert_eq!(all.matches("would replace an input").count(), 2, "{all}");
    assert_eq!(
        std::fs::read_to_string(world.path("session.txt")).unwrap(),
        text
    );
}

#[cfg(target_os = "linux")]
#[test]
fn a_repl_whose_output_fails_ends_with_exit_1_instead_of_a_panic() {
    let world = World::new();
    world.scene("fine.rhai", "");
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let output = world.repl(
        &["fine.rhai"],
        b"p.at(0, [21, 15]);\n:t 0.5\n",
        Stdio::from(full),
    );
    expect(&output, 1, "writing to standard output");
}

#[cfg(target_os = "linux")]
#[test]
fn accepting_goldens_into_a_failing_output_is_exit_1_instead_of_a_panic() {
    let world = World::new();
    world.scene("fine.rhai", "");
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["test", "--accept", "fine.rhai"])
        .current_dir(world.root.path())
        .env("RUST_BACKTRACE", "0")
        .stdout(full)
        .output()
        .unwrap();
    expect(&output, 1, "writing to standard output");
}

/// Standard error on a full device (as in `lapclone … 2>&1 | head -1` once `head` has gone):
/// messages are dropped, the exit code still tells, and a REPL session runs to its end.
#[cfg(target_os = "linux")]
#[test]
fn a_full_standard_error_drops_messages_instead_of_a_panic() {
    let world = World::new();
    world.scene("fine.rhai", "");
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    let run = |args: &[&str], input: &[u8]| {
        let mut child = Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .args(args)
            .current_dir(world.root.path())
            .env("RUST_BACKTRACE", "0")
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(full())
            .spawn()
            .unwrap();
        use std::io::Write as _;
        child.stdin.take().unwrap().write_all(input).unwrap();
        child.wait().unwrap().code()
    };
    assert_eq!(run(&["check", "missing.rhai"], b""), Some(1));
    assert_eq!(run(&["render", "fine.rhai", "--jobs", "0"], b""), Some(2));
    let session = b":bogus\nlet x = ;\n:save after.rhai\n";
    assert_eq!(
        run(&["repl", "fine.rhai", "--preview", "p.png"], session),
        Some(1)
    );
    assert!(
        world.path("after.rhai").is_file(),
        "the session stopped early"
    );
}

/// A piped session skips an entry that is not UTF-8 and goes on; a line over the scene size
/// limit ends it with an error instead of filling memory; `--script` must not be a device.
#[test]
fn piped_repl_input_is_bounded_and_survives_bytes_that_are_not_utf8() {
    let world = World::new();
    world.scene("fine.rhai", "");
    let output = world.repl(
        &["fine.rhai"],
        b"// caf\xe9\np.at(0, [21, 15]);\n:save after.rhai\n",
        Stdio::piped(),
    );
    expect(&output, 1, "input line 1: not valid UTF-8");
    let saved = std::fs::read_to_string(world.path("after.rhai")).unwrap();
    assert!(saved.contains("p.at(0, [21, 15]);"), "{saved}");
    let mut long = vec![b'x'; 17 << 20];
    long.extend_from_slice(b"\n:save never.rhai\n");
    let output = world.repl(&["fine.rhai"], &long, Stdio::piped());
    expect(&output, 1, "input line 1 is over 16777216 bytes");
    assert!(!world.path("never.rhai").exists());
    #[cfg(unix)]
    {
        let output = world.repl(&["--script", "/dev/zero"], b"", Stdio::piped());
        expect(&output, 1, "it is not a regular file (a device)");
    }
}

/// `lapclone test` reads, writes and removes only regular files in its goldens folders, only
/// pending frames inside `goldens/<name>/`, and never replaces a file that is not its own.
#[cfg(unix)]
#[test]
fn lapclone_test_touches_only_its_own_regular_files() {
    let world = World::new();
    world.scene("fine.rhai", "");
    expect(&world.run(&["test", "fine.rhai", "--update"]), 0, "");
    let goldens = world.path("goldens/fine");
    let first = sorted_names(&goldens)[0].clone();
    let src = std::fs::read(world.path("src.png")).unwrap();
    // A golden that links to an asset is not written through.
    let golden = goldens.join(&first);
    std::fs::remove_file(&golden).unwrap();
    std::os::unix::fs::symlink(world.path("src.png"), &golden).unwrap();
    let output = world.run(&["test", "fine.rhai", "--update"]);
    assert!(String::from_utf8_lossy(&output.stdout).contains("is a symbolic link"));
    assert_eq!(output.status.code(), Some(1));
    assert_eq!(std::fs::read(world.path("src.png")).unwrap(), src);
    // A FIFO golden is named, not waited on.
    std::fs::remove_file(&golden).unwrap();
    let made = Command::new("mkfifo").arg(&golden).status().unwrap();
    assert!(made.success());
    let output = world.run(&["test", "fine.rhai"]);
    assert!(String::from_utf8_lossy(&output.stdout).contains("(a FIFO)"));
    assert_eq!(output.status.code(), Some(1));
    std::fs::remove_file(&golden).unwrap();
    // A pending-looking file among the assets is not accepted.
    std::fs::create_dir(world.path("assets")).unwrap();
    std::fs::write(world.path("assets/frame_0001.png"), b"asset").unwrap();
    std::fs::write(world.path("assets/frame_0001.new.png"), b"stray").unwrap();
    expect(&world.run(&["test", "--accept", "."]), 0, "");
    assert_eq!(
        std::fs::read(world.path("assets/frame_0001.png")).unwrap(),
        b"asset"
    );
    // A JUnit path that is not an earlier report is refused before anything runs.
    let scene = std::fs::read(world.path("fine.rhai")).unwrap();
    expect(
        &world.run(&["test", "fine.rhai", "--junit", "fine.rhai"]),
        2,
        "not a JUnit report",
    );
    assert_eq!(std::fs::read(world.path("fine.rhai")).unwrap(), scene);
    // Goldens that would land above their folder, or be shared by two scenes.
    world.scene("...rhai", "");
    expect(
        &world.run(&["test", "...rhai", "--update"]),
        2,
        "must make a folder name",
    );
    std::fs::create_dir_all(world.path("a")).unwrap();
    std::fs::create_dir_all(world.path("b")).unwrap();
    world.scene("a/same.rhai", "");
    world.scene("b/same.rhai", "");
    let shared = ["test", "a", "b", "--goldens", "g", "--update"];
    expect(&world.run(&shared), 2, "would share the goldens");
    // A linked folder back up the tree is not followed.
    std::fs::create_dir(world.path("one")).unwrap();
    std::fs::copy(world.path("fine.rhai"), world.path("one/fine.rhai")).unwrap();
    std::os::unix::fs::symlink(world.path("one"), world.path("one/loop")).unwrap();
    let output = world.run(&["test", "one", "--update"]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("in 1 scenes"), "{stdout}");
}

/// `:undo` keeps the last 500 steps, not every one since the start (each holds the whole
/// scene and every variable).
#[test]
fn the_undo_history_is_bounded() {
    let world = World::new();
    world.scene("fine.rhai", "");
    let mut input = String::new();
    for i in 0..520 {
        input.push_str(&format!("p.at(0.5, [{}, 15]);\n", 20 + i % 7));
    }
    input.push_str(&":undo\n".repeat(501));
    let output = world.repl(&["fine.rhai"], input.as_bytes(), Stdio::piped());
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("undone (499 more)"), "{stdout}");
    assert!(stdout.contains("undone (0 more)"));
    let stderr = expect(&output, 1, "nothing to undo");
    assert!(stderr.contains("1 failed entry"), "{stderr}");
}

/// A pending file that is not a PNG is never made a golden: `--accept` takes the others and
/// exits 1 naming it; `--review` reports it and goes on to the next.
#[test]
fn an_unreadable_pending_frame_is_passed_over_not_accepted() {
    let world = World::new();
    world.scene("fine.rhai", "");
    expect(&world.run(&["test", "fine.rhai", "--update"]), 0, "");
    let goldens = world.path("goldens/fine");
    let names = sorted_names(&goldens);
    let (bad, good) = (&names[0], &names[1]);
    let pending = |name: &str| goldens.join(name.replace(".png", ".new.png"));
    let seed = || {
        std::fs::write(pending(bad), b"not a png").unwrap();
        std::fs::copy(goldens.join(good), pending(good)).unwrap();
    };
    seed();
    let golden_before = std::fs::read(goldens.join(bad)).unwrap();
    expect(
        &world.run(&["test", "--accept", "fine.rhai"]),
        1,
        "1 of 2 pending frame(s) not taken",
    );
    assert_eq!(std::fs::read(goldens.join(bad)).unwrap(), golden_before);
    assert!(!pending(good).exists(), "the readable one was not accepted");
    seed();
    let mut child = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["test", "--review", "fine.rhai", "--out", "review"])
        .current_dir(world.root.path())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    use std::io::Write as _;
    child.stdin.take().unwrap().write_all(b"\xff\na\n").unwrap();
    let output = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("skipped:"), "{stdout}");
    assert!(
        stdout.contains("1 accepted, 0 rejected, 1 skipped"),
        "{stdout}"
    );
}

/// Rhai sizes a value with everything nested in it: a list of 5,000 keys (each a map with
/// an `at` array: 15,000 map entries, 10,000 array entries) is an ordinary long animation
/// and must load; a runaway array is still refused.
#[test]
fn a_long_key_list_loads_and_a_runaway_array_is_still_refused() {
    let world = World::new();
    world.scene(
        "long.rhai",
        "let k = [];\nfor i in 0..5000 { k.push(#{ t: i / 5000.0, at: [20, 15], ease: \"smooth\" }); }\n\
         p.keys(k);\n",
    );
    let output = world.run(&["check", "long.rhai"]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    world.scene("runaway.rhai", "let a = []; a.pad(2000000, 0);\n");
    expect(&world.run(&["check", "runaway.rhai"]), 1, "Size of array");
}

/// A GIF above 50 fps cannot keep its rate (whole-centisecond delays, and players show
/// those under 2 cs for 10 cs): the render says so; at 50 fps it does not.
#[test]
fn a_gif_past_fifty_fps_says_it_plays_slower() {
    let world = World::new();
    for (fps, slower) in [(60, true), (50, false)] {
        world.write(
            "fast.rhai",
            &format!("canvas(8, 8, #{{ fps: {fps}, duration: 0.1 }});\n"),
        );
        let output = world.run(&["render", "fast.rhai", "-o", "fast.gif"]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{stderr}");
        assert_eq!(
            stderr.contains("past what GIF players keep"),
            slower,
            "{fps}: {stderr}"
        );
    }
}

/// `preview` and `clone` write one PNG: `-o -` puts it on standard output (the bytes of the
/// file they would write), another image extension is refused before any work, and a time
/// or frame past the scene's end is a usage error, as `render --frames` past it is.
#[test]
fn one_picture_outputs_are_png_files_or_standard_output() {
    let world = World::new();
    let scene = world.scene("fine.rhai", "").display().to_string();
    let scene = scene.as_str();
    for (args, message) in [
        (&["preview", scene, "-o", "x.jpg"][..], "preview writes PNG"),
        (
            &["preview", scene, "--t", "1.5", "-o", "x.png"],
            "--t 1.5: the scene lasts 1 s",
        ),
        (
            &["preview", scene, "--frame", "4", "-o", "x.png"],
            "--frame 4: the scene has 3 frames",
        ),
        (
            &[
                "clone", "--source", "src.png", "--mask", "mask.png", "--target", "bg.png", "--at",
                "20,15", "-o", "x.webp",
            ],
            "clone writes PNG",
        ),
        (
            &[
                "clone", "--source", "src.png", "--mask", "mask.png", "--target", "bg.png", "--at",
                "20,15", "--stats", "-o", "-",
            ],
            "--stats prints on standard output",
        ),
    ] {
        expect(&world.run(args), 2, message);
    }
    assert!(
        !world.names().iter().any(|n| n.starts_with('x')),
        "{:?}",
        world.names()
    );
    let clone = [
        "clone", "--source", "src.png", "--mask", "mask.png", "--target", "bg.png", "--at",
        "20,15", "-o",
    ];
    for (to_stdout, to_file) in [
        (
            vec!["preview", scene, "--t", "1", "-o", "-"],
            vec!["preview", scene, "--t", "1", "-o", "f.PNG"],
        ),
        (
            [&clone[..], &["-"]].concat(),
            [&clone[..], &["f.PNG"]].concat(),
        ),
    ] {
        let piped = world.run(&to_stdout);
        expect(&piped, 0, "");
        expect(&world.run(&to_file), 0, "");
        assert_eq!(
            piped.stdout,
            std::fs::read(world.path("f.PNG")).unwrap(),
            "{to_stdout:?}"
        );
        assert_eq!(&piped.stdout[..4], b"\x89PNG");
        assert!(!world.path("-").exists());
    }
}

/// An output whose name takes the whole 255 bytes a name may have is written: the temporary
/// file or folder beside it is named within the limit too.
#[test]
fn outputs_with_the_longest_names_are_written() {
    let world = World::new();
    let scene = world.scene("fine.rhai", "").display().to_string();
    let stem = "é".repeat(123);
    for (args, name) in [
        (vec!["preview", scene.as_str()], format!("{stem}abcde.png")),
        (vec!["render", scene.as_str()], format!("{stem}abcde.gif")),
        (vec!["render", scene.as_str()], format!("{stem}abcdefghi")),
    ] {
        assert_eq!(name.len(), 255);
        let output = world.run(&[&args[..], &["-o", &name]].concat());
        expect(&output, 0, "");
        assert!(world.path(&name).exists(), "{name}");
    }
    assert!(!world.names().iter().any(|n| n.ends_with(".tmp")));
}

/// A render flag the output's format does not use is named in a warning (the render goes
/// on): a user who gave `--crf` for a GIF expects a quality change that will not come.
#[test]
fn render_flags_the_format_ignores_are_named() {
    let world = World::new();
    let scene = world.scene("fine.rhai", "").display().to_string();
    let scene = scene.as_str();
    let cases: [(&[&str], &[&str]); 4] = [
        (
            &["-o", "a.gif", "--crf", "20"],
            &["--crf applies to MP4, WebM and MOV videos only; this GIF"],
        ),
        (
            &["-o", "b.apng", "--force", "--png-compression", "best"],
            &[
                "--force applies to PNG frame folders only",
                "--png-compression applies to PNG frame folders only; this APNG",
            ],
        ),
        (
            &["-o", "frames", "--crf", "3"],
            &["this PNG frame folder output ignores it"],
        ),
        (
            &[
                "-o",
                "c.gif",
                "--format",
                "y4m",
                "--png-compression",
                "fast",
            ],
            &["this Y4M output ignores it"],
        ),
    ];
    for (flags, warnings) in cases {
        let stderr = expect(&world.run(&[&["render", scene][..], flags].concat()), 0, "");
        for warning in warnings {
            assert!(stderr.contains(warning), "{flags:?}: {stderr}");
        }
    }
    let used = world.run(&[
        "render",
        scene,
        "-o",
        "frames",
        "--force",
        "--png-compression",
        "best",
    ]);
    assert!(!expect(&used, 0, "").contains("warning"));
}

/// Control characters a message quotes (a scene's `throw`, a file name) reach the terminal
/// escaped: a scene cannot clear the screen or retitle the window of the one reading it.
#[test]
fn messages_show_control_characters_escaped() {
    let world = World::new();
    world.scene(
        "throws.rhai",
        "throw \"bad\\x1b[2J\\x1b]0;title\\x07end\";\n",
    );
    let bell = "\u{7}.png";
    for args in [
        &["check", "throws.rhai"][..],
        &[
            "clone", "--source", bell, "--mask", "mask.png", "--target", "bg.png", "--at", "1,1",
            "-o", "o.png",
        ],
    ] {
        let output = world.run(args);
        let stderr = expect(&output, 1, "");
        assert!(!stderr.contains(['\u{1b}', '\u{7}']), "{stderr:?}");
        assert!(
            stderr.contains("\\u{1b}[2J") || stderr.contains("\\u{7}.png"),
            "{stderr:?}"
        );
    }
}

/// A full disk while writing a GIF, an APNG or one PNG: the message names the file that could
/// not be written, not just the encoder.
#[cfg(target_os = "linux")]
#[test]
fn a_full_disk_names_the_output() {
    let world = World::new();
    let scene = world.scene("fine.rhai", "").display().to_string();
    let scene = scene.as_str();
    for args in [
        &["render", scene, "-o", "/dev/full", "--format", "gif"][..],
        &["render", scene, "-o", "/dev/full", "--format", "apng"],
        &["preview", scene, "-o", "/dev/full"],
    ] {
        let stderr = expect(&world.run(args), 1, "/dev/full");
        assert!(stderr.contains("No space left on device"), "{stderr}");
    }
}

/// An output path longer than the system takes (4,096 bytes) is named as too long, not as a
/// missing folder the user can see exists.
#[cfg(target_os = "linux")]
#[test]
fn an_output_path_too_long_says_so() {
    let world = World::new();
    let scene = world.scene("fine.rhai", "").display().to_string();
    // The folders exist as far as a path may reach (made one step at a time).
    let mut folder = world.root.path().to_path_buf();
    for i in 0..21 {
        folder.push(format!("{i:02}{}", "d".repeat(198)));
        if folder.as_os_str().len() < 4000 {
            std::fs::create_dir(&folder).unwrap();
        }
    }
    let output = format!("{}/x.png", folder.display());
    assert!(output.len() > 4096);
    for args in [
        &["preview", scene.as_str(), "-o", &output][..],
        &["render", &scene, "-o", &output],
    ] {
        let stderr = expect(&world.run(args), 1, "File name too long");
        assert!(!stderr.contains("does not exist"), "{stderr}");
    }
}

/// Sizes that do not fit: polygons entirely outside their source are a positioned error;
/// polygons reaching past its edge, and a background that does not cover the canvas, are
/// warnings from `check` and `render` (what they draw is not what the scene seems to say).
#[test]
fn sizes_that_do_not_fit_are_named() {
    let world = World::new();
    let polygon = |name: &str, ring: &str| {
        world.write(
            name,
            &format!(
                "canvas({W}, {H}, #{{ fps: 2, duration: 1, background: \"bg.png\" }});\n\
                 let p = patch(\"p\", #{{ source: \"src.png\", polygons: [{ring}] }});\n"
            ),
        )
    };
    polygon("away.rhai", "[[-30, -30], [-10, -30], [-10, -10]]");
    polygon("past.rhai", "[[5, 5], [52.5, 5], [20, 25]]");
    polygon("inside.rhai", "[[0, 0], [40, 0], [40, 30]]");
    world.write(
        "small_bg.rhai",
        &format!(
            "canvas({}, {H}, #{{ fps: 2, duration: 1, background: \"bg.png\" }});\n",
            W + 8
        ),
    );
    let stderr = expect(
        &world.run(&["check", "away.rhai"]),
        1,
        "away.rhai:2:9: patch `p`: its polygons lie entirely outside its 40×30 source",
    );
    assert!(stderr.contains('^'), "{stderr}");
    for command in [&["check"][..], &["render", "-o", "out.gif"]] {
        let run = |scene: &str| world.run(&[&command[..1], &[scene], &command[1..]].concat());
        let stderr = expect(
            &run("past.rhai"),
            0,
            "patch `p`: its polygons reach 12.5 px past the edge of its 40×30 source",
        );
        assert_eq!(stderr.matches("warning").count(), 1, "{stderr}");
        expect(&run("small_bg.rhai"), 0, "is 40×30 and the canvas 48×30: it is drawn from the top-left corner, with opaque black");
        assert!(!expect(&run("inside.rhai"), 0, "").contains("warning"));
    }
    // The mask is 40×30 with inside pixels x 10..30, y 8..22; the source 40×30.
    let clone = |offset: &str| {
        world.run(&[
            "clone",
            "--source",
            "src.png",
            "--mask",
            "mask.png",
            "--target",
            "bg.png",
            "--at",
            "20,15",
            "--mask-offset",
            offset,
            "-o",
            "o.png",
        ])
    };
    expect(
        &clone("-40,0"),
        1,
        "the mask at offset (-40, 0) lies entirely outside the 40×30 source",
    );
    assert!(!world.path("o.png").exists());
    expect(
        &clone("-12.5,0"),
        0,
        "the mask at offset (-12.5, 0) reaches 2.5 px past the edge of the 40×30 source",
    );
    assert!(!expect(&clone("-10,0"), 0, "").contains("warning"));
}

/// A file name holding a newline is shown quoted with its escapes, so an error stays on its
/// line (`file:line:col: …`, which editors and CI read) instead of being split by the name.
#[cfg(unix)]
#[test]
fn a_newline_in_a_file_name_keeps_each_message_on_its_line() {
    let world = World::new();
    world.write("bad\nname.rhai", "canvas(10, 10);\nnope(;\n");
    let out = world.run(&["check", "bad\nname.rhai"]);
    let stderr = expect(&out, 1, "syntax error");
    assert_eq!(
        stderr.lines().next(),
        Some("lapclone: error: \"bad\\nname.rhai\":2:6: syntax error: Unexpected ';'"),
        "{stderr}"
    );
    let scene = world.scene("ok.rhai", "");
    let scene = scene.to_str().unwrap();
    let out = world.run(&["render", scene, "-o", "no\nfolder/out.gif"]);
    let stderr = expect(&out, 1, "does not exist");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("\"no\\nfolder\""), "{stderr}");
    let out = world.run(&["preview", "missing\n.rhai", "-o", "p.png"]);
    let stderr = expect(&out, 1, "missing\\n.rhai");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
}

/// `mesh` writes files only: `-` is refused rather than written as a file named `-`, and a
/// `--laplacian-out` that is a device or a folder is refused rather than given a new
/// `.boundary` file beside it (`/dev/null.boundary`).
#[cfg(unix)]
#[test]
fn mesh_outputs_are_files_never_dash_or_a_device() {
    let world = World::new();
    let before = world.names();
    for args in [
        &["-o", "-"][..],
        &["--laplacian-out", "-"],
        &["--laplacian-out", "/dev/null"],
        &["--laplacian-out", "."],
    ] {
        let mut all = vec!["mesh", "mask.png"];
        all.extend_from_slice(args);
        let out = world.run(&all);
        expect(&out, 2, if args[1] == "-" { "`-`" } else { ".boundary" });
    }
    assert_eq!(world.names(), before);
    assert!(!Path::new("/dev/null.boundary").exists());
    let out = world.run(&[
        "mesh",
        "mask.png",
        "--laplacian-out",
        "l.mtx",
        "-o",
        "/dev/null",
    ]);
    expect(&out, 0, "");
    assert!(world.path("l.mtx").is_file() && world.path("l.mtx.boundary").is_file());
}

/// A value nested thousands deep (a loop of `m = [m]`) printed, compared, interpolated and
/// echoed: the scene's code runs on a stack that holds it, in every command, where the
/// main thread's 8 MB (and a `test` job's 2 MB) overflowed and aborted the process.
#[test]
fn values_nested_thousands_deep_do_not_overflow_the_stack() {
    let world = World::new();
    let deep = "let m = []; for i in 0..6000 { m = [m]; }\n";
    let uses = "print(m == m); let s = `${m}`; debug(s.len());\n";
    world.scene("deep.rhai", &format!("{deep}{uses}"));
    let check = world.run(&["check", "deep.rhai"]);
    expect(&check, 0, "[line 5, position");
    let render = world.run(&["render", "deep.rhai", "-o", "frames"]);
    expect(&render, 0, "");
    std::fs::create_dir(world.path("goldens")).unwrap();
    let test = world.run(&["test", "deep.rhai", "--update"]);
    expect(&test, 0, "");
    let input = format!("canvas(10, 10);\n{deep}m == m\nm\n:quit\n");
    let (code, all) = world.session(input.as_bytes());
    assert_eq!(code, Some(0), "{}", &all[all.len().saturating_sub(400)..]);
    assert!(all.contains("true") && all.contains("[[[[[[") && !all.contains("overflowed"));
}

/// An entry of a frame folder named like a frame but no regular file (a folder, a FIFO, a
/// link) is refused before anything is rendered: the folder is left as it was, where a
/// folder failed the moves half-way (some new frames in) and a FIFO or a link was replaced.
#[cfg(unix)]
#[test]
fn a_frame_folder_entry_that_is_no_regular_file_is_refused_and_kept() {
    let world = World::new();
    world.scene("s.rhai", "");
    world.write("notes.txt", "mine");
    std::fs::create_dir_all(world.path("out/frame_0003.png")).unwrap();
    let render = world.run(&["render", "s.rhai", "-o", "out"]);
    expect(&render, 1, "frame_0003.png is a folder, not a file");
    assert_eq!(sorted_names(&world.path("out")), ["frame_0003.png"]);
    std::fs::create_dir(world.path("out2")).unwrap();
    make_fifo(&world.path("out2/frame_0002.png"));
    std::os::unix::fs::symlink("../notes.txt", world.path("out2/frame_0001.png")).unwrap();
    let render = world.run(&["render", "s.rhai", "-o", "out2"]);
    expect(&render, 1, "is a symbolic link");
    // Another render's frame that is a link is not removed by --force either.
    std::fs::remove_file(world.path("out2/frame_0002.png")).unwrap();
    std::fs::remove_file(world.path("out2/frame_0001.png")).unwrap();
    std::os::unix::fs::symlink("../notes.txt", world.path("out2/frame_0009.png")).unwrap();
    let render = world.run(&["render", "s.rhai", "-o", "out2", "--force"]);
    expect(&render, 1, "frame_0009.png is a symbolic link");
    assert_eq!(sorted_names(&world.path("out2")), ["frame_0009.png"]);
    assert!(world
        .path("out2/frame_0009.png")
        .symlink_metadata()
        .unwrap()
        .file_type()
        .is_symlink());
}

/// `-` for a file a command writes but never streams is a usage error naming `./-`, where
/// it made a file named `-` (which looked like standard output).
#[test]
fn a_dash_for_a_file_that_is_never_streamed_is_a_usage_error() {
    let world = World::new();
    world.scene("s.rhai", "");
    std::fs::create_dir(world.path("goldens")).unwrap();
    let test = world.run(&["test", "s.rhai", "--junit", "-"]);
    expect(&test, 2, "--junit -: `-` means standard output");
    let repl = world.run(&["repl", "--preview", "-"]);
    expect(&repl, 2, "--preview -: `-` means standard output");
    // Nor PNG bytes under another image's name, as `preview -o x.jpg` refuses.
    let repl = world.run(&["repl", "--preview", "pv.jpg"]);
    expect(
        &repl,
        2,
        "--preview pv.jpg: the REPL writes PNG; name the output .png",
    );
    let (code, all) = world.session(b"canvas(8, 8);\n:save -\n:gif -\n");
    assert_eq!(code, Some(1), "{all}");
    assert_eq!(all.matches("`-` means standard output").count(), 2, "{all}");
    assert!(!world.path("-").exists());
}
