"""The GIL is released while a clone computes: two threads cloning at once (two Cloners,
and one Cloner shared) both give the single-threaded pixels. Their speed is a benchmark
(python/bench), not a test."""

import threading

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
