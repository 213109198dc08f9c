"""lapclone: seamless cloning and deformation with the combinatorial Laplacian.

Images are numpy arrays: H×W (grey) or H×W×C with C = 1 (grey), 3 (RGB) or 4 (RGBA), dtype
``uint8`` or ``uint16``, contiguous or not. Channel order is RGB(A) unless a ``bgr=True``
flag says BGR(A), as OpenCV reads images; ``seamless_clone`` always takes and gives BGR, as
``cv2.seamlessClone`` does. Results have the target's shape, dtype and channel order. A
mask is inside where its luma (or, with an alpha channel, its alpha) is at least half scale;
``bool`` masks are accepted (any nonzero byte is ``True``, as numpy reads it); a colour
mask's channels are in the call's order too. Bad input raises ``ValueError`` (``TypeError`` for something
that is not an array), never crashes the interpreter.
"""

from os import PathLike
from typing import Any, Iterator, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

NORMAL_CLONE: int
"""``cv2.NORMAL_CLONE`` (1): the source's texture, seamlessly blended into the target."""
MIXED_CLONE: int
"""``cv2.MIXED_CLONE`` (2): not offered; ``seamless_clone`` raises ``ValueError``."""
MONOCHROME_TRANSFER: int
"""``cv2.MONOCHROME_TRANSFER`` (3): the source's texture in grey, coloured by the target."""

Image = npt.NDArray[Union[np.uint8, np.uint16]]
Mask = npt.NDArray[Union[np.uint8, np.uint16, np.bool_]]
Point = Union[Tuple[float, float], Sequence[float], npt.NDArray[np.floating]]
"""Two numbers (x, y): a tuple, a list or a numpy array, each within ±1e9 px."""
Drag = Union[Tuple[Point, Point], Tuple[Point, Point, float], Sequence[Any]]

class SceneError(Exception):
    """A scene file's error: ``str(error)`` is ``file:line:col: message``."""

    file: str
    """The scene file (or module) the error is in."""
    line: Optional[int]
    """1-based line, None when unknown."""
    column: Optional[int]
    """1-based column, None when unknown."""
    message: str
    """The message without its position."""

def seamless_clone(
    src: Image,
    dst: Image,
    mask: Mask,
    p: Union[Tuple[int, int], Sequence[int]],
    flags: int = NORMAL_CLONE,
) -> Image:
    """``cv2.seamlessClone`` with lapclone: the same arguments, array layout (BGR) and
    placement, so switching is one word (``cv2.seamlessClone`` → ``lapclone.seamless_clone``).

    The centre of the mask's bounding box goes to the pixel ``p`` of ``dst`` as OpenCV puts
    it (the box's top-left pixel on ``p − (w // 2, h // 2)``). ``mask`` must be ``src``'s
    size; ``flags`` is ``NORMAL_CLONE`` or ``MONOCHROME_TRANSFER``. Returns a new array like
    ``dst``; the inputs are not changed.

    Where lapclone deliberately differs from OpenCV:

    - no assert at the borders: a patch reaching past ``dst``'s edges is clipped;
    - holes in the mask and several separate pieces are allowed (each piece blends on its
      own boundary, holes keep the target);
    - the mask is not eroded: every inside pixel is cloned, and the blend's boundary runs
      through the centres of the first outside pixels (OpenCV erodes the mask and changes
      none of its outer ring);
    - ``MIXED_CLONE`` raises ``ValueError`` naming what lapclone offers instead.

    Each call meshes and factors the patch: to clone one patch many times, use ``Cloner``.
    """

class Cloner:
    """A patch meshed and factored once, cloned onto any number of targets: a loop over
    video frames pays only the per-frame solve. The GIL is released while it computes, so
    clones on several threads run at once (clones through one ``Cloner`` take turns)."""

    def __init__(
        self,
        source: Image,
        mask: Mask,
        *,
        density: float = 3.0,
        laplacian: str = "combinatorial",
        mode: str = "normal",
        feather: float = 0.0,
        boundary_data: str = "hat-average",
        bgr: bool = False,
        threads: Optional[int] = None,
    ) -> None:
        """Meshes ``mask`` (the source's size) and factors the patch's Laplacian.

        - ``density``: maximum boundary edge length in pixels (``lapclone clone --density``).
        - ``laplacian``: ``"combinatorial"`` (the paper) or ``"cotangent"``.
        - ``mode``: ``"normal"`` or ``"monochrome"`` (the source turned grey first).
        - ``feather``: soften the patch's outer edge over this many pixels.
        - ``boundary_data``: ``"hat-average"`` or ``"vertex"``.
        - ``bgr``: the source, the mask, every target and every result are BGR(A), as
          OpenCV's.
        - ``threads``: threads each clone shades on (default: every core); the pixels are
          the same for any count.
        """
    def clone(
        self,
        target: Image,
        at: Point,
        *,
        scale: float = 1.0,
        rotate: float = 0.0,
        drags: Sequence[Drag] = (),
        pins: Sequence[Point] = (),
        anchor: str = "centre",
        out: Optional[Image] = None,
    ) -> Image:
        """Clones the patch onto ``target`` and returns the result: the same pixels as
        ``lapclone clone`` with the same images and flags.

        - ``at``: where the anchor (the centre of the mask's bounding box, or its top-left
          corner with ``anchor="topleft"``) lands in the target, pixels, any finite numbers.
        - ``scale`` (> 0) and ``rotate`` (degrees; positive turns x towards y, clockwise on
          screen) about the anchor.
        - ``drags``: ``((x0, y0), (x1, y1))`` or ``((x0, y0), (x1, y1), radius)`` in source
          pixels, deforming the patch (radius by default a quarter of the mask's larger
          bounding-box side); ``pins``: source points held still.
        - ``out``: an array of the target's shape and dtype to write the result into (it
          may be ``target`` itself, for an in-place clone); returned.

        The target is read, and the result written, only over the pixels the patch can
        touch; the rest of the result is a copy of the target.
        """
    @property
    def vertex_count(self) -> int:
        """Vertices of the patch mesh."""
    @property
    def triangle_count(self) -> int:
        """Triangles of the patch mesh."""
    @property
    def bbox(self) -> Tuple[float, float, float, float]:
        """The bounding box (x0, y0, x1, y1) of the mask's inside pixels (pixel corners)."""
    @property
    def source_shape(self) -> Sequence[int]:
        """The source array's shape."""

class Scene:
    """A ``.rhai`` scene file, opened as ``lapclone render`` opens it (loaded, validated,
    every patch meshed and factored): its frames are H×W×4 RGBA arrays (BGRA with
    ``bgr=True``), ``uint8``, or ``uint16`` for a 16-bit canvas — the samples ``lapclone
    render`` writes (it stores opaque frames as RGB PNGs, whose alpha is 255 here).

    Raises ``FileNotFoundError`` for a missing file and ``SceneError`` (with ``file``,
    ``line`` and ``column``) for anything wrong in it."""

    def __init__(self, path: Union[str, PathLike[str]], *, bgr: bool = False) -> None: ...
    def __len__(self) -> int:
        """Number of frames: ⌈duration · fps⌉."""
    @property
    def fps(self) -> float:
        """Frames per second."""
    @property
    def size(self) -> Tuple[int, int]:
        """(width, height) in pixels."""
    @property
    def path(self) -> str:
        """The scene file."""
    def frame(self, index: int) -> Image:
        """Frame ``index`` (from 0; negative counts from the end; ``IndexError`` past the
        end), rendered with the GIL released."""
    def __getitem__(self, index: int) -> Image:
        """``frame(index)``."""
    def __iter__(self) -> Iterator[Image]:
        """Every frame in order (Ctrl-C stops between frames, in ``list(scene)`` too)."""
    def render(
        self,
        path: Union[str, PathLike[str]],
        format: Optional[str] = None,
        *,
        force: bool = False,
    ) -> str:
        """Renders every frame to ``path`` as ``lapclone render -o path [--format format]``
        does, byte for byte, and returns the path written. The GIL is released while it
        renders.

        ``format``: ``"png"`` (a folder of ``frame_NNNN.png``), ``"gif"``, ``"apng"``,
        ``"y4m"`` (YUV4MPEG2 4:4:4), or ``"mp4"``, ``"webm"``, ``"mov"`` (through ffmpeg,
        which must be on ``PATH``). Without it, the path's extension names the format
        (``.gif``, ``.apng``, ``.y4m``, ``.mp4``, ``.webm``, ``.mov``; no extension, or
        ``.png``: a folder of frames).

        The output appears whole or not at all (a temporary file or folder beside it,
        renamed at the end). A PNG folder holding frame files of another render is refused
        (``FileExistsError``) unless ``force=True`` (``--force``), which removes them.
        ``path`` ``"-"`` writes Y4M to standard output: ``sys.stdout`` must be file
        descriptor 1 (it is flushed first). Ctrl-C stops the render after the frame in
        progress and raises ``KeyboardInterrupt``; nothing is written. A signal that ends
        the process (SIGTERM's default) leaves the hidden temporary output beside ``path``:
        install a handler that raises (``signal.signal(signal.SIGTERM, …)``) to have it
        removed as Ctrl-C's is.

        Raises ``ValueError`` for an unknown format or extension and for an output that is
        one of the scene's inputs (the scene, its imports, images, plates, videos);
        ``FileNotFoundError`` when the output's folder does not exist;
        ``IsADirectoryError`` when a file format names a folder; ``SceneError`` for an error
        in the scene; ``OSError`` when writing fails (ffmpeg missing or failing, a full disk).
        """

def mesh(
    mask: Mask, *, density: float = 3.0, bgr: bool = False
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.uint32]]:
    """The patch mesh ``Cloner`` makes of ``mask``: ``(vertices, triangles)``, an N×2
    float64 array of positions in mask pixels (x right, y down; pixel (i, j) covers
    [i, i+1] × [j, j+1]) and an M×3 uint32 array of counter-clockwise vertex indices.
    A colour mask is read in RGB order, BGR with ``bgr=True`` (its luma decides)."""
