"""Scene.render writes the files `lapclone render` writes, byte for byte (a PNG folder, a
Y4M stream, a GIF, an APNG; MP4 when ffmpeg is installed), and refuses what the CLI refuses:
a bad format, a missing output folder, an output that is one of the scene's inputs."""

import shutil
from pathlib import Path

import pytest

import lapclone
from conftest import ASSETS


def write_scene(folder):
    """A 96×64 scene of 4 frames (fps 4, 1 s): a dragged, moving triangle patch."""
    scene = folder / "tiny.rhai"
    scene.write_text(
        f'canvas(96, 64, #{{ fps: 4, duration: 1, background: "{ASSETS / "coffee.png"}" }});\n'
        f'let p = patch("tri", #{{ source: "{ASSETS / "chelsea.png"}", '
        "polygons: [[[10, 10], [80, 14], [30, 60]]] });\n"
        'p.at(0, [40, 30]).at(1, [60, 34], "smooth");\n'
        "p.drag([60, 16], 20).key(0, [60, 16]).key(1, [66, 24]);\n"
    )
    return scene


def files_of(path):
    """{relative name: bytes} of a file or of every file in a folder."""
    path = Path(path)
    if path.is_file():
        return {"": path.read_bytes()}
    return {p.relative_to(path).as_posix(): p.read_bytes() for p in sorted(path.rglob("*"))}


@pytest.mark.parametrize(
    "name, format",
    [("frames", None), ("shot.png", None), ("clip.y4m", None), ("clip.gif", None),
     ("clip.apng", None), ("named.bin", "y4m"), ("anim", "gif")],
)
def test_render_writes_what_lapclone_render_writes(cli, tmp_path, name, format):
    scene_file = write_scene(tmp_path)
    (tmp_path / "py").mkdir()
    (tmp_path / "cli").mkdir()
    got = tmp_path / "py" / name
    written = lapclone.Scene(scene_file).render(got, format=format)
    assert Path(written) == got
    want = tmp_path / "cli" / name
    cli("render", scene_file, "-o", want, *(["--format", format] if format else []))
    got_files, want_files = files_of(got), files_of(want)
    assert len(got_files) >= 1
    if format is None and name in ("frames", "shot.png"):
        assert sorted(got_files) == [f"frame_{i:04d}.png" for i in range(1, 5)]
    assert got_files == want_files


def test_render_takes_a_str_path_and_renders_again(tmp_path):
    scene = lapclone.Scene(write_scene(tmp_path))
    first = scene.render(str(tmp_path / "a.y4m"))
    scene.frame(2)  # the renderer's state between renders changes nothing
    second = scene.render(str(tmp_path / "b.y4m"))
    assert Path(first).read_bytes() == Path(second).read_bytes()


def test_bad_format_raises_value_error(tmp_path):
    scene = lapclone.Scene(write_scene(tmp_path))
    with pytest.raises(ValueError, match="unknown output format `jpeg`"):
        scene.render(tmp_path / "out", format="jpeg")
    with pytest.raises(ValueError, match=r"unknown output extension `\.bmp`"):
        scene.render(tmp_path / "out.bmp")
    assert not (tmp_path / "out").exists() and not (tmp_path / "out.bmp").exists()


def test_missing_output_folder_raises_file_not_found(tmp_path):
    scene = lapclone.Scene(write_scene(tmp_path))
    with pytest.raises(FileNotFoundError, match="does not exist"):
        scene.render(tmp_path / "nowhere" / "clip.gif")
    with pytest.raises(FileNotFoundError):
        scene.render(tmp_path / "nowhere" / "frames")


def test_output_that_is_an_input_is_refused(tmp_path):
    scene_file = write_scene(tmp_path)
    scene = lapclone.Scene(scene_file)
    before = scene_file.read_bytes()
    # The scene file itself, named as a Y4M stream.
    with pytest.raises(ValueError, match="would replace an input"):
        scene.render(scene_file, format="y4m")
    assert scene_file.read_bytes() == before
    # A copy of the background is an input of a second scene.
    background = tmp_path / "bg.png"
    shutil.copy(ASSETS / "coffee.png", background)
    other = tmp_path / "other.rhai"
    other.write_text(scene_file.read_text().replace(str(ASSETS / "coffee.png"), str(background)))
    with pytest.raises(ValueError, match="would replace an input"):
        lapclone.Scene(other).render(background, format="gif")
    assert background.read_bytes() == (ASSETS / "coffee.png").read_bytes()


def test_file_output_over_a_folder_raises_is_a_directory(tmp_path):
    scene = lapclone.Scene(write_scene(tmp_path))
    (tmp_path / "taken.gif").mkdir()
    with pytest.raises(IsADirectoryError, match="is a folder"):
        scene.render(tmp_path / "taken.gif")


def test_mp4_through_ffmpeg_is_lapclone_render(cli, tmp_path):
    if shutil.which("ffmpeg") is None:
        print("skipping: ffmpeg is not installed")
        pytest.skip("ffmpeg is not installed: video output needs it")
    scene_file = write_scene(tmp_path)
    got, want = tmp_path / "py.mp4", tmp_path / "cli.mp4"
    lapclone.Scene(scene_file).render(got)
    cli("render", scene_file, "-o", want)
    assert got.stat().st_size > 0
    assert got.read_bytes() == want.read_bytes()
