"""Shared pieces of the Python package's tests: the repository's assets, synthetic images
(a textured source, a smooth target, the paper's spiral mask), PNG files in and out (pypng,
8 and 16 bit) and the `lapclone` program, found through LAPCLONE_BIN (set by .ci/run); tests
that need it skip with the reason when it is absent."""

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
ASSETS = ROOT / "assets"


def lapclone_bin():
    """The `lapclone` program: $LAPCLONE_BIN, else target/release/lapclone, else None."""
    candidates = [os.environ.get("LAPCLONE_BIN"), str(ROOT / "target" / "release" / "lapclone")]
    for candidate in candidates:
        if candidate and Path(candidate).is_file() and os.access(candidate, os.X_OK):
            return candidate
    return shutil.which("lapclone")


@pytest.fixture
def cli():
    program = lapclone_bin()
    if program is None:
        pytest.skip("the lapclone program is absent: set LAPCLONE_BIN or build target/release/lapclone")

    def run(*args):
        done = subprocess.run([program, *map(str, args)], capture_output=True, text=True)
        assert done.returncode == 0, f"lapclone {' '.join(map(str, args))}: {done.stderr}"
        return done

    return run


def write_png(path, array):
    """Writes an H×W (grey) or H×W×C uint8/uint16 RGB(A) array as a PNG."""
    import png

    array = np.ascontiguousarray(array)
    channels = 1 if array.ndim == 2 else array.shape[2]
    depth = 16 if array.dtype == np.uint16 else 8
    writer = png.Writer(
        width=array.shape[1],
        height=array.shape[0],
        greyscale=channels in (1, 2),
        alpha=channels in (2, 4),
        bitdepth=depth,
    )
    rows = array.reshape(array.shape[0], -1)
    with open(path, "wb") as f:
        writer.write(f, rows.tolist())


def read_png(path):
    """A PNG as an H×W×C array of its own depth and channels (C = 1 for grey)."""
    import png

    width, height, rows, info = png.Reader(filename=str(path)).read()
    dtype = np.uint16 if info["bitdepth"] == 16 else np.uint8
    data = np.array([np.asarray(row, dtype=dtype) for row in rows])
    return data.reshape(height, width, info["planes"])


@pytest.fixture(autouse=True, scope="session")
def _pypng():
    pytest.importorskip("png", reason="pypng writes and reads the PNG files the CLI sees")


def load_asset(name):
    """An asset PNG as RGB (H×W×3) or grey (H×W) uint8."""
    array = read_png(ASSETS / name)
    return array[:, :, 0] if array.shape[2] == 1 else array[:, :, :3]


def textured_source(width, height, seed=1):
    """A colourful source with detail at every scale."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    rng = np.random.default_rng(seed)
    noise = rng.integers(0, 40, size=(height, width, 3))
    r = 128 + 100 * np.sin(x / 7.0) * np.cos(y / 11.0)
    g = 128 + 90 * np.cos((x + y) / 9.0)
    b = 60 + 150 * (x / max(width - 1, 1))
    image = np.stack([r, g, b], axis=2) + noise - 20
    return np.clip(image, 0, 255).astype(np.uint8)


def smooth_target(width, height):
    """A smooth gradient target."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    r = 40 + 160 * x / max(width - 1, 1)
    g = 200 - 120 * y / max(height - 1, 1)
    b = 90 + 60 * np.sin(x / 40.0 + y / 50.0)
    return np.clip(np.stack([r, g, b], axis=2), 0, 255).astype(np.uint8)


def spiral_mask(width, height):
    """The paper's spiral band (as tests/common/synth_masks.rs's spiral), 255 inside."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    cx, cy = width / 2.0, height / 2.0
    dx, dy = x + 0.5 - cx, y + 0.5 - cy
    side = min(width, height)
    outer, start, turns = 0.47 * side, 0.05 * side, 4.5
    theta_max = 2 * np.pi * turns
    pitch = (outer - start) / turns
    growth = pitch / (2 * np.pi)
    half_min = 1.5
    half_max = max(min(10.0 * side / 743.0, 0.3 * pitch), half_min)
    r = np.hypot(dx, dy)
    phi = np.mod(np.arctan2(dy, dx), 2 * np.pi)
    turn = np.round((r - start) / pitch - phi / (2 * np.pi))
    inside = np.zeros((height, width), dtype=bool)
    for k in (-1, 0, 1):
        theta = phi + 2 * np.pi * (turn + k)
        half = half_min + (half_max - half_min) * theta / theta_max
        hit = (theta >= 0) & (theta <= theta_max) & (np.abs(r - (start + growth * theta)) <= half)
        inside |= hit
    return np.where(inside, 255, 0).astype(np.uint8)
