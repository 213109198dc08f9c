"""Test images for the large one-shot clone benchmark (not committed): a 6000x5000 target,
a 4400x3700 source (16.3 MP) and its mask (an ellipse filling most of it, about 12.6 MP
inside), written as 8-bit PNGs into the folder given (default /tmp/lapclone_big).

    python3 benches/make_big_images.py /tmp/lapclone_big
    target/release/lapclone clone --source /tmp/lapclone_big/source.png \
        --mask /tmp/lapclone_big/mask.png --target /tmp/lapclone_big/target.png \
        --at 3000,2500 -o /tmp/lapclone_big/out.png
    python3 benches/opencv/clone_big.py /tmp/lapclone_big
"""
import os
import sys

import cv2
import numpy as np


def smooth_noise(rng, height, width, cell):
    small = rng.random((height // cell + 2, width // cell + 2, 3), dtype=np.float32)
    big = cv2.resize(small, (width + 2 * cell, height + 2 * cell), interpolation=cv2.INTER_CUBIC)
    return big[cell:cell + height, cell:cell + width]


def picture(rng, height, width, tint):
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    base = np.stack([xs / width, ys / height, 0.5 + 0.5 * np.sin(xs / 700 + ys / 900)], axis=2)
    texture = smooth_noise(rng, height, width, 37) * 0.35 + rng.random((height, width, 3), dtype=np.float32) * 0.08
    image = np.clip(base * tint + texture, 0, 1)
    return (image * 255 + 0.5).astype(np.uint8)


def main(out):
    os.makedirs(out, exist_ok=True)
    rng = np.random.default_rng(7)
    cv2.imwrite(os.path.join(out, "target.png"), picture(rng, 5000, 6000, np.array([0.5, 0.6, 0.4], np.float32)))
    sh, sw = 3700, 4400
    cv2.imwrite(os.path.join(out, "source.png"), picture(rng, sh, sw, np.array([0.3, 0.2, 0.6], np.float32)))
    mask = np.zeros((sh, sw), np.uint8)
    cv2.ellipse(mask, (sw // 2, sh // 2), (sw // 2 - 20, sh // 2 - 20), 0, 0, 360, 255, -1)
    cv2.imwrite(os.path.join(out, "mask.png"), mask)
    print(f"mask inside: {np.count_nonzero(mask) / 1e6:.1f} MP")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/lapclone_big")
