"""trompe: impostor-based and image-based rendering, from Python.

Bake impostors of meshes (SPOC, pinhole, orthographic, graph camera; octahedral atlases for
engines, a whole folder at once), check them against the exact ray tracer, capture, score and
render calibrated views, render scene files by any of trompe's methods. Reports are dicts (the
documents ``trompe --json`` prints, described in docs/json.md); images are NumPy arrays; errors
raise :class:`TrompeError` with the message the command line prints.

>>> import trompe
>>> mesh = trompe.load_mesh("assets/meshes/teapot.obj")
>>> mesh.positions.shape[1]
3
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Callable, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import TrompeError

__all__ = [
    "TrompeError",
    "Mesh",
    "Frame",
    "load_mesh",
    "info",
    "bake_impostor",
    "bake_octahedral",
    "check_impostor",
    "capture_views",
    "score_views",
    "render_views",
    "render",
    "read_image",
    "compare",
    "methods",
    "__version__",
]

__version__: str = _native.VERSION

PathLike = Union[str, "os.PathLike[str]"]


def _rgba(width: int, height: int, data: bytes) -> np.ndarray:
    return np.frombuffer(data, dtype="<f4").reshape(height, width, 4)


@dataclass(frozen=True)
class Mesh:
    """A mesh file as trompe loads it: what ``trompe info`` says of it, and its geometry."""

    path: str
    info: dict
    positions: np.ndarray
    """Vertex positions, ``(n, 3)`` float32 (vertices split by attribute, as trompe uses them)."""
    triangles: np.ndarray
    """Vertex indices, ``(m, 3)`` uint32."""


@dataclass(frozen=True)
class Frame:
    """A rendered frame."""

    color: np.ndarray
    """Linear RGBA radiance, ``(height, width, 4)`` float32."""
    object_id: np.ndarray
    """The object each pixel sees (scene file order), ``(height, width)`` uint32;
    0xFFFFFFFF where it sees none."""
    depth: np.ndarray
    """Distance along each pixel's ray to what it sees, ``(height, width)`` float32."""
    report: str
    """What the method says of the frame (impostors built or kept, atlases baked …)."""


def load_mesh(path: PathLike) -> Mesh:
    """Loads an ``.obj``, ``.ply``, ``.gltf`` or ``.glb`` file."""
    summary, positions, triangles = _native.load_mesh(os.fspath(path))
    return Mesh(
        path=os.fspath(path),
        info=json.loads(summary),
        positions=np.frombuffer(positions, dtype="<f4").reshape(-1, 3),
        triangles=np.frombuffer(triangles, dtype="<u4").reshape(-1, 3),
    )


def info(path: PathLike) -> dict:
    """What ``trompe info`` says of a mesh file or of an impostor's or atlas's JSON sidecar."""
    path = os.fspath(path)
    if path.lower().endswith(".json"):
        return json.loads(_native.sidecar_info(path))
    return load_mesh(path).info


def bake_impostor(
    input: PathLike,
    output: PathLike,
    *,
    camera: str = "spoc",
    resolution: int = 512,
    from_dir: Sequence[float] = (0.0, 0.3, 1.0),
    distance: float = 3.0,
    k: Optional[float] = None,
    layers: Union[int, str] = 1,
) -> dict:
    """Bakes a depth-image impostor of ``input`` to ``output`` (``NAME.json``; ``NAME.exr``
    and ``NAME.png`` beside it), as ``trompe impostor bake`` does.

    ``camera``: ``"spoc"``, ``"pinhole"``, ``"orthographic"``, or ``"graph"`` (``input`` a
    ``.maze``); ``from_dir`` the direction it looks from, ``distance`` in bounding radii;
    ``layers`` a count (1–8) or ``"auto"``. Returns the bake's report (``kind``, ``resolution``,
    ``coverage``, ``layers``, ``map_bytes``, ``files``, ``timings``).
    """
    text = _native.bake_impostor(
        os.fspath(input),
        os.fspath(output),
        camera,
        int(resolution),
        [float(c) for c in from_dir],
        float(distance),
        k,
        str(layers),
    )
    return json.loads(text)


def bake_octahedral(
    inputs: Union[PathLike, Sequence[PathLike]],
    output: PathLike,
    *,
    frames: int = 16,
    resolution: int = 2048,
    glb: bool = False,
    exr: bool = False,
    skip_existing: bool = False,
    progress: Optional[Callable[[int, int, str], None]] = None,
) -> dict:
    """Bakes octahedral atlases of meshes into the folder ``output``, as ``trompe impostor bake
    --octahedral`` bakes a batch: ``inputs`` mesh files and folders (walked, mirrored under
    ``output``), ``frames`` × ``frames`` views in a ``resolution``² atlas; ``glb`` adds a
    self-contained ``.glb`` beside each atlas, ``exr`` its normal and depth maps as float
    OpenEXR files. ``progress(done, total, input)`` is called after each mesh. Returns the
    manifest (``shards``, ``entries``: each input with its hash, outputs and their hashes,
    settings, seconds, or its error).
    """
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    text = _native.bake_octahedral(
        [os.fspath(p) for p in inputs],
        os.fspath(output),
        int(frames),
        int(resolution),
        bool(glb),
        bool(exr),
        bool(skip_existing),
        progress,
    )
    return json.loads(text)


def check_impostor(
    mesh: PathLike,
    impostor: Optional[PathLike] = None,
    *,
    camera: str = "spoc",
    resolution: int = 512,
    k: Optional[float] = None,
    rays: int = 20000,
    region: float = 1.0,
    layers: Union[int, str] = "auto",
) -> dict:
    """Fires rays at an impostor of ``mesh`` and at the exact BVH, as ``trompe impostor check``
    does: one built through ``camera`` at ``resolution``, or the baked ``impostor`` (its
    sidecar) on ``rays`` rays from ``region`` bounding radii around its viewpoint. Returns the
    report (``fidelity``: agreement, misses, position errors …; ``captured``; …).
    """
    text = _native.check_impostor(
        os.fspath(mesh),
        None if impostor is None else os.fspath(impostor),
        camera,
        int(resolution),
        k,
        int(rays),
        float(region),
        str(layers),
    )
    return json.loads(text)


def capture_views(
    mesh: PathLike,
    output: PathLike,
    *,
    count: int = 24,
    size: Tuple[int, int] = (640, 480),
    rig: str = "ring",
) -> dict:
    """Renders ``count`` calibrated views of ``mesh`` into the folder ``output`` (PNGs and a
    COLMAP text model), as ``trompe views capture`` does; ``rig``: ``"ring"``, ``"sphere"``
    or ``"hemisphere"``."""
    text = _native.capture_views(
        os.fspath(mesh), os.fspath(output), int(count), (int(size[0]), int(size[1])), rig
    )
    return json.loads(text)


def score_views(
    model: PathLike,
    mesh: PathLike,
    *,
    weights: Sequence[str] = ("ulr", "vdtm", "view-map", "best-face"),
    every: Optional[int] = None,
    k: int = 4,
) -> dict:
    """Leaves views of a COLMAP model out and renders each from the others with each weighting,
    as ``trompe views score`` does. Returns ``views``, ``left_out`` and per weighting its mean
    PSNR / SSIM / FLIP / holes and every view's scores."""
    text = _native.score_views(os.fspath(model), os.fspath(mesh), list(weights), every, int(k))
    return json.loads(text)


def render_views(
    model: PathLike,
    mesh: PathLike,
    scene: PathLike,
    *,
    weights: str = "ulr",
    k: int = 4,
) -> np.ndarray:
    """``mesh`` from the camera of the scene file ``scene``, textured from a COLMAP model's
    views: linear RGBA, ``(height, width, 4)`` float32, alpha 0 where no view sees it."""
    w, h, data = _native.render_views(
        os.fspath(model), os.fspath(mesh), os.fspath(scene), weights, int(k)
    )
    return _rgba(w, h, data)


def render(
    scene: PathLike,
    method: str = "trace",
    *,
    time: Optional[float] = None,
    size: Optional[Tuple[int, int]] = None,
) -> Frame:
    """Renders the scene file ``scene`` by ``method`` (one of :func:`methods`) at ``time``
    (the scene's own by default), at ``size`` = (width, height) if given."""
    w, h, color, ids, depth, report = _native.render(
        os.fspath(scene),
        method,
        None if time is None else float(time),
        None if size is None else (int(size[0]), int(size[1])),
    )
    return Frame(
        color=_rgba(w, h, color),
        object_id=np.frombuffer(ids, dtype="<u4").reshape(h, w),
        depth=np.frombuffer(depth, dtype="<f4").reshape(h, w),
        report=report,
    )


def read_image(path: PathLike) -> np.ndarray:
    """A PNG (sRGB, decoded to linear), EXR or HDR file as linear RGBA, ``(height, width, 4)``
    float32."""
    w, h, data = _native.read_image(os.fspath(path))
    return _rgba(w, h, data)


def compare(reference: PathLike, test: PathLike) -> dict:
    """PSNR (dB), SSIM and FLIP of two image files, as ``trompe compare`` prints them."""
    return json.loads(_native.compare(os.fspath(reference), os.fspath(test)))


def methods() -> list:
    """The methods :func:`render` accepts, by name, in trompe's order."""
    return list(_native.methods())
