"""svbtdf: thin transparent slabs' BTDFs from Python (docs/python.md).

Materials (``Material.load``), capture sessions (``Session.open``), slice stores
(``SliceStore.open``) and the pipeline's stages (``calibrate``, ``process``, ``fit``, ``run``,
``compare``, ``render``), all computed by the same C++ libraries as the ``svbtdf`` command line.
Errors are ``svbtdf.Error`` and its subclasses, carrying the command line's one-line message.
"""

from typing import Callable, Optional, Sequence, Tuple, Union

import numpy as np

from ._svbtdf import (  # noqa: F401  (re-exported)
    Error,
    FormatError,
    HardwareError,
    InvalidInputError,
    Interrupted,
    IoError,
    Material,
    NumericalError,
    Session,
    SliceStore,
    hemicube_cells,
)
from . import _svbtdf

__all__ = [
    "Error", "FormatError", "HardwareError", "InvalidInputError", "Interrupted", "IoError", "NumericalError",
    "Material", "Session", "SliceStore", "hemicube_cells", "ndf_grid",
    "calibrate", "process", "fit", "run", "compare", "render",
]

Progress = Optional[Callable[[str, int, int], None]]
Log = Optional[Callable[[str], None]]


def ndf_grid(material: Material, column: int, row: int, size: int = 64) -> np.ndarray:
    """The texel's NDF on a size x size grid of normals, float64 (size, size).

    Cell [j, i] holds D(h) at h = (x, y, sqrt(1 - x^2 - y^2)) with x = -1 + (2 i + 1) / size and
    y = 1 - (2 j + 1) / size (+y up, as ``plt.imshow`` shows it); NaN outside the unit disk.
    """
    centres = -1.0 + (2.0 * np.arange(size) + 1.0) / size
    x, y = np.meshgrid(centres, -centres)
    r2 = x * x + y * y
    inside = r2 < 1.0
    h = np.stack([x[inside], y[inside], np.sqrt(1.0 - r2[inside])], axis=1)
    grid = np.full((size, size), np.nan)
    grid[inside] = material.ndf_at(column, row, h)
    return grid


def calibrate(session: str, *, fix_k3: bool = False, full_lens_model: bool = False,
              progress: Progress = None, log: Log = None) -> dict:
    """``svbtdf calibrate SESSION``: writes SESSION/calibration.json and checks it.

    Returns {"file", "calibration" (the written JSON as a dict), "warnings" (docs/quality.md)}.
    """
    return _svbtdf._calibrate(str(session), fix_k3, full_lens_model, progress, log)


def process(session: str, out: str, *, texels: Optional[Tuple[int, int]] = None, light_resolution: int = 16,
            threads: int = 0, progress: Progress = None, log: Log = None) -> dict:
    """``svbtdf process SESSION --out OUT``: the calibrated session into the slice store OUT.

    texels=(width, height) as --texels WxH (default: the session's). An unfinished OUT resumes.
    Returns {"store", "texels", "valid_texels", "dots", "dots_resumed", "images_read", "seconds", "warnings"}.
    """
    return _svbtdf._process(str(session), str(out), tuple(texels) if texels else (0, 0), light_resolution, threads,
                            progress, log)


def _fit_arguments(model, eta, representatives, holdout, refine, fixed_horizon, ndf_resolution, seed, threads):
    return (model, 0.0 if eta is None else float(eta), str(representatives), float(holdout), bool(refine),
            bool(fixed_horizon), int(ndf_resolution), int(seed), int(threads))


def fit(processed: str, out: str, *, model: str = "dual", eta: Optional[float] = None,
        representatives: Union[float, str] = 0.01, holdout: float = 0.0, refine: bool = True,
        fixed_horizon: bool = False, ndf_resolution: int = 32, seed: int = 1, threads: int = 0,
        progress: Progress = None, log: Log = None) -> dict:
    """``svbtdf fit PROCESSED --out OUT``: fits and writes the material (resumable).

    The options are the command line's: model ("dual" | "ggx" | "slab"), eta (None: the store's),
    representatives (fraction or "all"), holdout, refine (False: --no-refine), fixed_horizon,
    ndf_resolution, seed, threads. Returns {"material", "warnings"}.
    """
    return _svbtdf._fit(str(processed), str(out),
                        *_fit_arguments(model, eta, representatives, holdout, refine, fixed_horizon, ndf_resolution,
                                        seed, threads), progress, log)


def run(session: str, out: str, *, work: Optional[str] = None, light_resolution: int = 16, model: str = "dual",
        eta: Optional[float] = None, representatives: Union[float, str] = 0.01, holdout: float = 0.0,
        refine: bool = True, fixed_horizon: bool = False, ndf_resolution: int = 32, seed: int = 1, threads: int = 0,
        progress: Progress = None, log: Log = None) -> dict:
    """``svbtdf run SESSION --out OUT``: calibrate, process and fit, each resumable.

    Returns {"material", "work" (the reusable processed slices), "warnings"}.
    """
    return _svbtdf._run(str(session), str(out), "" if work is None else str(work), light_resolution,
                        *_fit_arguments(model, eta, representatives, holdout, refine, fixed_horizon, ndf_resolution,
                                        seed, threads), progress, log)


def compare(material: str, truth: str, *, texels: int = 1000, seed: int = 1) -> dict:
    """``svbtdf compare MATERIAL TRUTH``: the metrics, as ``--json`` writes them (NaN as None)."""
    return _svbtdf._compare(str(material), str(truth), texels, seed)


def render(material: str, *, out: Optional[str] = None, png: Optional[str] = None, exposure: float = 1.0,
           scene: str = "background", view_deg: Tuple[float, float] = (0.0, 0.0), distance: float = 0.3,
           fov_deg: float = 20.0, resolution: Tuple[int, int] = (512, 512), spp: int = 64, seed: int = 1,
           threads: int = 0, background: Optional[str] = None, background_distance: float = 0.05,
           background_width: float = 0.0, checker_size: float = 0.01, environment: Optional[str] = None,
           sample_size: Optional[Tuple[float, float]] = None, progress: Progress = None) -> np.ndarray:
    """``svbtdf render MATERIAL``: the linear RGB image, float32 (height, width, 3).

    MATERIAL is a material or a truth folder; out (EXR) and png are written when given.
    """
    return _svbtdf._render(str(material), "" if out is None else str(out), "" if png is None else str(png), exposure,
                           scene, tuple(view_deg), distance, fov_deg, tuple(resolution), spp, seed, threads,
                           "" if background is None else str(background), background_distance, background_width,
                           checker_size, "" if environment is None else str(environment),
                           None if sample_size is None else tuple(sample_size), progress)


for _stage in (calibrate, process, fit, run, render):
    _stage.__doc__ += _svbtdf._CALLBACKS_DOC
del _stage
