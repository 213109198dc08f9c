"""OpenCV's seamlessClone on the large benchmark images (benches/make_big_images.py): prints
the wall time of the seamlessClone call alone (reading and writing excluded), the figure
lapclone's whole `lapclone clone` process is compared with.

    python3 benches/opencv/clone_big.py /tmp/lapclone_big
"""
import os
import sys
import time

import cv2


def main(folder):
    target = cv2.imread(os.path.join(folder, "target.png"))
    source = cv2.imread(os.path.join(folder, "source.png"))
    mask = cv2.imread(os.path.join(folder, "mask.png"), cv2.IMREAD_GRAYSCALE)
    centre = (target.shape[1] // 2, target.shape[0] // 2)
    started = time.perf_counter()
    result = cv2.seamlessClone(source, target, mask, centre, cv2.NORMAL_CLONE)
    seconds = time.perf_counter() - started
    print(f"seamlessClone: {seconds:.3f} s")
    cv2.imwrite(os.path.join(folder, "opencv_out.png"), result)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/lapclone_big")
