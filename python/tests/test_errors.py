"""Bad input raises the stated exception and never crashes the interpreter: wrong dtypes,
shapes, empty and mismatched arrays, non-finite placements, MIXED_CLONE, bad options, scene
files that are missing or wrong (lapclone.SceneError with file, line and column), and 1,000
random fixed-seed cases run in a child interpreter so a crash would show."""

import os
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import lapclone
from conftest import ASSETS, ROOT

SRC = np.full((40, 50, 3), 120, np.uint8)
DST = np.full((60, 70, 3), 30, np.uint8)
MASK = np.zeros((40, 50), np.uint8)
MASK[10:30, 10:40] = 255


@pytest.mark.parametrize(
    "src, dst, mask",
    [
        (SRC.astype(np.float32), DST, MASK),  # wrong dtype
        (SRC, DST.astype(np.int16), MASK),
        (SRC, DST, MASK.astype(np.float64)),
        (SRC[:0], DST, MASK[:0]),  # 0-sized
        (SRC, DST[:, :0], MASK),
        (SRC, DST, MASK[:39]),  # mask and src sizes differ
        (SRC[:, :, :2], DST, MASK),  # two channels
        (SRC[None], DST, MASK),  # four dimensions
        (SRC, DST, np.zeros_like(MASK)),  # nothing inside the mask
    ],
)
def test_bad_arrays_raise_value_error(src, dst, mask):
    with pytest.raises(ValueError):
        lapclone.seamless_clone(src, dst, mask, (35, 30))


def test_not_an_array_raises_type_error():
    with pytest.raises(TypeError):
        lapclone.seamless_clone(SRC.tolist(), DST, MASK, (35, 30))


@pytest.mark.parametrize("p", [(float("nan"), 3), (1.5, 2), (1, float("inf")), (1,), "ab"])
def test_bad_p_raises_value_error(p):
    with pytest.raises(ValueError):
        lapclone.seamless_clone(SRC, DST, MASK, p)


def test_mixed_clone_names_what_lapclone_offers():
    with pytest.raises(ValueError, match="NORMAL_CLONE.*MONOCHROME_TRANSFER"):
        lapclone.seamless_clone(SRC, DST, MASK, (35, 30), lapclone.MIXED_CLONE)
    with pytest.raises(ValueError):
        lapclone.seamless_clone(SRC, DST, MASK, (35, 30), 7)


@pytest.mark.parametrize(
    "kw",
    [
        dict(at=(float("nan"), 1)),
        dict(at=(1, float("inf"))),
        dict(at=(1, 2), scale=0.0),
        dict(at=(1, 2), scale=float("nan")),
        dict(at=(1, 2), rotate=float("inf")),
        dict(at=(1, 2), drags=[((1, 2),)]),
        dict(at=(1, 2), drags=[((1, 2), (3, float("nan")))]),
        dict(at=(1, 2), drags=[((1, 2), (3, 4), -1.0)]),
        dict(at=(1, 2), pins=[(float("nan"), 0)]),
        dict(at=(1, 2), anchor="middle"),
        dict(at=(1, 2), out=np.zeros((60, 70, 3), np.uint16)),
        dict(at=(1, 2), out=np.zeros((61, 70, 3), np.uint8)),
    ],
)
def test_bad_clone_arguments_raise_value_error(kw):
    cloner = lapclone.Cloner(SRC, MASK)
    with pytest.raises(ValueError):
        cloner.clone(DST, **kw)


def test_mask_of_another_size_raises_value_error():
    with pytest.raises(ValueError, match="mask"):
        lapclone.Cloner(SRC, MASK[:39])
    with pytest.raises(ValueError):
        lapclone.mesh(MASK[:, :0])


def test_read_only_out_raises_value_error():
    out = np.zeros_like(DST)
    out.flags.writeable = False
    with pytest.raises(ValueError):
        lapclone.Cloner(SRC, MASK).clone(DST, (30, 30), out=out)


@pytest.mark.parametrize(
    "kw",
    [dict(density=0.0), dict(density=float("nan")), dict(laplacian="x"), dict(mode="mixed"),
     dict(feather=-1.0), dict(boundary_data="edge")],
)
def test_bad_options_raise_value_error(kw):
    with pytest.raises(ValueError):
        lapclone.Cloner(SRC, MASK, **kw)


def test_missing_scene_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        lapclone.Scene(tmp_path / "nope.rhai")


def test_scene_error_has_file_line_and_column(tmp_path):
    path = tmp_path / "broken.rhai"
    path.write_text("canvas(64, 48, 24.0, 1.0);\nlet x = ;\n")
    with pytest.raises(lapclone.SceneError) as caught:
        lapclone.Scene(path)
    error = caught.value
    assert error.file == str(path)
    assert error.line == 2 and isinstance(error.column, int)
    assert f"{path}:2:" in str(error)


def test_scene_index_out_of_range():
    scene = lapclone.Scene(ROOT / "scenes" / "cat_in_coffee.rhai")
    with pytest.raises(IndexError):
        scene.frame(len(scene))


FUZZ = textwrap.dedent(
    """
    import numpy as np, lapclone
    rng = np.random.default_rng(42)
    dtypes = [np.uint8, np.uint16, np.float32, np.int32, bool]
    outcomes = {"ok": 0, "ValueError": 0, "TypeError": 0}
    for case in range(1000):
        def image(h, w):
            c = rng.choice([0, 1, 2, 3, 4, 5])
            shape = (h, w) if c == 0 else (h, w, c)
            dtype = dtypes[rng.integers(0, len(dtypes))] if rng.random() < 0.2 else np.uint8
            a = (rng.random(shape) * 255).astype(dtype)
            if rng.random() < 0.3 and a.ndim >= 2:
                a = a[::-1, ::2]
            return a
        h, w = int(rng.integers(0, 40)), int(rng.integers(0, 40))
        src = image(h, w)
        mask = (rng.random((h, w)) < rng.random()).astype(np.uint8) * 255
        if rng.random() < 0.1:
            mask = mask[: max(h - 1, 0)]
        dst = image(int(rng.integers(0, 50)), int(rng.integers(0, 50)))
        p = (int(rng.integers(-60, 110)), int(rng.integers(-60, 110)))
        try:
            if rng.random() < 0.5:
                out = lapclone.seamless_clone(src, dst, mask, p)
            else:
                at = (float(rng.normal(20, 40)), float(rng.normal(20, 40)))
                if rng.random() < 0.05:
                    at = (float("nan"), 0.0)
                c = lapclone.Cloner(src, mask, density=float(rng.uniform(0.5, 6)))
                out = c.clone(dst, at, scale=float(rng.uniform(0.2, 3)), rotate=float(rng.uniform(-180, 180)))
            assert out.shape == dst.shape and out.dtype == dst.dtype
            outcomes["ok"] += 1
        except (ValueError, TypeError) as e:
            outcomes[type(e).__name__] += 1
    print(outcomes)
    """
)


def test_random_inputs_never_crash():
    done = subprocess.run([sys.executable, "-c", FUZZ], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    outcomes = eval(done.stdout.strip().splitlines()[-1])
    assert sum(outcomes.values()) == 1000
    assert outcomes["ok"] > 50 and outcomes["ValueError"] > 50, outcomes


def test_arrays_past_the_image_limits_raise_value_error():
    # Zero strides declare a huge array without its memory: refused from the shape alone.
    huge = np.broadcast_to(np.uint8(255), (10**6, 10**6))
    for call in [
        lambda: lapclone.mesh(huge),
        lambda: lapclone.Cloner(SRC, huge),
        lambda: lapclone.seamless_clone(SRC, huge, MASK, (35, 30)),
        lambda: lapclone.mesh(np.full((16385, 1), 255, np.uint8)),
    ]:
        with pytest.raises(ValueError, match="size limit"):
            call()


def test_a_view_stepping_by_part_of_a_sample_is_refused():
    # A uint16 field of packed records: its strides are not whole samples.
    records = np.zeros((60, 70, 3), [("pad", "u1"), ("v", "<u2")])
    view = records["v"]
    assert view.strides[1] % view.itemsize != 0
    with pytest.raises(ValueError, match="ascontiguousarray"):
        lapclone.Cloner(SRC, MASK).clone(view, (35, 30))


def test_a_feather_past_the_limit_raises_value_error():
    with pytest.raises(ValueError, match="feather"):
        lapclone.Cloner(SRC, MASK, feather=4e9)


@pytest.mark.parametrize(
    "call, error",
    [
        (lambda: lapclone.Cloner(SRC, MASK, threads=-1), ValueError),
        (lambda: lapclone.Cloner(SRC, MASK, threads=2**64), ValueError),
        (lambda: lapclone.seamless_clone(SRC, DST, MASK, (35, 30), 2**63), ValueError),
        (lambda: lapclone.Cloner(SRC, MASK).clone(DST, (35, 30), scale=2**1024), ValueError),
        (lambda: lapclone.Cloner(SRC, MASK).clone(DST, (35, 30), rotate=-(2**1024)), ValueError),
        (lambda: lapclone.Scene(ROOT / "scenes" / "cat_in_coffee.rhai").frame(2**63), IndexError),
        (lambda: lapclone.Scene(ROOT / "scenes" / "cat_in_coffee.rhai")[-(2**64)], IndexError),
    ],
)
def test_numbers_out_of_range_raise_the_documented_errors(call, error):
    with pytest.raises(error, match="out of range"):
        call()


def test_a_target_reshaped_during_the_call_raises_value_error():
    target = DST.copy()

    class Reshaping:
        def __float__(self):
            target.shape = (70, 60, 3)
            return 35.0

    with pytest.raises(ValueError, match="changed shape"):
        lapclone.Cloner(SRC, MASK).clone(target, (Reshaping(), 30.0))


def test_a_subclass_copy_runs_no_code_inside_the_clone():
    # A subclass's own copy() would run while the clone holds its lock: a clone from there
    # waited for itself. The result is a plain array copied by numpy.
    cloner = lapclone.Cloner(SRC, MASK)
    calls = []

    class Reentrant(np.ndarray):
        def copy(self, *args, **kwargs):
            calls.append(cloner.clone(np.asarray(self), (1.0, 1.0)))
            return np.ndarray.copy(self)

    result = cloner.clone(DST.view(Reentrant), (35, 30))
    assert type(result) is np.ndarray and not calls
    assert np.array_equal(result, cloner.clone(DST, (35, 30)))


def test_a_scene_error_shows_its_line_around_the_column(tmp_path):
    path = tmp_path / "long.rhai"
    path.write_text("canvas(16, 16);\nlet s = 1 " + "+ 1 " * 50_000 + "@ 2;\n")
    with pytest.raises(lapclone.SceneError) as caught:
        lapclone.Scene(path)
    assert len(str(caught.value)) < 1000
    big = tmp_path / "big.rhai"
    big.write_text("canvas(16, 16);\n//" + "x" * (17 << 20) + "\n")
    with pytest.raises(lapclone.SceneError, match="larger than 16 MiB"):
        lapclone.Scene(big)


@pytest.mark.parametrize(
    "call, shown",
    [
        (lambda: lapclone.Cloner(SRC, MASK, density=-1e300), "-1e300"),
        (lambda: lapclone.mesh(MASK, density=-1e300), "-1e300"),
        (lambda: lapclone.Cloner(SRC, MASK, feather=1e300), "not 1e300"),
        (lambda: lapclone.Cloner(SRC, MASK, feather=1e39), "not 1e39"),
        (lambda: lapclone.seamless_clone(SRC, DST, MASK, (1e300, 0)), "1e300 is past"),
        (lambda: lapclone.seamless_clone(SRC, DST, MASK, (2**63, 0)), "is past"),
        (lambda: lapclone.Cloner(SRC, MASK).clone(DST, (1, 1), scale=-1e300), "-1e300"),
        (lambda: lapclone.Cloner(SRC, MASK).clone(DST, (1e-300, 1e300)), "1e300 is past"),
        (lambda: lapclone.Cloner(SRC, MASK).clone(DST, (1, 1), drags=[((20, 20), (1e300, 20))]),
         "1e300 is past"),
        (lambda: lapclone.Cloner(SRC, MASK).clone(DST, (1, 1), drags=[((1, 1), (2, 2), -1e300)]),
         "-1e300"),
    ],
)
def test_extreme_numbers_are_named_short(call, shown):
    with pytest.raises(ValueError) as caught:
        call()
    message = str(caught.value)
    assert shown in message, message
    assert "0" * 20 not in message, message


@pytest.mark.parametrize(
    "call",
    [
        lambda: lapclone.Cloner(SRC, MASK, density=10**400),
        lambda: lapclone.Cloner(SRC, MASK, feather=10**400),
        lambda: lapclone.mesh(MASK, density=10**400),
    ],
)
def test_integers_too_large_for_a_float_raise_value_error(call):
    with pytest.raises(ValueError, match="out of range"):
        call()


def test_a_pair_may_be_a_tuple_a_list_or_an_array():
    cloner = lapclone.Cloner(SRC, MASK)
    want = cloner.clone(DST, (35, 30))
    for at in ([35, 30], np.array([35.0, 30.0])):
        assert np.array_equal(cloner.clone(DST, at), want)
    want = lapclone.seamless_clone(SRC, DST, MASK, (35, 30))
    assert np.array_equal(lapclone.seamless_clone(SRC, DST, MASK, [35, 30]), want)
    dragged = cloner.clone(DST, (35, 30), drags=[((20, 20), (24, 22))], pins=[(5, 5)])
    listed = cloner.clone(DST, (35, 30), drags=[[[20, 20], [24, 22]]], pins=[[5, 5]])
    assert np.array_equal(dragged, listed)
    with pytest.raises(ValueError, match="two numbers"):
        cloner.clone(DST, [1, 2, 3])


def test_a_scene_path_that_is_not_a_file_says_what_it_is(tmp_path):
    with pytest.raises(IsADirectoryError, match="is a folder"):
        lapclone.Scene(tmp_path)
    fifo = tmp_path / "scene.rhai"
    os.mkfifo(fifo)
    with pytest.raises(ValueError, match="not a regular file"):
        lapclone.Scene(fifo)


def test_an_empty_output_path_is_refused_before_rendering():
    scene = lapclone.Scene(ROOT / "scenes" / "cat_in_coffee.rhai")
    for fmt in (None, "gif"):
        with pytest.raises(ValueError, match="empty"):
            scene.render("", format=fmt)


def test_a_frame_that_fails_raises_the_scene_error_render_raises(tmp_path):
    plates = tmp_path / "plates"
    plates.mkdir()
    for k in (1, 2, 3):
        shutil.copy(ASSETS / "coffee.png", plates / f"frame_{k:04d}.png")
    path = tmp_path / "plates.rhai"
    path.write_text('canvas(#{ fps: 24, duration: 0.125, background: "plates/frame_%04d.png" });\n')
    scene = lapclone.Scene(path)
    (plates / "frame_0002.png").unlink()
    with pytest.raises(lapclone.SceneError) as caught:
        scene[1]
    assert caught.value.line == 1 and "frame_0002.png" in str(caught.value)
    with pytest.raises(lapclone.SceneError) as rendered:
        scene.render(str(tmp_path / "out.gif"))
    assert rendered.value.line == caught.value.line


@pytest.mark.parametrize(
    "out, message",
    [
        (np.zeros((60, 70, 3), np.uint16),
         "out must be a uint8 array of shape (60, 70, 3), as the target is, "
         "not a uint16 array of shape (60, 70, 3)"),
        (np.zeros((70, 60, 3), np.uint8),
         "out must be a uint8 array of shape (60, 70, 3), as the target is, "
         "not a uint8 array of shape (70, 60, 3)"),
        (np.zeros((60, 70), np.uint8),
         "out must be a uint8 array of shape (60, 70, 3), as the target is, "
         "not a uint8 array of shape (60, 70)"),
        (np.zeros((60, 70, 3), np.float32), "out must have dtype uint8 or uint16, not float32"),
        (np.zeros((60, 70, 2), np.uint8),
         "out must have shape (H, W) (grey) or (H, W, C) with C = 1, 3 or 4, not (60, 70, 2)"),
        (np.zeros(60, np.uint8),
         "out must have shape (H, W) (grey) or (H, W, C) with C = 1, 3 or 4, not (60,)"),
    ],
)
def test_a_wrong_out_array_is_named_as_numpy_names_it(out, message):
    with pytest.raises(ValueError) as caught:
        lapclone.Cloner(SRC, MASK).clone(DST, (35, 30), out=out)
    assert str(caught.value) == message


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: lapclone.Cloner(SRC, MASK).clone(DST[:, :0], (35, 30)),
         "target is empty: shape (60, 0, 3)"),
        (lambda: lapclone.seamless_clone(SRC, DST, MASK[:39], (35, 30)),
         "mask has height and width (39, 50) but src (40, 50): they must be the same"),
        (lambda: lapclone.mesh(np.broadcast_to(np.uint8(255), (20000, 10))),
         "mask of shape (20000, 10) exceeds the image size limit"),
    ],
)
def test_array_sizes_are_numpy_shapes(call, message):
    with pytest.raises(ValueError) as caught:
        call()
    assert str(caught.value).startswith(message), str(caught.value)
    assert "×" not in str(caught.value)


def test_a_mask_of_another_size_names_no_mask_offset():
    # `lapclone clone` takes --mask-offset for a smaller mask; Cloner takes none.
    with pytest.raises(ValueError) as caught:
        lapclone.Cloner(SRC, MASK[:39])
    message = str(caught.value)
    assert message.startswith("mask has height and width (39, 50) but source (40, 50)"), message
    assert "crop or pad the mask" in message and "offset" not in message


def test_a_boundary_past_the_vertex_budget_names_density_not_max_vertices():
    # 562,500 pieces of 2×2 pixels: 2,250,000 boundary vertices, past the 2,000,000 a mesh
    # may have; Python has no max_vertices to raise.
    mask = np.zeros((3000, 3000), np.uint8)
    mask.reshape(750, 4, 750, 4)[:, :2, :, :2] = 255
    for call in (lambda: lapclone.mesh(mask), lambda: lapclone.Cloner(mask, mask)):
        with pytest.raises(ValueError) as caught:
            call()
        message = str(caught.value)
        assert "2250000 vertices" in message and "raise density" in message, message
        assert "max_vertices" not in message, message
