"""lapclone from Python against OpenCV, in one process, on the same arrays.

    python python/bench/bench.py [--repeat N]

needs the `lapclone` package (pip install ./python), numpy and opencv-python(-headless);
pypng reads the repository's PNG assets. Prints one line per case: best and median wall-clock
times and the ratios lapclone / OpenCV, against the targets of the Python package:

- seamless_clone on the 400² spiral and the README's cat: ≤ 0.3× cv2.seamlessClone;
- Cloner.clone (mesh and factor made once) on the same: ≤ 0.05×;
- a 48-frame 1920×1080 loop moving, scaling and turning the cat's face over the rocket
  plate (benches/opencv/hd_move.py without file I/O): ≤ 0.1× cv2.warpAffine +
  cv2.seamlessClone per frame;
- two threads cloning at once against one thread doing both shares (the GIL is released).

Not part of CI's test run: timings depend on the machine.
"""

import argparse
import os
import statistics
import sys
import threading
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests"))

import cv2  # noqa: E402

import lapclone  # noqa: E402
from conftest import ROOT, load_asset, smooth_target, spiral_mask, textured_source  # noqa: E402


def timings(fn, repeat):
    """(best, median) wall-clock seconds of `repeat` calls after a warm-up call."""
    fn()  # warm-up (first touch of pages, thread pools)
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        fn()
        times.append(time.perf_counter() - started)
    return min(times), statistics.median(times)


def report(name, ours, theirs, target):
    """Best-of and median times and ratios; the verdict is on the best (the machine's own
    speed, without other load), the median shows the spread."""
    best, median = ours[0] / theirs[0], ours[1] / theirs[1]
    verdict = "ok" if best <= target else "MISSED"
    print(f"{name:<44} lapclone {ours[0] * 1e3:8.2f} ms (median {ours[1] * 1e3:8.2f})  "
          f"opencv {theirs[0] * 1e3:8.2f} ms (median {theirs[1] * 1e3:8.2f})  "
          f"ratio {best:6.3f} (median {median:6.3f}; target ≤ {target}) {verdict}")


def one_shot(name, src, dst, mask, p, repeat):
    """seamless_clone and Cloner.clone against cv2.seamlessClone."""
    ours = timings(lambda: lapclone.seamless_clone(src, dst, mask, p), repeat)
    # OpenCV (5.0.0 here) writes into the mask it is given: each call gets its own copy.
    theirs = timings(lambda: cv2.seamlessClone(src, dst, mask.copy(), p, cv2.NORMAL_CLONE), repeat)
    report(f"{name}: seamless_clone", ours, theirs, 0.3)
    cloner = lapclone.Cloner(src, mask, bgr=True)
    x0, y0, x1, y1 = cloner.bbox
    at = (p[0] - (x1 - x0) // 2 + (x1 - x0) / 2, p[1] - (y1 - y0) // 2 + (y1 - y0) / 2)
    ours = timings(lambda: cloner.clone(dst, at), repeat)
    report(f"{name}: Cloner.clone", ours, theirs, 0.05)


def ease_in_out(s):
    s = min(max(s, 0.0), 1.0)
    return 4 * s**3 if s < 0.5 else 1 - (-2 * s + 2) ** 3 / 2


def hd_poses(frames=48, fps=24):
    for i in range(frames):
        s = ease_in_out((i / fps) / 2.0)
        yield (400 + s * 1100, 300 + s * 460), 1.0 + 0.3 * s, -10 + 30 * s


def hd_loop():
    background = cv2.imread(str(ROOT / "benches" / "assets" / "rocket_1080p.jpg"))
    source = load_asset("chelsea.png")[:, :, ::-1].copy()
    mask = load_asset("masks/chelsea_face.png")
    height, width = background.shape[:2]
    x, y, w, h = cv2.boundingRect((mask >= 128).astype(np.uint8))
    pivot = (x + w / 2, y + h / 2)

    def opencv():
        for at, scale, rotation in hd_poses():
            m = cv2.getRotationMatrix2D(pivot, -rotation, scale)
            m[0, 2] += at[0] - pivot[0]
            m[1, 2] += at[1] - pivot[1]
            patch = cv2.warpAffine(source, m, (width, height), flags=cv2.INTER_LINEAR)
            patch_mask = cv2.warpAffine(mask, m, (width, height), flags=cv2.INTER_NEAREST)
            bx, by, bw, bh = cv2.boundingRect(patch_mask)
            cv2.seamlessClone(patch, background, patch_mask, (bx + bw // 2, by + bh // 2),
                              cv2.NORMAL_CLONE)

    frame = np.empty_like(background)

    def ours():
        cloner = lapclone.Cloner(source, mask, bgr=True)  # mesh and factor: once per loop
        for at, scale, rotation in hd_poses():
            cloner.clone(background, at, scale=scale, rotate=rotation, out=frame)

    theirs_s = timings(opencv, 3)
    ours_s = timings(ours, 3)
    report("48 HD frames, move+scale+rotate (whole loop)", ours_s, theirs_s, 0.1)


def threads(repeat):
    """Two threads, each with its own Cloner, against one thread doing both shares."""
    src = load_asset("chelsea.png")
    mask = load_asset("masks/chelsea_face.png")
    dst = load_asset("coffee.png")
    cloners = [lapclone.Cloner(src, mask), lapclone.Cloner(src, mask)]
    places = [(250 + i, 150 + i) for i in range(20)]

    def share(cloner):
        for at in places:
            cloner.clone(dst, at)

    def serial():
        share(cloners[0])
        share(cloners[1])

    def parallel():
        workers = [threading.Thread(target=share, args=(c,)) for c in cloners]
        for w in workers:
            w.start()
        for w in workers:
            w.join()

    one = timings(serial, repeat)
    two = timings(parallel, repeat)
    print(f"{'two threads vs one (40 cat clones)':<44} one thread {one[0] * 1e3:8.2f} ms "
          f"(median {one[1] * 1e3:8.2f})  two threads {two[0] * 1e3:8.2f} ms "
          f"(median {two[1] * 1e3:8.2f})  ratio {two[0] / one[0]:6.3f} (cores: {os.cpu_count()})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15)
    args = parser.parse_args()
    print(f"lapclone {lapclone.__version__}, OpenCV {cv2.__version__}, numpy {np.__version__}, "
          f"{os.cpu_count()} cores")
    spiral = (textured_source(400, 400)[:, :, ::-1].copy(), smooth_target(520, 460)[:, :, ::-1].copy(),
              spiral_mask(400, 400))
    one_shot("400² spiral", spiral[0], spiral[1], spiral[2], (260, 230), args.repeat)
    cat = (load_asset("chelsea.png")[:, :, ::-1].copy(), load_asset("coffee.png")[:, :, ::-1].copy(),
           load_asset("masks/chelsea_face.png"))
    one_shot("README cat", cat[0], cat[1], cat[2], (288, 143), args.repeat)
    hd_loop()
    threads(args.repeat)


if __name__ == "__main__":
    main()
