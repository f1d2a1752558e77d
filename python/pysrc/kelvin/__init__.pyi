# Type stubs of the public API (kelvin/__init__.py documents it). Image sizes are (width, height);
# image arrays are (height, width, 3), rows first.
from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__all__ = ["render", "Scene", "write_exr", "write_png", "read_exr", "spectrum", "ies", "LightSystem", "luminance",
           "LUMINANCE_WEIGHTS"]

_Path = Union[str, PathLike]
_Vec3 = Sequence[float]
_Rgb = Sequence[float]
_Image = npt.NDArray[np.float32]  # H x W x 3
_Points = npt.ArrayLike  # N x 3

LUMINANCE_WEIGHTS: npt.NDArray[np.float32]

def luminance(rgb: npt.ArrayLike) -> npt.NDArray[np.float32]: ...

class Scene:
    summary: Optional[str]
    @classmethod
    def load(cls, scene: Optional[_Path] = None, *, env: Optional[_Path] = None, env_intensity: float = 1.0,
             sky: Optional[str] = None, sky_intensity: float = 1.0) -> "Scene": ...
    def render(
        self,
        *,
        size: Tuple[int, int] = (512, 512),
        spp: int = 32,
        time: Optional[float] = None,
        integrator: str = "path",
        max_depth: int = 16,
        roulette_depth: int = 3,
        light_sampler: str = "bvh",
        candidates: Optional[int] = None,
        neighbours: Optional[int] = None,
        radius: Optional[int] = None,
        biased_reuse: bool = False,
        color: str = "rgb",
        all_lights: bool = False,
        mis: bool = True,
        seed: int = 0,
        pattern: str = "sobol",
        threads: Optional[int] = None,
        environment_at: Optional[Sequence[float]] = None,
        crop: Optional[Tuple[int, int, int, int]] = None,
        stats: Optional[Dict[str, Any]] = None,
    ) -> _Image: ...
    def pose(self, animation: Union[int, str], t: float) -> Dict[str, int]: ...
    @property
    def lights(self) -> List[Dict[str, Any]]: ...
    @property
    def cameras(self) -> List[Dict[str, Any]]: ...
    @property
    def animations(self) -> List[Dict[str, Any]]: ...

def render(
    scene: Optional[_Path] = None,
    *,
    size: Tuple[int, int] = (512, 512),
    spp: int = 32,
    time: Optional[float] = None,
    env: Optional[_Path] = None,
    env_intensity: float = 1.0,
    sky: Optional[str] = None,
    sky_intensity: float = 1.0,
    integrator: str = "path",
    max_depth: int = 16,
    roulette_depth: int = 3,
    light_sampler: str = "bvh",
    candidates: Optional[int] = None,
    neighbours: Optional[int] = None,
    radius: Optional[int] = None,
    biased_reuse: bool = False,
    color: str = "rgb",
    all_lights: bool = False,
    mis: bool = True,
    seed: int = 0,
    pattern: str = "sobol",
    threads: Optional[int] = None,
    environment_at: Optional[Sequence[float]] = None,
    crop: Optional[Tuple[int, int, int, int]] = None,
    stats: Optional[Dict[str, Any]] = None,
) -> _Image: ...
def write_exr(path: _Path, image: npt.ArrayLike) -> None: ...
def write_png(path: _Path, image: npt.ArrayLike, exposure: Optional[float] = None) -> None: ...
def read_exr(path: _Path) -> _Image: ...
def spectrum(spec: str) -> Dict[str, Any]: ...
def ies(path: _Path) -> Dict[str, Any]: ...

class LightSystem:
    def __init__(self, sampler: str = "bvh", *, color: str = "rgb", seed: int = 0, all_lights: bool = False) -> None: ...
    def add_point(self, position: _Vec3, *, candela: Optional[float] = None, lumens: Optional[float] = None,
                  watts: Optional[float] = None, color: Optional[_Rgb] = None, temperature: Optional[float] = None,
                  radius: float = 0.0) -> int: ...
    def add_spot(self, position: _Vec3, direction: _Vec3, *, candela: Optional[float] = None,
                 lumens: Optional[float] = None, inner_angle: float = 0.0, outer_angle: float = 45.0,
                 color: Optional[_Rgb] = None, temperature: Optional[float] = None) -> int: ...
    def add_distant(self, direction: _Vec3, *, lux: Optional[float] = None, color: Optional[_Rgb] = None,
                    temperature: Optional[float] = None, angular_diameter: float = 0.0) -> int: ...
    def add_area(self, center: _Vec3, normal: _Vec3, size: Tuple[float, float], *, nits: Optional[float] = None,
                 lumens: Optional[float] = None, color: Optional[_Rgb] = None, temperature: Optional[float] = None,
                 two_sided: bool = False) -> int: ...
    def add_ies(self, path: _Path, position: _Vec3, direction: _Vec3 = (0.0, -1.0, 0.0), *,
                lumens: Optional[float] = None, multiplier: float = 1.0, color: Optional[_Rgb] = None,
                temperature: Optional[float] = None) -> int: ...
    def add_mesh(self, vertices: npt.ArrayLike, indices: npt.ArrayLike) -> int: ...
    def load_gltf(self, path: _Path) -> None: ...
    def move(self, id: int, position: _Vec3, direction: Optional[_Vec3] = None) -> None: ...
    def remove(self, id: int) -> None: ...
    def irradiance(self, points: _Points, normals: _Points, *, spp: int = 64,
                   threads: Optional[int] = None) -> npt.NDArray[np.float32]: ...
    def sample_li(self, points: _Points, normals: _Points, *, spp: int = 1,
                  threads: Optional[int] = None) -> Dict[str, np.ndarray]: ...
    def warnings(self) -> List[str]: ...
