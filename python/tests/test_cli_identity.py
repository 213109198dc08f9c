"""The Python API gives the pixels `lapclone clone` and `lapclone render` write, byte for
byte: seamless_clone (cv2's arguments and placement), Cloner.clone with scale, rotation,
drags and pins, grey, 16-bit and RGBA targets, non-contiguous arrays and `out=`, and
Scene.frame against the rendered PNG frames."""

import numpy as np
import pytest

import lapclone
from conftest import ROOT, load_asset, read_png, smooth_target, spiral_mask, textured_source, write_png


def bbox(mask):
    ys, xs = np.nonzero(mask >= 128)
    return xs.min(), ys.min(), xs.max() + 1, ys.max() + 1


def cli_clone(cli, tmp_path, source_rgb, mask, target, extra):
    """`lapclone clone` on PNGs of the arrays; the output PNG as an H×W×C array."""
    write_png(tmp_path / "source.png", source_rgb)
    write_png(tmp_path / "mask.png", mask)
    write_png(tmp_path / "target.png", target)
    out = tmp_path / "out.png"
    cli("clone", "--source", tmp_path / "source.png", "--mask", tmp_path / "mask.png",
        "--target", tmp_path / "target.png", "-o", out, *extra)
    return read_png(out)


def cv2_at(mask, p):
    """The `--anchor topleft --at` that puts the mask where cv2.seamlessClone puts it."""
    x0, y0, x1, y1 = bbox(mask)
    return ["--anchor", "topleft", "--at", f"{p[0] - (x1 - x0) // 2},{p[1] - (y1 - y0) // 2}"]


@pytest.mark.parametrize("p", [(288, 143), (301, 200)])
def test_seamless_clone_is_lapclone_clone_on_the_cat(cli, tmp_path, p):
    src = load_asset("chelsea.png")
    mask = load_asset("masks/chelsea_face.png")
    dst = load_asset("coffee.png")
    got = lapclone.seamless_clone(src[:, :, ::-1].copy(), dst[:, :, ::-1].copy(), mask, p)
    want = cli_clone(cli, tmp_path, src, mask, dst, cv2_at(mask, p))
    assert got.shape == dst.shape and got.dtype == np.uint8
    assert np.array_equal(got[:, :, ::-1], want)
    assert not np.array_equal(got[:, :, ::-1], dst), "the clone changed nothing"


def test_seamless_clone_is_lapclone_clone_on_the_spiral(cli, tmp_path):
    src = textured_source(400, 400)
    mask = spiral_mask(400, 400)
    dst = smooth_target(520, 460)
    p = (260, 230)
    got = lapclone.seamless_clone(src[:, :, ::-1], dst[:, :, ::-1], mask, p)
    want = cli_clone(cli, tmp_path, src, mask, dst, cv2_at(mask, p))
    assert np.array_equal(got[:, :, ::-1], want)


def test_monochrome_transfer_is_lapclone_clone_monochrome(cli, tmp_path):
    src = load_asset("chelsea.png")
    mask = load_asset("masks/chelsea_face.png")
    dst = load_asset("coffee.png")
    p = (288, 143)
    got = lapclone.seamless_clone(src[:, :, ::-1], dst[:, :, ::-1], mask, p, lapclone.MONOCHROME_TRANSFER)
    want = cli_clone(cli, tmp_path, src, mask, dst, cv2_at(mask, p) + ["--mode", "monochrome"])
    assert np.array_equal(got[:, :, ::-1], want)


def test_seamless_clone_at_the_border_is_lapclone_clone_clipped(cli, tmp_path):
    src = textured_source(120, 100)
    mask = np.zeros((100, 120), np.uint8)
    mask[20:80, 10:110] = 255
    dst = smooth_target(200, 150)
    p = (15, 140)  # the patch's left and bottom parts fall outside dst
    got = lapclone.seamless_clone(src[:, :, ::-1], dst[:, :, ::-1], mask, p)
    want = cli_clone(cli, tmp_path, src, mask, dst, cv2_at(mask, p))
    assert np.array_equal(got[:, :, ::-1], want)


CLONES = [
    dict(at=(300.5, 190.25)),
    dict(at=(280.0, 170.0), scale=1.25, rotate=-17.0),
    dict(at=(290.0, 160.0), drags=[((213, 150), (240, 120))], pins=[(120, 100)]),
    dict(at=(290.0, 160.0), drags=[((213, 150), (200, 180), 30.0)], rotate=8.0),
]


def cli_args(kw):
    args = ["--at", "{},{}".format(*kw["at"])]
    if "scale" in kw:
        args += ["--scale", kw["scale"]]
    if "rotate" in kw:
        args += ["--rotate", kw["rotate"]]
    for d in kw.get("drags", []):
        text = "{},{}:{},{}".format(*d[0], *d[1])
        args += ["--drag", text + (f":{d[2]}" if len(d) == 3 else "")]
    for pin in kw.get("pins", []):
        args += ["--pin", "{},{}".format(*pin)]
    return args


@pytest.mark.parametrize("kw", CLONES)
def test_cloner_is_lapclone_clone(cli, tmp_path, kw):
    src = load_asset("chelsea.png")
    mask = load_asset("masks/chelsea_face.png")
    dst = load_asset("coffee.png")
    got = lapclone.Cloner(src, mask).clone(dst, **kw)
    want = cli_clone(cli, tmp_path, src, mask, dst, cli_args(kw))
    assert np.array_equal(got, want)


def test_cloner_reused_matches_fresh_clones(cli, tmp_path):
    """A factor re-used over moves gives each clone's own `lapclone clone` pixels."""
    src = load_asset("chelsea.png")
    mask = load_asset("masks/chelsea_face.png")
    dst = load_asset("coffee.png")
    cloner = lapclone.Cloner(src, mask, density=4.0)
    for at in [(250, 150), (320.5, 180), (90, 60), (580, 390)]:
        got = cloner.clone(dst, at)
        want = cli_clone(cli, tmp_path, src, mask, dst, ["--at", f"{at[0]},{at[1]}", "--density", 4])
        assert np.array_equal(got, want), at


def test_grey_16bit_and_rgba_targets(cli, tmp_path):
    src = textured_source(96, 96)
    mask = spiral_mask(96, 96)
    rgb = smooth_target(130, 110)
    grey = (rgb.astype(np.uint32).sum(axis=2) // 3).astype(np.uint8)
    sixteen = (rgb.astype(np.uint16) * 257 + np.arange(130, dtype=np.uint16)[None, :, None])
    rgba = np.dstack([rgb, np.full(rgb.shape[:2], 200, np.uint8)])
    cloner = lapclone.Cloner(src, mask)
    for target in [grey, sixteen, rgba]:
        got = cloner.clone(target, (64, 55), rotate=10)
        want = cli_clone(cli, tmp_path, src, mask, target, ["--at", "64,55", "--rotate", 10])
        want = want[:, :, 0] if target.ndim == 2 else want
        assert got.dtype == target.dtype and got.shape == target.shape
        assert np.array_equal(got, want), target.dtype


def test_sixteen_bit_and_grey_sources(cli, tmp_path):
    rgb = textured_source(96, 96)
    mask = spiral_mask(96, 96)
    target = smooth_target(130, 110)
    sixteen = rgb.astype(np.uint16) * 257 + 3
    grey = rgb[:, :, 1].copy()
    for source in [sixteen, grey]:
        got = lapclone.Cloner(source, mask, mode="monochrome").clone(target, (60.5, 50))
        want = cli_clone(cli, tmp_path, source, mask, target, ["--at", "60.5,50", "--mode", "monochrome"])
        assert np.array_equal(got, want), source.dtype


def test_bgr_non_contiguous_and_out(cli, tmp_path):
    src = load_asset("chelsea.png")
    mask = load_asset("masks/chelsea_face.png")
    dst = load_asset("coffee.png")
    want = cli_clone(cli, tmp_path, src, mask, dst, ["--at", "288,143"])
    # BGR views with negative strides, a Fortran-ordered mask.
    cloner = lapclone.Cloner(src[:, :, ::-1], np.asfortranarray(mask), bgr=True)
    bgr = dst[:, :, ::-1]
    assert np.array_equal(cloner.clone(bgr, (288, 143))[:, :, ::-1], want)
    out = np.zeros_like(bgr)
    result = cloner.clone(bgr, (288, 143), out=out)
    assert result is out and np.array_equal(out[:, :, ::-1], want)
    in_place = bgr.copy()
    cloner.clone(in_place, (288, 143), out=in_place)
    assert np.array_equal(in_place[:, :, ::-1], want)


def test_scene_frames_are_lapclone_render(cli, tmp_path):
    scene = lapclone.Scene(ROOT / "scenes" / "cat_in_coffee.rhai")
    assert len(scene) == 72 and scene.size == (600, 400) and scene.fps == 24
    cli("render", ROOT / "scenes" / "cat_in_coffee.rhai", "-o", tmp_path / "frames", "--frames", "10..12")
    for i in (9, 10, 11):
        want = read_png(tmp_path / "frames" / f"frame_{i + 1:04d}.png")
        got = scene.frame(i)
        assert got.shape == (400, 600, 4) and got.dtype == np.uint8
        if want.shape[2] == 3:  # the render writes opaque frames as RGB
            assert (got[:, :, 3] == 255).all()
            got = got[:, :, :3]
        assert np.array_equal(got, want), i
    bgra = lapclone.Scene(ROOT / "scenes" / "cat_in_coffee.rhai", bgr=True)
    assert np.array_equal(bgra[10][:, :, [2, 1, 0, 3]], scene.frame(10))
    assert np.array_equal(scene[-1], scene.frame(71))
    frames = iter(scene)
    assert np.array_equal(next(frames), scene.frame(0))
