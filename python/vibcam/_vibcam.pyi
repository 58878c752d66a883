"""Type stubs of the native module (the public functions are in vibcam/__init__.py)."""

from typing import Any, Optional, Sequence

import numpy as np
import numpy.typing as npt

class InputError(ValueError): ...
class VibcamError(RuntimeError): ...

FLAGS: list[tuple[int, str]]
MODEL_REVISION: int
__version__: str
MAX_TARGETS: int

_Point = tuple[float, float, int, int, Optional[int], Optional[int]]

def centroid(
    frame: np.ndarray, threshold: int, mode: str = ..., roi: Optional[tuple[int, int, int, int]] = ...
) -> tuple[float, float, int, list[str]]: ...
def track(
    frames: Any,
    tracking: dict[str, Any],
    view: Optional[dict[str, Any]] = ...,
    axis: str = ...,
) -> dict[str, Any]: ...
def frf(
    x: npt.NDArray[np.float64],
    y: npt.NDArray[np.float64],
    fs: float,
    window: str = ...,
    nperseg: Optional[int] = ...,
    noverlap: Optional[int] = ...,
    nfft: Optional[int] = ...,
    detrend: str = ...,
) -> tuple[
    npt.NDArray[np.float64], npt.NDArray[np.complex128], npt.NDArray[np.float64], int
]: ...
def upsample(
    x: npt.NDArray[np.float64], from_hz: float, to_hz: float
) -> npt.NDArray[np.float64]: ...
def analyze(frames: Any, tracking: dict[str, Any], **kwargs: Any) -> dict[str, Any]: ...
def ema(response: str, excitation: str, **kwargs: Any) -> dict[str, Any]: ...
def modal(displacement: str, **kwargs: Any) -> dict[str, Any]: ...
def study(
    out: str,
    config: Optional[str] = ...,
    preset: Optional[str] = ...,
    runs: Optional[int] = ...,
    exposures_ms: Optional[Sequence[float]] = ...,
    seed: Optional[int] = ...,
    threads: int = ...,
    progress: bool = ...,
    plots: bool = ...,
) -> tuple[str, str]: ...

class FrameReader:
    fps: Optional[float]
    count: Optional[int]
    label: Optional[str]
    def __init__(
        self,
        path: str,
        fps: Optional[float] = ...,
        retime: bool = ...,
        frame_range: Optional[str] = ...,
    ) -> None: ...
    def __iter__(self) -> "FrameReader": ...
    def __next__(self) -> np.ndarray: ...
    def close(self) -> None: ...
