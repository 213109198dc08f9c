"""OpenCV doing what benches/scenes/hd_move.rhai does: 48 frames of 1920x1080 at 24 fps, the
cat's face moving from (400, 300) to (1500, 760), scaling 1.0 -> 1.3 and turning -10 -> 20
degrees (ease_in_out), each frame warpAffine of the patch and its mask, seamlessClone
NORMAL_CLONE, imwrite. The comparison for lapclone's PNG render of that scene:

    farm-bench --vs 'python3 benches/opencv/hd_move.py /tmp/cv_out' -- \
        target/release/lapclone render benches/scenes/hd_move.rhai -o /tmp/lc_out --force
"""
import os
import sys

import cv2
import numpy as np

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
FPS, FRAMES = 24, 48


def ease_in_out(s):
    s = min(max(s, 0.0), 1.0)
    return 4 * s**3 if s < 0.5 else 1 - (-2 * s + 2) ** 3 / 2


def main(out):
    os.makedirs(out, exist_ok=True)
    background = cv2.imread(os.path.join(ROOT, "benches/assets/rocket_1080p.jpg"))
    source = cv2.imread(os.path.join(ROOT, "assets/chelsea.png"))
    mask = cv2.imread(os.path.join(ROOT, "assets/masks/chelsea_face.png"), cv2.IMREAD_GRAYSCALE)
    x, y, w, h = cv2.boundingRect((mask >= 128).astype(np.uint8))
    pivot = (x + w / 2, y + h / 2)
    height, width = background.shape[:2]
    for i in range(FRAMES):
        s = ease_in_out((i / FPS) / 2.0)
        at = (400 + s * 1100, 300 + s * 460)
        scale, rotation = 1.0 + 0.3 * s, -10 + 30 * s
        # Clockwise on screen (y down) is a negative angle for OpenCV.
        m = cv2.getRotationMatrix2D(pivot, -rotation, scale)
        m[0, 2] += at[0] - pivot[0]
        m[1, 2] += at[1] - pivot[1]
        patch = cv2.warpAffine(source, m, (width, height), flags=cv2.INTER_LINEAR)
        patch_mask = cv2.warpAffine(mask, m, (width, height), flags=cv2.INTER_NEAREST)
        bx, by, bw, bh = cv2.boundingRect(patch_mask)
        centre = (bx + bw // 2, by + bh // 2)
        frame = cv2.seamlessClone(patch, background, patch_mask, centre, cv2.NORMAL_CLONE)
        cv2.imwrite(os.path.join(out, f"frame_{i + 1:04d}.png"), frame)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/opencv_hd_move")
