"""lapclone.seamless_clone against fpie's Jacobi solver, in one process, on the 400² spiral.

    python python/bench/fpie_compare.py [--repeat N] [--backend taichi-cpu] [--iterations 5000]

needs the `lapclone` package (pip install ./python), numpy, scipy and fpie (pip install fpie;
its `taichi-cpu` backend needs taichi, `numba` needs numba). Times fpie's equation solver
(`EquProcessor`, gradient "src": the source's guidance field, as NORMAL_CLONE; the default
5000 iterations; set-up excluded, as fpie's own CLI times it) and seamless_clone on the same
BGR arrays and placement (the mask's bounding-box centre at p, as cv2.seamlessClone places
it), against the target seamless_clone ≤ 0.01× fpie.

Beside the times, the PSNR of both results against the exact pixel-grid Poisson clone, over
the mask's inside pixels and all channels (peak 255): one unknown per inside pixel,
4·u − Σ inside neighbours = Σ (s − s_neighbour) + Σ target at outside neighbours, solved
directly (scipy's sparse LU, three right-hand sides). fpie's Jacobi iteration converges to
that solution; lapclone's mesh membrane approximates it.

Not part of CI's test run: timings depend on the machine.
"""

import argparse
import os
import statistics
import sys
import time

import numpy as np
import scipy.sparse
import scipy.sparse.linalg

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests"))

import lapclone  # noqa: E402
from conftest import smooth_target, spiral_mask, textured_source  # noqa: E402

P = (260, 230)


def offset_of(mask, p):
    """(dy, dx): target pixel = source pixel + offset, with the mask's bounding-box centre
    at p as cv2.seamlessClone (and lapclone) place it."""
    ys, xs = np.nonzero(mask >= 128)
    x0, y0, x1, y1 = xs.min(), ys.min(), xs.max() + 1, ys.max() + 1
    top, left = p[1] - (y1 - y0) // 2, p[0] - (x1 - x0) // 2
    return top - y0, left - x0


def exact_clone(src, dst, mask, offset):
    """The pixel-grid Poisson clone (float64, unclipped), solved directly."""
    inside = mask >= 128
    ys, xs = np.nonzero(inside)
    index = -np.ones(mask.shape, np.int64)
    index[ys, xs] = np.arange(len(ys))
    dy, dx = offset
    s = src.astype(np.float64)
    t = dst.astype(np.float64)
    rows, cols = [np.arange(len(ys))], [np.arange(len(ys))]
    vals = [np.full(len(ys), 4.0)]
    rhs = np.zeros((len(ys), 3))
    for ny, nx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        qy, qx = ys + ny, xs + nx
        rhs += s[ys, xs] - s[qy, qx]
        neighbour = index[qy, qx]
        coupled = neighbour >= 0
        rows.append(np.nonzero(coupled)[0])
        cols.append(neighbour[coupled])
        vals.append(np.full(coupled.sum(), -1.0))
        outside = ~coupled
        rhs[outside] += t[qy[outside] + dy, qx[outside] + dx]
    matrix = scipy.sparse.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(len(ys), len(ys)),
    )
    solution = scipy.sparse.linalg.splu(matrix).solve(rhs)
    out = t.copy()
    out[ys + dy, xs + dx] = solution
    return out, (ys + dy, xs + dx)


def psnr(result, reference, pixels):
    """PSNR (dB, peak 255) of `result` against `reference` over `pixels`, all channels."""
    a = result[pixels].astype(np.float64)
    b = np.clip(reference[pixels], 0, 255)
    mse = np.mean((a - b) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(255.0**2 / mse)


def timings(fn, repeat):
    """(best, median) wall-clock seconds of `repeat` calls after a warm-up call."""
    fn()
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        fn()
        times.append(time.perf_counter() - started)
    return min(times), statistics.median(times)


def fpie_run(src, dst, mask, offset, backend, iterations):
    """fpie's solver on the arrays: (seconds of the iterations alone, result). The set-up
    (reset: index and right-hand side) is left out, as fpie's own CLI times it."""
    from fpie.process import EquProcessor

    processor = EquProcessor("src", backend)
    # reset takes (row, column) offsets of the mask in the source and in the target: the mask
    # is source-sized here, so the source's is 0 and the target's is `offset`.
    processor.reset(src, mask, dst, (0, 0), offset)
    started = time.perf_counter()
    image, _ = processor.step(iterations)
    return time.perf_counter() - started, image.copy()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--backend", default="taichi-cpu")
    parser.add_argument("--iterations", type=int, default=5000)
    args = parser.parse_args()

    import fpie

    src = textured_source(400, 400)[:, :, ::-1].copy()
    dst = smooth_target(520, 460)[:, :, ::-1].copy()
    mask = spiral_mask(400, 400)
    offset = offset_of(mask, P)
    print(f"lapclone {lapclone.__version__}, fpie {fpie.__version__} ({args.backend}, "
          f"{args.iterations} iterations), numpy {np.__version__}, {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.2f}")

    started = time.perf_counter()
    reference, pixels = exact_clone(src, dst, mask, offset)
    print(f"exact pixel-grid clone: {len(pixels[0])} unknowns, sparse LU in "
          f"{(time.perf_counter() - started) * 1e3:.0f} ms")

    ours = timings(lambda: lapclone.seamless_clone(src, dst, mask, P), max(args.repeat, 5))
    ours_image = lapclone.seamless_clone(src, dst, mask, P)

    fpie_run(src, dst, mask, offset, args.backend, 10)  # the backend compiles its kernels
    runs = [fpie_run(src, dst, mask, offset, args.backend, args.iterations)
            for _ in range(args.repeat)]
    times = [seconds for seconds, _ in runs]
    theirs = (min(times), statistics.median(times))
    theirs_image = runs[-1][1]

    ratio, median = ours[0] / theirs[0], ours[1] / theirs[1]
    verdict = "ok" if ratio <= 0.01 else "MISSED"
    print(f"seamless_clone  {ours[0] * 1e3:9.2f} ms (median {ours[1] * 1e3:9.2f})  "
          f"PSNR {psnr(ours_image, reference, pixels):6.2f} dB")
    print(f"fpie            {theirs[0] * 1e3:9.2f} ms (median {theirs[1] * 1e3:9.2f})  "
          f"PSNR {psnr(theirs_image, reference, pixels):6.2f} dB")
    print(f"ratio {ratio:.4f} (median {median:.4f}; target ≤ 0.01) {verdict}")


if __name__ == "__main__":
    main()
