"""Inputs a Python user can give that once hung, lost data or were misread: masks viewed as
bool from 0/255 bytes, colour masks in RGB order, a clone called again from a finaliser
while one runs, `render("-")` when Python's standard output is not file descriptor 1,
Ctrl-C while a scene file runs, a frame folder of another render, and one frame iterator
shared by threads."""

import os
import signal
import subprocess
import sys
import textwrap
import threading

import numpy as np
import pytest

import lapclone
from conftest import ASSETS, textured_source


def square_mask(value, dtype=np.uint8):
    mask = np.zeros((60, 80), dtype)
    mask[15:45, 20:60] = value
    return mask


def run_python(code, timeout=60, **kw):
    """Runs `code` in a fresh interpreter; gives the finished process."""
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=timeout,
        **kw,
    )


def test_a_bool_view_of_0_255_bytes_is_inside_wherever_numpy_says_true():
    source = textured_source(80, 60)
    bytes_255 = square_mask(255)
    mixed = bytes_255.copy()
    mixed[:, :40] //= 255  # the left half stored as 1, the right half as 255
    expected = lapclone.Cloner(source, bytes_255 > 0).bbox
    for view in (bytes_255.view(bool), mixed.view(bool)):
        assert np.count_nonzero(view) == 1200
        assert lapclone.Cloner(source, view).bbox == expected
        vertices, _ = lapclone.mesh(view)
        reference, _ = lapclone.mesh(bytes_255 > 0)
        assert np.array_equal(vertices, reference)


def test_a_colour_mask_is_read_in_the_order_the_call_says():
    # Orange in RGB: luma 146, inside; read as BGR it would be azure, luma 104, outside.
    rgb = np.zeros((60, 80, 3), np.uint8)
    rgb[15:45, 20:60] = (255, 128, 0)
    grey = square_mask(255)
    source = textured_source(80, 60)
    inside = lapclone.Cloner(source, grey).bbox
    assert lapclone.Cloner(source, rgb).bbox == inside
    assert lapclone.Cloner(source[..., ::-1], rgb[..., ::-1], bgr=True).bbox == inside
    assert np.array_equal(lapclone.mesh(rgb)[0], lapclone.mesh(grey)[0])
    assert np.array_equal(lapclone.mesh(rgb[..., ::-1], bgr=True)[0], lapclone.mesh(grey)[0])
    with pytest.raises(ValueError, match="no inside pixels"):
        lapclone.mesh(rgb[..., ::-1])


def test_a_clone_called_from_a_finaliser_during_a_clone_raises_instead_of_hanging():
    # Garbage collection can run inside a clone (numpy allocates the result) and call a
    # finaliser that clones with the same Cloner: it must get an error, not wait forever.
    done = run_python(
        """
        import gc, numpy as np, lapclone
        src = np.zeros((60, 80, 3), np.uint8)
        mask = np.zeros((60, 80), np.uint8); mask[15:45, 20:60] = 255
        dst = np.zeros((120, 160, 3), np.uint8)
        C = lapclone.Cloner(src, mask); C.clone(dst, (80, 60))
        seen = []
        class Frame:
            def __init__(self): self.me = self
            def __del__(self):
                try:
                    C.clone(dst, (10, 10))
                    seen.append("cloned")
                except RuntimeError as e:
                    seen.append(str(e))
        for k in range(1, 12):
            gc.collect(); gc.disable(); Frame()
            gc.set_threshold(gc.get_count()[0] + k); gc.enable()
            C.clone(dst, (80, 60))
        gc.collect()
        print(sorted(set(seen)))
        """,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert "already cloning on this thread" in done.stdout, done.stdout


def test_render_to_standard_output_refuses_a_replaced_descriptor(tmp_path):
    scene = tmp_path / "s.rhai"
    scene.write_text('canvas(16, 8, #{ fps: 2, duration: 1, background: "#204080" });\n')
    log = tmp_path / "user.log"
    # With file descriptor 1 closed at start, Python's sys.stdout is None and the next file
    # opened takes descriptor 1: the frames must not go into it.
    code = f"""
        import lapclone
        log = open({str(log)!r}, "w"); log.write("my log\\n"); log.flush()
        try:
            lapclone.Scene({str(scene)!r}).render("-")
        except ValueError as e:
            log.write("refused: " + str(e) + "\\n")
        log.close()
    """
    done = run_python(code, stdout=None, stdin=subprocess.DEVNULL, close_fds=True,
                      preexec_fn=lambda: os.close(1))
    assert done.returncode == 0, done.stderr
    text = log.read_text()
    assert text.startswith("my log\nrefused: "), text[:200]
    assert "standard output" in text
    assert "YUV4MPEG2" not in text


def test_render_to_standard_output_flushes_what_python_printed_first(tmp_path):
    scene = tmp_path / "s.rhai"
    scene.write_text('canvas(16, 8, #{ fps: 2, duration: 1, background: "#204080" });\n')
    code = f"""
        import lapclone, sys
        print("before", end="")
        lapclone.Scene({str(scene)!r}).render("-")
    """
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(b"beforeYUV4MPEG2 "), done.stdout[:40]


def test_ctrl_c_stops_a_scene_file_that_runs_long(tmp_path):
    scene = tmp_path / "slow.rhai"
    scene.write_text("canvas(64, 64); let a = []; for i in 0..300000 { a.push(i); }\n")
    child = subprocess.Popen(
        [sys.executable, "-c", f"import lapclone; lapclone.Scene({str(scene)!r})"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        # Give it time to import and start the scene (which runs for many seconds).
        threading.Event().wait(2.0)
        child.send_signal(signal.SIGINT)
        _, stderr = child.communicate(timeout=10)
    finally:
        child.kill()
    assert "KeyboardInterrupt" in stderr, stderr


def test_a_frame_folder_of_another_render_names_force_and_force_replaces_it(tmp_path):
    long_scene = tmp_path / "long.rhai"
    long_scene.write_text('canvas(16, 8, #{ fps: 4, duration: 2, background: "#204080" });\n')
    short_scene = tmp_path / "short.rhai"
    short_scene.write_text('canvas(16, 8, #{ fps: 4, duration: 1, background: "#802040" });\n')
    out = tmp_path / "out"
    lapclone.Scene(long_scene).render(out)
    assert len(list(out.iterdir())) == 8
    with pytest.raises(FileExistsError) as error:
        lapclone.Scene(short_scene).render(out)
    assert "force=True" in str(error.value) and "--force" not in str(error.value)
    assert len(list(out.iterdir())) == 8
    lapclone.Scene(short_scene).render(out, force=True)
    assert sorted(p.name for p in out.iterdir()) == [f"frame_{i:04}.png" for i in range(1, 5)]


def test_one_frame_iterator_shared_by_threads_gives_each_frame_once():
    scene = lapclone.Scene(ASSETS.parent / "scenes" / "cat_in_coffee.rhai")
    frames = iter(scene)
    got, errors = [], []

    def take():
        try:
            for frame in frames:
                got.append(frame.tobytes())
        except Exception as e:  # noqa: BLE001 (the test reports any)
            errors.append(repr(e))

    threads = [threading.Thread(target=take) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert sorted(got) == sorted(scene.frame(i).tobytes() for i in range(len(scene)))
