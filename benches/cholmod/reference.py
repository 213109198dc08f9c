"""CHOLMOD's figures on the Laplacians `lapclone-bench factor --matrix-out DIR` writes, and
lapclone's ratios to them.

Usage:
    lapclone-bench factor --json --matrix-out DIR > lapclone.json
    python3 benches/cholmod/reference.py DIR lapclone.json

Needs scikit-sparse (CHOLMOD) with numpy and scipy. The matrix is the one lapclone factors:
L + eps*I + alpha*diag(constrained), eps = 1e-12 and alpha = 1e8 times the largest diagonal
entry. Times are the best of several runs, milliseconds: symbolic analysis, numeric
factorisation, a solve with three right-hand sides (CHOLMOD cannot skip zeros, so any
right-hand side costs the same), and one rank-1 switch of a constrained vertex (a downdate
and the update restoring it, halved; the first switch, which turns CHOLMOD's factor into the
simplicial form its update needs, is not counted).
"""

import json
import pathlib
import sys
import time

import numpy as np
import scipy.io
import scipy.sparse as sp
from sksparse import cholmod


def best_ms(work, runs):
    best = float("inf")
    for _ in range(runs):
        start = time.perf_counter()
        work()
        best = min(best, time.perf_counter() - start)
    return best * 1e3


def measure(mtx, constrained_path):
    lower = scipy.io.mmread(mtx).tocsc()
    laplacian = (lower + sp.tril(lower, -1).T).tocsc()
    n = laplacian.shape[0]
    scale = np.abs(laplacian.diagonal()).max() or 1.0
    constrained = np.loadtxt(constrained_path, dtype=np.int64, ndmin=1)
    weights = np.full(n, 1e-12 * scale)
    weights[constrained] += 1e8 * scale
    a = (laplacian + sp.diags(weights)).tocsc()
    runs = 2 if n > 200_000 else 5
    analyse_ms = best_ms(lambda: cholmod.analyze(a), runs)
    factor = cholmod.analyze(a)
    factor_ms = best_ms(lambda: factor.cholesky_inplace(a), runs)
    rhs = (np.arange(3 * n) * 7919 % 1000 / 1000.0).reshape(n, 3)
    solve3_ms = best_ms(lambda: factor(rhs), max(runs, 5))
    vertex = int(constrained[len(constrained) // 2])
    column = sp.csc_matrix(([np.sqrt(1e8 * scale)], ([vertex], [0])), shape=(n, 1))

    def switch():
        factor.update_inplace(column, subtract=True)
        factor.update_inplace(column, subtract=False)

    switch()
    switch_ms = best_ms(switch, 20) / 2.0
    return {"n": n, "analyze_ms": analyse_ms, "factor_ms": factor_ms,
            "solve3_ms": solve3_ms, "update_ms": switch_ms}


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    folder = pathlib.Path(sys.argv[1])
    ours = {}
    if len(sys.argv) == 3:
        ours = {row["n"]: row for row in json.loads(pathlib.Path(sys.argv[2]).read_text())}
    keys = ["analyze_ms", "factor_ms", "solve3_ms", "update_ms"]
    print(f"{'n':>8} " + " ".join(f"{k:>18}" for k in keys))
    for mtx in sorted(folder.glob("disc_*.mtx"), key=lambda p: int(p.stem.split("_")[1])):
        theirs = measure(mtx, mtx.with_suffix(".constrained"))
        cells = []
        for key in keys:
            mine = ours.get(theirs["n"], {}).get(key)
            ratio = f" ({mine / theirs[key]:.2f}x)" if mine is not None else ""
            cells.append(f"{theirs[key]:9.3f}{ratio:>9}")
        print(f"{theirs['n']:>8} " + " ".join(f"{c:>18}" for c in cells))
    print("CHOLMOD ms; in brackets lapclone / CHOLMOD (solve3: lapclone's Dirichlet solve)")


if __name__ == "__main__":
    main()
