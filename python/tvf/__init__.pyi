# Type stub of the tvf module (python/tvf_module.cpp). Shapes: N frames, V vertices, F faces.
import os
from typing import Any, Callable, Literal, Optional, Protocol, Sequence, Union, overload

import numpy as np
import numpy.typing as npt

JSON = Any
SceneLike = Union[dict, str, os.PathLike]
# Vertices (V, 3) float64 and faces (F, 3) integer indices, or anything np.asarray makes so.
VertexArray = Union[npt.NDArray[np.floating], Sequence[Sequence[float]]]
FaceArray = Union[npt.NDArray[np.integer], Sequence[Sequence[int]]]
Image = npt.NDArray[np.uint8]  # (H, W, 3) RGB

class _Event(Protocol):
    def is_set(self) -> bool: ...

Progress = Callable[[int, int], Any]
# What a solve does before its frames' count starts ("planning the topology between key frames (interval 1 of 2)").
Stage = Callable[[str], Any]

class Cancelled(RuntimeError): ...

vdb_available: bool

class Field:
    @property
    def vectors(self) -> npt.NDArray[np.float32]: ...  # (N, V, 3), the values of field.npy
    @property
    def values(self) -> npt.NDArray[np.complex128]: ...  # (N, V), tangent-basis form
    @property
    def vertices(self) -> npt.NDArray[np.float64]: ...  # (V, 3)
    @property
    def faces(self) -> npt.NDArray[np.int32]: ...  # (F, 3)
    @property
    def times(self) -> npt.NDArray[np.float64]: ...  # (N,)
    @property
    def e1(self) -> npt.NDArray[np.float64]: ...  # (V, 3)
    @property
    def e2(self) -> npt.NDArray[np.float64]: ...  # (V, 3)
    @property
    def frames(self) -> int: ...
    @property
    def planar(self) -> bool: ...
    @property
    def report(self) -> dict: ...
    def streamline(self, seed: Sequence[float], t: float = 0.0, *, step: float = 0.0,
                   max_length: float = 0.0) -> dict: ...
    def pathline(self, seed: Sequence[float], t_start: float = 0.0, t_end: Optional[float] = None, *,
                 dt: float = 0.0) -> dict: ...
    def ftle(self, horizon: float, *, direction: Literal["both", "forward", "backward"] = "both",
             frames: Optional[Sequence[int]] = None, beyond_range: Literal["clamp", "nan"] = "clamp",
             compose: bool = False, dt: float = 0.0, progress: Optional[Progress] = None,
             cancel: Optional[_Event] = None) -> dict: ...
    def streakline(self, seed: Sequence[float], t_start: Optional[float] = None, t_end: Optional[float] = None, *,
                   release_spacing: float = 0.0, max_gap: float = 0.0, dt: float = 0.0) -> dict: ...
    def timeline(self, a: Sequence[float], b: Sequence[float], t_start: Optional[float] = None,
                 t_end: Optional[float] = None, *, count: int = 100, max_gap: float = 0.0) -> dict: ...
    def export_vdb(self, dir: str) -> list[str]: ...
    def export_ply(self, dir: str) -> list[str]: ...

def generate(scene: SceneLike, *, vertices: Optional[VertexArray] = None, faces: Optional[FaceArray] = None,
             progress: Optional[Progress] = None, cancel: Optional[_Event] = None,
             parallel: bool = True, stage: Optional[Stage] = None) -> Field: ...
def analyze(field: Field) -> JSON: ...
def load(path: str) -> Field: ...
def export_vdb(field: Field, dir: str) -> list[str]: ...
def export_ply(field: Field, dir: str) -> list[str]: ...
@overload
def render_texture(field: Field, size: int = 512, frames: int = ..., *, frames_dir: Optional[str] = None,
                   video: Optional[str] = None, pictures: int = 0, alpha: float = 0.1, lic: int = -1,
                   noise_scale: float = 0.0, speed: Literal["uniform", "physical"] = "uniform",
                   pixels_per_frame: float = 0.0, contrast: float = 1.0, seed: int = 1,
                   overlay: Sequence[str] = (), view: Optional[Sequence[float]] = None,
                   up: Optional[Sequence[float]] = None, fps: float = 25.0,
                   streaklines: Sequence[Sequence[float]] = (),
                   timelines: Sequence[Sequence[Sequence[float]]] = (), time_scale: float = 1.0,
                   progress: Optional[Progress] = None) -> Image: ...
@overload
def render_texture(field: Field, size: int = 512, frames: Optional[Sequence[int]] = None, *,
                   frames_dir: Optional[str] = None, video: Optional[str] = None, pictures: int = 0,
                   alpha: float = 0.1, lic: int = -1, noise_scale: float = 0.0,
                   speed: Literal["uniform", "physical"] = "uniform", pixels_per_frame: float = 0.0,
                   contrast: float = 1.0, seed: int = 1, overlay: Sequence[str] = (),
                   view: Optional[Sequence[float]] = None, up: Optional[Sequence[float]] = None,
                   fps: float = 25.0, streaklines: Sequence[Sequence[float]] = (),
                   timelines: Sequence[Sequence[Sequence[float]]] = (), time_scale: float = 1.0,
                   progress: Optional[Progress] = None) -> list[Image]: ...

class Design:
    def __init__(self, scene: SceneLike, *, vertices: Optional[VertexArray] = None,
                 faces: Optional[FaceArray] = None, parallel: bool = True) -> None: ...
    scene: dict
    @property
    def field(self) -> Field: ...
    @property
    def has_field(self) -> bool: ...
    @property
    def can_undo(self) -> bool: ...
    @property
    def can_redo(self) -> bool: ...
    def generate(self, *, progress: Optional[Progress] = None, cancel: Optional[_Event] = None,
                 stage: Optional[Stage] = None) -> Field: ...
    def analyze(self, *, progress: Optional[Progress] = None, cancel: Optional[_Event] = None,
                stage: Optional[Stage] = None) -> JSON: ...
    def check(self) -> Optional[JSON]: ...
    def edit(self, entry: Optional[dict] = None, **kwargs: Any) -> dict: ...
    def undo(self) -> None: ...
    def redo(self) -> None: ...
    def save(self, path: Optional[str] = None) -> None: ...
    def write_outputs(self, dir: str, *, vtk: bool = True) -> list[str]: ...
