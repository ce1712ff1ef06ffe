"""Type stubs of strata_rt._native, the compiled half of strata_rt."""

import os
from typing import Any, Callable, Dict, Iterator, List, Literal, Mapping, Optional, Sequence, Tuple, TypeVar, Union, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

__version__: str

_T = TypeVar("_T")

class InputError(ValueError):
    """A file or scene strata cannot use: the message is strata's one line,
    naming the file and the key or line."""

class Hits:
    """The first hit of each ray (``Mesh.intersect``), as attributes or keys; an array
    not asked for in ``fields`` is None and not among the keys. A mapping of names to
    arrays (``keys()``, ``items()``, ``get()``, ``dict(hits)``), indexed by name, not by
    ray: ``hits.t[0]`` is ray 0's distance. It pickles."""

    @property
    def t(self) -> Optional[NDArray[np.float32]]:
        """float32 (n,): distance along the ray, in direction lengths; inf on a miss."""
    @property
    def prim(self) -> Optional[NDArray[np.int64]]:
        """int64 (n,): the triangle (face index) hit; -1 on a miss."""
    @property
    def u(self) -> Optional[NDArray[np.float32]]:
        """float32 (n,): barycentric coordinate of the face's second vertex; NaN on a miss."""
    @property
    def v(self) -> Optional[NDArray[np.float32]]:
        """float32 (n,): barycentric coordinate of the face's third vertex; NaN on a miss."""
    @property
    def normal(self) -> Optional[NDArray[np.float32]]:
        """float32 (n, 3): unit geometric normal of the triangle hit (right-hand rule); NaN on a miss."""
    @property
    def point(self) -> Optional[NDArray[np.float64]]:
        """float64 (n, 3): where the ray meets the triangle's plane, computed in float64 on the
        triangle as given (on its plane to float64's precision, wherever the mesh lies); NaN on a miss."""
    def __getitem__(self, key: str) -> NDArray[Any]:
        """The array named ``key``: one of ``keys()``; KeyError for another name, TypeError
        for an int (index the array instead: ``hits.t[0]``)."""
    def keys(self) -> List[str]:
        """The names of the arrays computed (by default t, prim, u, v, normal, point)."""
    def items(self) -> List[Tuple[str, NDArray[Any]]]:
        """``(name, array)`` of each array computed, in the order of ``keys()``."""
    def values(self) -> List[NDArray[Any]]:
        """The arrays computed, in the order of ``keys()``."""
    def get(self, key: str, default: Optional[_T] = None) -> Union[NDArray[Any], _T, None]:
        """The array named ``key`` if it was computed, else ``default``."""
    def __contains__(self, key: object) -> bool:
        """Whether ``key`` names one of the arrays computed."""
    def __len__(self) -> int:
        """The length of the rays' first axis (the number of rays for an (n, 3) input), as
        numpy's ``len``; a TypeError for one ray given as (3,)."""
    def __reduce__(
        self,
    ) -> Tuple[Callable[..., "Hits"], Tuple[Optional[NDArray[Any]], ..., List[int]]]:
        """Pickling: ``Hits._unpickle`` of t, prim, u, v, normal, point (None where not
        computed) and the rays' leading shape."""
    @staticmethod
    def _unpickle(
        t: Optional[NDArray[np.float32]],
        prim: Optional[NDArray[np.int64]],
        u: Optional[NDArray[np.float32]],
        v: Optional[NDArray[np.float32]],
        normal: Optional[NDArray[np.float32]],
        point: Optional[NDArray[np.float64]],
        shape: Sequence[int],
    ) -> "Hits":
        """Unpickling: the Hits of these arrays and leading shape."""

class ClosestPoints:
    """The nearest surface point to each query point (``Mesh.closest_point``), as attributes or keys:
    a mapping of names to arrays, as ``Hits`` is. It pickles."""

    @property
    def point(self) -> NDArray[np.float64]:
        """float64 (n, 3): the nearest point on the surface, computed in float64 on the triangle
        as given; NaN where none lies within max_distance."""
    @property
    def distance(self) -> NDArray[np.float64]:
        """float64 (n,): its distance (negative inside with ``signed=True``); inf where none."""
    @property
    def prim(self) -> NDArray[np.int64]:
        """int64 (n,): the triangle (face index) it lies on; -1 where none."""
    @property
    def u(self) -> NDArray[np.float64]:
        """float64 (n,): barycentric coordinate of the face's second vertex at the point; NaN where none."""
    @property
    def v(self) -> NDArray[np.float64]:
        """float64 (n,): barycentric coordinate of the face's third vertex at the point; NaN where none."""
    def __getitem__(self, key: str) -> NDArray[Any]:
        """The array named ``key``: one of ``keys()``; KeyError for another name, TypeError
        for an int (index the array instead: ``near.distance[0]``)."""
    def keys(self) -> List[str]:
        """The names of the arrays: point, distance, prim, u, v."""
    def items(self) -> List[Tuple[str, NDArray[Any]]]:
        """``(name, array)`` of each array, in the order of ``keys()``."""
    def values(self) -> List[NDArray[Any]]:
        """The arrays, in the order of ``keys()``."""
    def get(self, key: str, default: Optional[_T] = None) -> Union[NDArray[Any], _T, None]:
        """The array named ``key``, else ``default``."""
    def __contains__(self, key: object) -> bool:
        """Whether ``key`` names one of the arrays."""
    def __len__(self) -> int:
        """The length of the points' first axis (the number of points for an (n, 3) input),
        as numpy's ``len``; a TypeError for one point given as (3,)."""
    def __reduce__(self) -> Tuple[Callable[..., "ClosestPoints"], Tuple[Any, ...]]:
        """Pickling: ``ClosestPoints._unpickle`` of point, distance, prim, u, v and the
        points' leading shape."""
    @staticmethod
    def _unpickle(
        point: NDArray[np.float64],
        distance: NDArray[np.float64],
        prim: NDArray[np.int64],
        u: NDArray[np.float64],
        v: NDArray[np.float64],
        shape: Sequence[int],
    ) -> "ClosestPoints":
        """Unpickling: the ClosestPoints of these arrays and leading shape."""

class Crossings:
    """Every crossing of each ray (``Mesh.all_hits``), ray after ray, each ray's nearest first,
    as attributes or keys (``keys()``, ``items()``, ``get()``); unpacks as ``splits, t, prim``.
    It pickles."""

    @property
    def splits(self) -> NDArray[np.int64]:
        """int64 (n + 1,): ray i's crossings are ``splits[i]:splits[i+1]`` (Open3D's ray_splits)."""
    @property
    def t(self) -> NDArray[np.float32]:
        """float32 (h,): each crossing's distance along its ray, in direction lengths."""
    @property
    def prim(self) -> NDArray[np.int64]:
        """int64 (h,): the triangle (face index) crossed."""
    @property
    def ray(self) -> NDArray[np.int64]:
        """int64 (h,): the ray each crossing is on (Open3D's ray_ids, trimesh's index_ray)."""
    @property
    def u(self) -> Optional[NDArray[np.float64]]:
        """float64 (h,): barycentric coordinate of the face's second vertex; None unless ``uv=True``."""
    @property
    def v(self) -> Optional[NDArray[np.float64]]:
        """float64 (h,): barycentric coordinate of the face's third vertex; None unless ``uv=True``."""
    def __getitem__(self, key: Union[str, int]) -> NDArray[Any]:
        """The array named ``key`` (one of ``keys()``), or splits, t, prim by their place 0, 1, 2."""
    def keys(self) -> List[str]:
        """The names of the arrays computed: splits, t, prim, ray (and u, v with ``uv=True``)."""
    def items(self) -> List[Tuple[str, NDArray[Any]]]:
        """``(name, array)`` of each array computed, in the order of ``keys()``."""
    def values(self) -> List[NDArray[Any]]:
        """The arrays computed, in the order of ``keys()``."""
    def get(self, key: str, default: Optional[_T] = None) -> Union[NDArray[Any], _T, None]:
        """The array named ``key`` if it was computed, else ``default``."""
    def __contains__(self, key: object) -> bool:
        """Whether ``key`` names one of the arrays computed."""
    def __iter__(self) -> Iterator[NDArray[Any]]:
        """``splits, t, prim``: what ``all_hits`` returned as a tuple before."""
    def __reduce__(
        self,
    ) -> Tuple[Callable[..., "Crossings"], Tuple[Optional[NDArray[Any]], ...]]:
        """Pickling: ``Crossings._unpickle`` of splits, t, prim, ray, u, v (u and v None
        unless computed)."""
    @staticmethod
    def _unpickle(
        splits: NDArray[np.int64],
        t: NDArray[np.float32],
        prim: NDArray[np.int64],
        ray: NDArray[np.int64],
        u: Optional[NDArray[np.float64]],
        v: Optional[NDArray[np.float64]],
    ) -> "Crossings":
        """Unpickling: the Crossings of these arrays."""

_TMax = Union[float, ArrayLike, None]

class Mesh:
    """A triangle mesh and its BVH, built once (on every core) and asked any number of queries.

    Queries take (n, 3) origins, directions and points, or (..., 3) of any leading shape
    whose answers come back in that shape (all_hits lists the rays flattened; one
    row given as (3,) answers 0-d; one origin or one direction goes with every row
    of the other, as numpy broadcasts it) (any float dtype; ``t`` is in
    direction lengths), ``t_max`` (a number or one per ray) and ``t_min``
    (where rays start); each releases the GIL and runs on every core, or on at
    most ``threads`` threads (never more than it has tasks of 256 rays or points:
    a small query, or ``threads=1``, runs on the calling thread). ``bad_rays="miss"`` makes a ray with a NaN or
    infinite coordinate or a zero direction a miss instead of a ValueError.
    A mesh far from the origin is traced relative to its centre, and hit
    and closest points are float64, computed on the triangle as given.
    """

    def __init__(self, vertices: Any, faces: Optional[ArrayLike] = None) -> None:
        """Build the mesh and its BVH from vertices ((n, 3) floats) and faces ((m, 3) integer indices),
        or from one mesh object that has them: a ``trimesh.Trimesh`` (``vertices``, ``faces``), an
        Open3D ``o3d.geometry.TriangleMesh`` (``vertices``, ``triangles``) or
        ``o3d.t.geometry.TriangleMesh`` (``vertex.positions``, ``triangle.indices``). A vertex no
        face uses is never traced and may be NaN; one a face uses must be finite (ValueError)."""
    def __reduce__(
        self,
    ) -> Union[
        Tuple[type, Tuple[NDArray[np.floating[Any]], NDArray[np.int64]]],
        Tuple[Callable[..., "Mesh"], Tuple[NDArray[np.float32], NDArray[np.int64], NDArray[np.float64]]],
    ]:
        """Pickling: as ``Mesh(vertices, faces)`` of its triangles, one float32 vertex row per corner;
        a mesh whose float64 vertices float32 does not hold exactly (most float64 arrays) as
        ``Mesh(vertices, faces)`` of them as given (float64, int64); a placed mesh as
        ``Mesh._placed(vertices, faces, transforms)`` of the mesh it places (float32, int64) and
        its maps (float64 (n, 3, 4)). The copy answers every query bit for bit as this one does."""
    @staticmethod
    def _placed(vertices: ArrayLike, faces: ArrayLike, transforms: ArrayLike) -> "Mesh":
        """Unpickling a placed mesh: ``Mesh(vertices, faces).place(transforms)``."""
    @staticmethod
    def load(path: Union[str, bytes, os.PathLike[str], os.PathLike[bytes]]) -> "Mesh":
        """Load an OBJ, PLY, glTF, GLB, OFF or STL file with strata's loaders; triangle i of the file
        is face i. ``path`` is a str, bytes or an ``os.PathLike``, as ``os.fspath`` takes them.
        OBJ, OFF and ASCII STL decimals and PLY ``double`` properties are kept in float64 (as from
        arrays); PLY ``float``, binary STL and glTF coordinates are read as float32. Only the faces
        are read (no material library or texture). A file strata cannot read raises
        ``InputError``; what it reads leniently (no faces) warns (``UserWarning``)."""
    @property
    def triangle_count(self) -> int:
        """The number of triangles (faces); of a placed mesh, every copy's."""
    def __len__(self) -> int:
        """The number of triangles (faces); of a placed mesh, every copy's."""
    @property
    def bounds(self) -> NDArray[np.float32]:
        """float32 (2, 3): the [min, max] corners of the bounding box."""
    @property
    def vertices(self) -> NDArray[np.float64]:
        """float64 (n, 3): the faces' corners, each position once, in order of first use (a loaded
        file's vertices less unused ones; a far mesh's arrays as given)."""
    @property
    def faces(self) -> NDArray[np.int64]:
        """int64 (m, 3): each face's indices into ``vertices``, in face order."""
    @property
    def triangles(self) -> NDArray[np.float32]:
        """float32 (m, 3, 3): each face's three vertices, in face order."""
    def place(self, transforms: ArrayLike) -> "Mesh":
        """This mesh placed once by each (3, 4) or (4, 4) row-major object-to-world
        matrix of ``transforms`` (n of them): stored once, each placement about
        170 bytes. Every query answers as a mesh of every copy would (face
        ``k * triangle_count + j`` is face ``j`` of copy ``k``): crossings,
        counts, ``contains`` and nearest points (world distances under any
        map) are the copies' bit for bit. ValueError names ``transforms[i]``
        for a matrix that is not finite or not invertible; a placed mesh
        cannot be placed again (NotImplementedError)."""
        ...
    def intersect(
        self,
        origins: ArrayLike,
        directions: ArrayLike,
        t_max: _TMax = None,
        threads: Optional[int] = None,
        t_min: Optional[float] = None,
        bad_rays: Literal["raise", "miss"] = "raise",
        fields: Optional[Sequence[Literal["t", "prim", "u", "v", "normal", "point"]]] = None,
        zero_misses: bool = False,
    ) -> Hits:
        """The first hit of each ray in (t_min, t_max] (t_min 0 and t_max inf by default): t, prim,
        u, v, normal, point, or only the arrays named in ``fields`` (the others are not computed);
        with ``zero_misses=True`` a miss's u, v, normal and point are 0 (as Open3D's), not NaN."""
    def occluded(
        self,
        origins: ArrayLike,
        directions: ArrayLike,
        t_max: _TMax = None,
        threads: Optional[int] = None,
        t_min: Optional[float] = None,
        bad_rays: Literal["raise", "miss"] = "raise",
    ) -> NDArray[np.bool_]:
        """Whether anything blocks each ray in (t_min, t_max] (t_min 0 and t_max inf by default):
        bool (n,)."""
    def all_hits(
        self,
        origins: ArrayLike,
        directions: ArrayLike,
        t_max: _TMax = None,
        threads: Optional[int] = None,
        t_min: Optional[float] = None,
        bad_rays: Literal["raise", "miss"] = "raise",
        uv: bool = False,
    ) -> Crossings:
        """Every surface crossing along each ray in (t_min, t_max] (t_min 0 and t_max inf by
        default), nearest first: splits (n+1,), t, prim, ray (and u, v with ``uv=True``); unpacks
        as ``splits, t, prim``."""
    def count_hits(
        self,
        origins: ArrayLike,
        directions: ArrayLike,
        t_max: _TMax = None,
        threads: Optional[int] = None,
        t_min: Optional[float] = None,
        bad_rays: Literal["raise", "miss"] = "raise",
    ) -> NDArray[np.int64]:
        """The number of surface crossings along each ray in (t_min, t_max] (t_min 0 and t_max
        inf by default): int64 (n,)."""
    def contains(self, points: ArrayLike, threads: Optional[int] = None) -> NDArray[np.bool_]:
        """Whether each point is inside the (closed) mesh, by crossing parity: bool (n,)."""
    def closest_point(
        self,
        points: ArrayLike,
        max_distance: Optional[float] = None,
        signed: bool = False,
        threads: Optional[int] = None,
    ) -> ClosestPoints:
        """The nearest surface point to each point: point (n, 3), distance (n,), prim (n,)."""

_Aovs = Union[bool, Sequence[Literal["albedo", "normal", "depth", "spp"]], None]
_Set = Union[Mapping[str, object], Sequence[str], str, None]

@overload
def render(
    scene: Union[str, os.PathLike[str], Mapping[str, Any]],
    *,
    width: Optional[int] = None,
    height: Optional[int] = None,
    spp: Optional[int] = None,
    shadow_samples: Optional[int] = None,
    reflection_samples: Optional[int] = None,
    max_depth: Optional[int] = None,
    sampler: Optional[Literal["stratified", "sobol", "random"]] = None,
    seed: Optional[int] = None,
    background: Optional[Sequence[float]] = None,
    light_sampling: Optional[Literal["solid_angle", "area", "auto"]] = None,
    glossy_sampling: Optional[Literal["lobe", "uniform"]] = None,
    noise: Optional[float] = None,
    exposure: Optional[float] = None,
    tonemap: Optional[Literal["clamp", "filmic"]] = None,
    integrator: Optional[Literal["distribution", "path"]] = None,
    set: _Set = None,
    camera: Union[int, Literal["auto"], None] = None,
    threads: Optional[int] = None,
    passes: Optional[int] = None,
    packets: Optional[Literal["auto", "on", "off"]] = None,
    schedule: Optional[Literal["slices", "regions"]] = None,
    bvh_quality: Optional[Literal["preview", "fastest", "fast", "auto", "medium", "high"]] = None,
    crop: Union[Tuple[int, int, int, int], str, None] = None,
    aovs: Literal[False, None] = None,
) -> NDArray[np.float32]:
    """Render a scene file, or a model file as it comes, as ``strata render`` does: float32
    (height, width, 3), the CLI's EXR pixels bit for bit."""
@overload
def render(
    scene: Union[str, os.PathLike[str], Mapping[str, Any]],
    *,
    width: Optional[int] = None,
    height: Optional[int] = None,
    spp: Optional[int] = None,
    shadow_samples: Optional[int] = None,
    reflection_samples: Optional[int] = None,
    max_depth: Optional[int] = None,
    sampler: Optional[Literal["stratified", "sobol", "random"]] = None,
    seed: Optional[int] = None,
    background: Optional[Sequence[float]] = None,
    light_sampling: Optional[Literal["solid_angle", "area", "auto"]] = None,
    glossy_sampling: Optional[Literal["lobe", "uniform"]] = None,
    noise: Optional[float] = None,
    exposure: Optional[float] = None,
    tonemap: Optional[Literal["clamp", "filmic"]] = None,
    integrator: Optional[Literal["distribution", "path"]] = None,
    set: _Set = None,
    camera: Union[int, Literal["auto"], None] = None,
    threads: Optional[int] = None,
    passes: Optional[int] = None,
    packets: Optional[Literal["auto", "on", "off"]] = None,
    schedule: Optional[Literal["slices", "regions"]] = None,
    bvh_quality: Optional[Literal["preview", "fastest", "fast", "auto", "medium", "high"]] = None,
    crop: Union[Tuple[int, int, int, int], str, None] = None,
    aovs: Union[Literal[True], Sequence[Literal["albedo", "normal", "depth", "spp"]]] = ...,
) -> Tuple[NDArray[np.float32], Dict[str, NDArray[np.float32]]]:
    """Render a scene file, or a model file as it comes, as ``strata render`` does, with its
    AOVs as a dict of arrays."""
