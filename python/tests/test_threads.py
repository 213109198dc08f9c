"""The GIL is released while a clone computes: two threads cloning at once (two Cloners,
and one Cloner shared) both give the single-threaded pixels, and a child forked after its
parent cloned clones too. Their speed is a benchmark (python/bench), not a test."""

import os
import signal
import threading
import time
import warnings

import pytest

import numpy as np

import lapclone
from conftest import load_asset


def test_two_threads_give_right_results():
    src = load_asset("chelsea.png")
    mask = load_asset("masks/chelsea_face.png")
    dst = load_asset("coffee.png")
    places = [(250 + 7 * i, 150 + 3 * i) for i in range(12)]
    expected = [lapclone.Cloner(src, mask).clone(dst, at) for at in places]
    shared = lapclone.Cloner(src, mask)
    results = {}

    def work(name, cloner):
        results[name] = [cloner.clone(dst, at) for at in places]

    threads = [
        threading.Thread(target=work, args=("own", lapclone.Cloner(src, mask))),
        threading.Thread(target=work, args=("shared-a", shared)),
        threading.Thread(target=work, args=("shared-b", shared)),
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(results) == ["own", "shared-a", "shared-b"]
    for name, got in results.items():
        for g, e in zip(got, expected):
            assert np.array_equal(g, e), name


@pytest.mark.skipif(not hasattr(os, "fork"), reason="os.fork is POSIX only")
def test_a_child_forked_after_a_clone_clones_too():
    """The raster's worker threads started with the parent's first clone are not in a child
    forked after it (multiprocessing's fork start method): the child's clone runs on its own
    thread, with the parent's pixels, instead of waiting for workers that are not there."""
    src = load_asset("chelsea.png")
    mask = load_asset("masks/chelsea_face.png")
    dst = load_asset("coffee.png")
    cloner = lapclone.Cloner(src, mask, threads=2)
    expected = cloner.clone(dst, (250, 150))
    with warnings.catch_warnings():
        # Python warns that forking a process with threads may deadlock: the point here.
        warnings.simplefilter("ignore", DeprecationWarning)
        pid = os.fork()
    if pid == 0:
        code = 1
        try:
            got = lapclone.Cloner(src, mask, threads=2).clone(dst, (250, 150))
            code = 0 if np.array_equal(got, expected) else 3
        finally:
            os._exit(code)
    deadline = time.monotonic() + 60
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            pytest.fail("the forked child's clone did not finish in 60 s")
        time.sleep(0.02)
    assert os.waitstatus_to_exitcode(status) == 0
