# Type stubs of the svbtdf module (docs/python.md). Arrays are numpy arrays; shapes in comments:
# N pairs or texels, H x W texels, C hemicube cells, Q dots, K blend terms.
from typing import Any, Callable, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
F32 = npt.NDArray[np.float32]
F64 = npt.NDArray[np.float64]
Progress = Optional[Callable[[str, int, int], None]]
Log = Optional[Callable[[str], None]]

class Error(Exception):
    kind: str  # "invalid_input" | "format" | "io" | "hardware" | "numerical" | "interrupted"
    subject: str  # the file, argument or device at fault
    problem: str
    hint: str

class InvalidInputError(Error, ValueError): ...
class FormatError(Error, ValueError): ...
class IoError(Error, OSError): ...
class HardwareError(Error): ...
class NumericalError(Error, ArithmeticError): ...
class Interrupted(Error, KeyboardInterrupt): ...

def hemicube_cells(resolution: int) -> Tuple[F64, F64]:
    """Cell centre directions (C, 3) and solid angles (C,) of the hemicube of `resolution`."""

class Material:
    @staticmethod
    def load(path: str) -> "Material": ...
    path: str
    width: int
    height: int
    eta: float
    btdf: str  # "dual-microfacet" | "walter-ggx"
    ndf_resolution: int
    sample_size: Tuple[float, float]  # metres; (0, 0) when not recorded
    representative_texels: npt.NDArray[np.int64]  # (R,), texel index row * width + column
    provenance: dict
    alpha: F32  # (H, W)
    shadowing_roughness: F32  # (H, W)
    k_s: F32  # (H, W, 3)
    rho_d: F32  # (H, W, 3)
    residual: F32  # (H, W); -1 where not fitted
    cluster: F32  # (H, W)
    weight_index: F32  # (H, W, K)
    weight_value: F32  # (H, W, K)
    baseline_alpha_x: Optional[F32]  # (H, W), walter-ggx only
    baseline_alpha_y: Optional[F32]
    baseline_azimuth: Optional[F32]
    slab_entry_alpha_x: Optional[F32]  # (H, W), slab only: the side facing the light, along its first axis
    slab_entry_alpha_y: Optional[F32]  # across it
    slab_entry_azimuth: Optional[F32]  # the first axis from +x, radians
    slab_exit_alpha_x: Optional[F32]  # the side facing the camera
    slab_exit_alpha_y: Optional[F32]
    slab_exit_azimuth: Optional[F32]
    slab_entry_roughness_se: Optional[F32]  # of sqrt(alpha_x alpha_y); -1 where not known
    slab_exit_roughness_se: Optional[F32]
    slab_internal_reflection: Optional[F32]  # weight of the light reflected inside the slab
    slab_longer_paths: Optional[F32]  # weight of the longer internal paths (the same shape widened by sqrt(2))
    def eval(self, texels: ArrayLike, wi: ArrayLike, wo: ArrayLike, threads: int = 0) -> F64:
        """R (N, 3) as `svbtdf eval`; texels (N, 2) of (column, row) or (2,); wi, wo (N, 3) or (3,)."""
    def bsdf_eval(self, texels: ArrayLike, wi: ArrayLike, wo: ArrayLike, threads: int = 0) -> F64: ...
    def sample(self, texels: ArrayLike, wo: ArrayLike, u: ArrayLike,
               threads: int = 0) -> Tuple[F64, F64, F64, npt.NDArray[np.bool_]]:
        """(wi (N, 3), pdf (N,), weight (N, 3), valid (N,)) for u (N, 3) in [0, 1)."""
    def pdf(self, texels: ArrayLike, wi: ArrayLike, wo: ArrayLike, threads: int = 0) -> F64: ...
    def ndf_cells(self, column: int, row: int) -> F64:
        """D per hemicube cell (C,), on hemicube_cells(ndf_resolution)."""
    def ndf_at(self, column: int, row: int, h: ArrayLike) -> F64: ...

def ndf_grid(material: Material, column: int, row: int, size: int = 64) -> F64:
    """D on a (size, size) grid of normals (x right, y up); NaN outside the unit disk."""

class Session:
    @staticmethod
    def open(path: str) -> "Session": ...
    path: str
    manifest: dict
    rig: dict
    plan: list[str]
    journal: list[dict]
    def __contains__(self, key: str) -> bool: ...
    def image(self, key: str, check_crc: bool = False) -> npt.NDArray[np.uint16]:
        """(H, W) or (H, W, 3) as stored."""
    def verify(self, check_crc: bool = True, decode: bool = False) -> dict: ...

class SliceStore:
    @staticmethod
    def open(path: str) -> "SliceStore": ...
    path: str
    info: dict
    rho_d: F32  # (H, W, 3)
    mask: F32  # (H, W)
    reach: F32  # (H, W)
    def samples(self, column: int, row: int, held_out_dots: Optional[Sequence[int]] = None, holdout: float = 0.0,
                seed: int = 1) -> dict:
        """light (Q, 3), view (x, y, z), values float32 (Q, 3), valid (Q,), held_out (Q,)."""
    def slice(self, column: int, row: int) -> F32: ...

def calibrate(session: str, *, fix_k3: bool = False, full_lens_model: bool = False, progress: Progress = None,
              log: Log = None) -> dict: ...
def process(session: str, out: str, *, texels: Optional[Tuple[int, int]] = None, light_resolution: int = 16,
            threads: int = 0, progress: Progress = None, log: Log = None) -> dict: ...
def fit(processed: str, out: str, *, model: str = "dual", eta: Optional[float] = None,
        representatives: Union[float, str] = 0.01, holdout: float = 0.0, refine: bool = True,
        fixed_horizon: bool = False, ndf_resolution: int = 32, seed: int = 1, threads: int = 0,
        progress: Progress = None, log: Log = None) -> dict: ...
def run(session: str, out: str, *, work: Optional[str] = None, light_resolution: int = 16, model: str = "dual",
        eta: Optional[float] = None, representatives: Union[float, str] = 0.01, holdout: float = 0.0,
        refine: bool = True, fixed_horizon: bool = False, ndf_resolution: int = 32, seed: int = 1, threads: int = 0,
        progress: Progress = None, log: Log = None) -> dict: ...
def compare(material: str, truth: str, *, texels: int = 1000, seed: int = 1) -> dict: ...
def render(material: str, *, out: Optional[str] = None, png: Optional[str] = None, exposure: float = 1.0,
           scene: str = "background", view_deg: Tuple[float, float] = (0.0, 0.0), distance: float = 0.3,
           fov_deg: float = 20.0, resolution: Tuple[int, int] = (512, 512), spp: int = 64, seed: int = 1,
           threads: int = 0, background: Optional[str] = None, background_distance: float = 0.05,
           background_width: float = 0.0, checker_size: float = 0.01, environment: Optional[str] = None,
           sample_size: Optional[Tuple[float, float]] = None, progress: Progress = None) -> F32:
    """(height, width, 3) linear RGB."""
