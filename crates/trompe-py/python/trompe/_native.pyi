# Types of trompe's native module (crates/trompe-py/src/lib.rs). The package `trompe` wraps it:
# reports come back as JSON text, images as little-endian bytes with their size.
from typing import Callable, List, Optional, Sequence, Tuple

VERSION: str

class TrompeError(Exception):
    """An error from trompe: the message names the file, the element and the reason."""

def load_mesh(path: str) -> Tuple[str, bytes, bytes]: ...
def sidecar_info(path: str) -> str: ...
def bake_impostor(
    input: str,
    output: str,
    camera: str,
    resolution: int,
    from_dir: Sequence[float],
    distance: float,
    k: Optional[float],
    layers_text: str,
) -> str: ...
def bake_octahedral(
    inputs: List[str],
    output: str,
    frames: int,
    resolution: int,
    glb: bool,
    exr: bool,
    skip_existing: bool,
    progress: Optional[Callable[[int, int, str], None]],
) -> str: ...
def check_impostor(
    mesh: str,
    impostor: Optional[str],
    camera: str,
    resolution: int,
    k: Optional[float],
    rays: int,
    region: float,
    layers_text: str,
) -> str: ...
def capture_views(mesh: str, output: str, count: int, size: Tuple[int, int], rig: str) -> str: ...
def score_views(
    model: str, mesh: str, weights: List[str], every: Optional[int], k: int
) -> str: ...
def render(
    scene: str, method: str, time: Optional[float], size: Optional[Tuple[int, int]]
) -> Tuple[int, int, bytes, bytes, bytes, str]: ...
def render_views(
    model: str, mesh: str, scene: str, weights: str, k: int
) -> Tuple[int, int, bytes]: ...
def read_image(path: str) -> Tuple[int, int, bytes]: ...
def compare(reference: str, test: str) -> str: ...
def methods() -> List[str]: ...
