"""Against OpenCV (skipped without cv2): seamless_clone puts the patch where
cv2.seamlessClone does, and at a border, where cv2 asserts, returns the clipped clone.

Where the two differ by design: cv2 erodes the mask before it clones, so it changes no pixel
of the mask's outer ring, while lapclone's patch boundary runs through the centres of the
first outside pixels, so it changes that ring a little. Each one's changed pixels therefore
lie within 1 px of the placed mask's bounding box (cv2's one pixel inside it, lapclone's one
outside it), and the two boxes share their centre."""

import numpy as np
import pytest

import lapclone
from conftest import load_asset, smooth_target, spiral_mask, textured_source

cv2 = pytest.importorskip("cv2", reason="opencv-python(-headless) is not installed")


def changed_box(result, dst):
    ys, xs = np.nonzero(np.any(result != dst, axis=2))
    return np.array([xs.min(), ys.min(), xs.max(), ys.max()])


def placed_mask_box(mask, p):
    """The inclusive pixel box cv2.seamlessClone's docs place: bbox centre on p."""
    ys, xs = np.nonzero(mask >= 128)
    w, h = xs.max() + 1 - xs.min(), ys.max() + 1 - ys.min()
    x0, y0 = p[0] - w // 2, p[1] - h // 2
    return np.array([x0, y0, x0 + w - 1, y0 + h - 1])


def cases():
    cat = (load_asset("chelsea.png")[:, :, ::-1].copy(), load_asset("coffee.png")[:, :, ::-1].copy(),
           load_asset("masks/chelsea_face.png"))
    spiral = (textured_source(400, 400)[:, :, ::-1].copy(), smooth_target(520, 460)[:, :, ::-1].copy(),
              spiral_mask(400, 400))
    rect_mask = np.zeros((100, 120), np.uint8)
    rect_mask[21:80, 10:101] = 255
    odd = (textured_source(120, 100), smooth_target(300, 200), rect_mask)
    return [(cat, (288, 143)), (cat, (301, 201)), (spiral, (260, 230)), (odd, (150, 100)), (odd, (151, 99))]


@pytest.mark.parametrize("case", range(5))
def test_placement_agrees_with_cv2_away_from_borders(case):
    (src, dst, mask), p = cases()[case]
    ours = changed_box(lapclone.seamless_clone(src, dst, mask, p), dst)
    # OpenCV (5.0.0) writes into the mask it is given: it gets a copy.
    theirs = changed_box(cv2.seamlessClone(src, dst, mask.copy(), p, cv2.NORMAL_CLONE), dst)
    placed = placed_mask_box(mask, p)
    # Each within a pixel of the placed box: lapclone up to 1 px outside, cv2 up to 1 px inside.
    outward = np.array([-1, -1, 1, 1])
    assert np.all((ours - placed) * outward >= 0) and np.all(np.abs(ours - placed) <= 1), (ours, placed)
    assert np.all((placed - theirs) * outward >= 0) and np.all(np.abs(theirs - placed) <= 1), (theirs, placed)
    # The same place: the boxes' centres agree.
    assert np.abs((ours[:2] + ours[2:]) - (theirs[:2] + theirs[2:])).max() <= 1, (ours, theirs)


@pytest.mark.parametrize("p", [(10, 40), (290, 190), (150, 5), (-20, 100)])
def test_at_a_border_cv2_asserts_and_lapclone_clips(p):
    src = textured_source(120, 100)
    mask = np.zeros((100, 120), np.uint8)
    mask[20:80, 10:110] = 255
    dst = smooth_target(300, 200)
    with pytest.raises(cv2.error):
        cv2.seamlessClone(src, dst, mask.copy(), p, cv2.NORMAL_CLONE)
    result = lapclone.seamless_clone(src, dst, mask, p)
    assert result.shape == dst.shape
    placed = placed_mask_box(mask, p)
    clipped = np.clip(placed + [-1, -1, 1, 1], 0, [299, 199, 299, 199])
    changed = np.any(result != dst, axis=2)
    if placed[2] < 0:
        assert not changed.any()
        return
    box = changed_box(result, dst)
    assert np.all(box[:2] >= clipped[:2]) and np.all(box[2:] <= clipped[2:]), (box, clipped)
    # The part inside dst took the source's texture: far from the flat target there.
    inside = (slice(max(placed[1], 0) + 5, min(placed[3], 199) - 5), slice(max(placed[0], 0) + 5, min(placed[2], 299) - 5))
    assert np.abs(result[inside].astype(int) - dst[inside]).max() > 20
