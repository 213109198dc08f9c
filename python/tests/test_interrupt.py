"""Ctrl-C stops a long render: `Scene.render` raises KeyboardInterrupt within moments (the
frame in progress finishes), the output does not appear and no temporary file or folder is
left beside it; `list(scene)` stops between frames. Each run is a child interpreter sent
SIGINT, as a terminal's Ctrl-C would."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from conftest import ASSETS

# Python turns SIGINT into KeyboardInterrupt only when it was not ignored at start (a
# background job of a non-interactive shell starts with it ignored): the handler is set
# explicitly, as an interactive session has it.
CHILD = textwrap.dedent(
    """
    import signal, sys
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import lapclone
    scene = lapclone.Scene(sys.argv[1])
    print("ready", flush=True)
    try:
        if sys.argv[2] == "list":
            list(scene)
        else:
            scene.render(sys.argv[2])
    except KeyboardInterrupt:
        print("interrupted", flush=True)
        sys.exit(3)
    print("finished", flush=True)
    """
)


def long_scene(folder):
    """A small scene of 100,000 frames (fps 100, 1000 s): minutes to render whole."""
    scene = folder / "long.rhai"
    scene.write_text(
        f'canvas(64, 48, #{{ fps: 100, duration: 1000, background: "{ASSETS / "coffee.png"}" }});\n'
        f'let p = patch("tri", #{{ source: "{ASSETS / "chelsea.png"}", '
        "polygons: [[[10, 10], [50, 14], [20, 40]]] });\n"
        'p.at(0, [20, 20]).at(1000, [40, 24], "smooth");\n'
    )
    return scene


def interrupt(scene, target, started):
    """Runs the child on `target`, sends SIGINT once `started()` holds (or after 5 s), and
    gives its exit code, its output and how long it took to stop after the signal."""
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(scene), str(target)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout.readline().strip() == "ready"
        deadline = time.monotonic() + 5
        while not started() and time.monotonic() < deadline:
            time.sleep(0.01)
        # Some frames in, so the signal lands mid-render.
        time.sleep(0.2)
        assert child.poll() is None, "the render ended before the signal"
        os.kill(child.pid, signal.SIGINT)
        sent = time.monotonic()
        out, err = child.communicate(timeout=5)
        return child.returncode, out, err, time.monotonic() - sent
    except subprocess.TimeoutExpired:
        pytest.fail("the child did not stop within 5 s of SIGINT")
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()


@pytest.mark.parametrize("name", ["clip.y4m", "frames", "clip.gif"])
def test_ctrl_c_stops_a_render_and_leaves_no_output(tmp_path, name):
    scene = long_scene(tmp_path)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    target = out_dir / name
    code, out, err, took = interrupt(scene, target, lambda: any(out_dir.iterdir()))
    assert code == 3 and "interrupted" in out, (code, out, err)
    assert took < 3, took
    assert not target.exists()
    assert list(out_dir.iterdir()) == []


def test_ctrl_c_stops_iterating_a_scene(tmp_path):
    code, out, err, took = interrupt(long_scene(tmp_path), "list", lambda: True)
    assert code == 3 and "interrupted" in out, (code, out, err)
    assert took < 3, took
