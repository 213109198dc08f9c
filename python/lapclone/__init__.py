"""lapclone: seamless cloning and deformation with the combinatorial Laplacian.

numpy arrays in and out. ``seamless_clone`` takes the arguments of ``cv2.seamlessClone``;
``Cloner`` meshes and factors a patch once and clones it onto any number of frames;
``Scene`` renders ``.rhai`` scene files frame by frame; ``mesh`` gives a mask's patch mesh.
See the type stubs (``__init__.pyi``) for every argument.
"""

from ._lapclone import (
    MIXED_CLONE,
    MONOCHROME_TRANSFER,
    NORMAL_CLONE,
    Cloner,
    Scene,
    SceneError,
    __version__,
    mesh,
    seamless_clone,
)

__all__ = [
    "MIXED_CLONE",
    "MONOCHROME_TRANSFER",
    "NORMAL_CLONE",
    "Cloner",
    "Scene",
    "SceneError",
    "__version__",
    "mesh",
    "seamless_clone",
]
