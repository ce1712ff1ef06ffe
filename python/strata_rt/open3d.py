"""Open3D's ray-casting scene on strata.

``RaycastingScene`` has the methods, arguments, result keys, dtypes and
invalid ids of Open3D's tensor ``open3d.t.geometry.RaycastingScene``, so
that code written for it runs on strata by changing one import::

    from strata_rt.open3d import RaycastingScene

    scene = RaycastingScene()
    cube_id = scene.add_triangles(vertices, triangles)   # or a mesh
    rays = RaycastingScene.create_rays_pinhole(
        fov_deg=60, center=[0.5, 0.5, 0.5], eye=[-1, -1, -1], up=[0, 0, 1],
        width_px=320, height_px=240)
    ans = scene.cast_rays(rays)          # ans["t_hit"]: (240, 320) float32

It takes numpy arrays (and lists), and Open3D tensors and meshes where
Open3D is installed; it answers with numpy arrays, or with Open3D tensors
where it was given one or holds an Open3D mesh. ``create_rays_pinhole``
answers a tensor, as Open3D's does, wherever ``open3d`` is imported
(found in ``sys.modules``), else a numpy array: Open3D is never imported
by ``strata_rt``. A query point with a NaN or infinite coordinate gets
Open3D's answers: distance NaN (a NaN coordinate) or inf, occupancy 0,
no closest point (INVALID_ID).

What differs is what strata does better: a ray through a shared edge or
vertex of a closed mesh is counted once (``count_intersections``,
``list_intersections``, the sign of ``compute_signed_distance`` and
``compute_occupancy``), never twice or not at all, so one sample
(``nsamples=1``) is exact; and a ray with a NaN or infinite coordinate
or a zero direction is a miss. Meshes far from the origin are traced
relative to their centre (``strata_rt.Mesh``). Also different: a ray that
starts exactly on a surface does not hit it there, as strata's rays
cover (0, t_max] so that a ray leaving a surface does not hit it again.
From a point on a face of a box, Open3D 0.20 answers t_hit 0 both ways,
counts 2 crossings going into the box and 1 going out, and calls both
occluded; strata answers the far face's t_hit and 1 crossing going in,
and going out t_hit inf, 0 crossings, not occluded.
"""

from __future__ import annotations

import math
import sys
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from ._native import Mesh

__all__ = ["RaycastingScene", "INVALID_ID"]

#: The id of no geometry and no primitive: a miss (Open3D's value).
INVALID_ID = 4294967295


def _is_open3d(x: Any) -> bool:
    return type(x).__module__.split(".")[0] == "open3d"


def _array(x: Any, name: str) -> np.ndarray:
    """``x`` as a numpy array: an Open3D tensor by its ``numpy()``."""
    if _is_open3d(x) and hasattr(x, "numpy"):
        x = x.numpy()
    try:
        return np.asarray(x)
    except Exception as err:  # noqa: BLE001 - named for the user
        raise ValueError(f"{name} must be an array of numbers: {err}") from None


def _threads(nthreads: Any) -> Optional[int]:
    """Open3D's ``nthreads`` (0: every core) as strata's ``threads``."""
    if isinstance(nthreads, bool) or not isinstance(nthreads, (int, np.integer)) or nthreads < 0:
        raise ValueError(f"nthreads must be an int >= 0 (0 for every core); got {nthreads!r}")
    return None if nthreads == 0 else int(nthreads)


def _nsamples(nsamples: Any) -> int:
    ok = isinstance(nsamples, (int, np.integer)) and not isinstance(nsamples, bool)
    if not ok or nsamples < 1 or nsamples % 2 == 0:
        raise ValueError(f"nsamples must be an odd int >= 1; got {nsamples!r}")
    return int(nsamples)


def _rows(x: Any, width: int, name: str) -> Tuple[np.ndarray, Tuple[int, ...]]:
    """``x`` of shape (..., width) as (n, width) rows and its leading shape."""
    a = _array(x, name)
    if a.dtype.kind not in "fiu":
        raise ValueError(f"{name} must be an array of numbers of shape (..., {width}); got dtype {a.dtype}")
    if a.ndim < 1 or a.shape[-1] != width:
        raise ValueError(f"{name} must have shape (..., {width}); got {a.shape}")
    return a.reshape(-1, width), a.shape[:-1]


def _mesh_arrays(mesh: Any) -> Tuple[Any, Any]:
    """Vertices and triangles of one mesh object: an Open3D tensor mesh
    (``vertex.positions``, ``triangle.indices``), a legacy Open3D mesh
    (``vertices``, ``triangles``), a trimesh (``vertices``, ``faces``) or a
    ``strata_rt.Mesh`` (its float64 ``vertices`` and ``faces``: its
    float32 ``triangles`` would move a far mesh's corners)."""
    if isinstance(mesh, Mesh):
        return mesh.vertices, mesh.faces
    if hasattr(mesh, "vertex") and hasattr(mesh, "triangle"):
        return mesh.vertex["positions"], mesh.triangle["indices"]
    for faces in ("faces", "triangles"):
        if hasattr(mesh, "vertices") and hasattr(mesh, faces):
            return mesh.vertices, getattr(mesh, faces)
    raise TypeError(
        "add_triangles takes vertex_positions and triangle_indices, or one mesh "
        f"(Open3D's, trimesh's or a strata_rt.Mesh); got a {type(mesh).__name__}"
    )


def _vote_directions(n: int) -> np.ndarray:
    """``n`` fixed directions for majority votes of inside or outside:
    points of a Fibonacci sphere turned off every axis and diagonal."""
    k = np.arange(n, dtype=np.float64) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = k * math.pi * (3.0 - math.sqrt(5.0)) + 0.3141592653589793
    r = np.sqrt(1.0 - z * z)
    d = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    # A small fixed turn, so that no direction runs along an axis.
    a, b = 0.2718281828, 0.1414213562
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    return d @ (ry @ rx).T


class RaycastingScene:
    """A scene of triangle meshes and strata's queries on it, as Open3D's
    ``open3d.t.geometry.RaycastingScene`` has them (module docs).

    ``nthreads``: the threads every query runs on by default (0: every
    core); each query's own ``nthreads`` overrides it where not 0.
    ``device`` is accepted for Open3D's signature and must be the CPU.
    """

    #: The id of no geometry and no primitive: a miss.
    INVALID_ID = INVALID_ID

    def __init__(self, nthreads: int = 0, device: Any = None) -> None:
        self._nthreads = _threads(nthreads)
        if device is not None and "cpu" not in str(device).lower():
            raise ValueError(f"device must be the CPU; got {device}")
        self._vertices: List[np.ndarray] = []
        self._faces: List[np.ndarray] = []
        self._mesh: Optional[Mesh] = None
        #: Where each geometry's faces start in the scene's mesh; the last
        #: entry is the face count.
        self._starts = np.zeros(1, dtype=np.int64)
        self._tensors = False

    def add_triangles(self, vertex_positions: Any, triangle_indices: Any = None) -> int:
        """Add a triangle mesh: ``vertex_positions`` (n, 3) floats and
        ``triangle_indices`` (m, 3) integers, or one mesh object (Open3D's
        tensor or legacy mesh, a trimesh, a ``strata_rt.Mesh``). Returns
        its geometry id (0, 1, ... in the order added). The scene's tree is
        built again at the next query."""
        if triangle_indices is None:
            vertex_positions, triangle_indices = _mesh_arrays(vertex_positions)
        self._tensors |= _is_open3d(vertex_positions)
        v = _array(vertex_positions, "vertex_positions")
        f = _array(triangle_indices, "triangle_indices")
        if v.size == 0:
            v = v.reshape(0, 3)
        if f.size == 0:
            f = f.reshape(0, 3)
        if v.ndim != 2 or v.shape[1] != 3 or v.dtype.kind not in "fiu":
            raise ValueError(f"vertex_positions must be an (n, 3) array of floats; got shape {v.shape}, dtype {v.dtype}")
        if f.ndim != 2 or f.shape[1] != 3 or f.dtype.kind not in "iu":
            raise ValueError(f"triangle_indices must be an (m, 3) array of integers; got shape {f.shape}, dtype {f.dtype}")
        f = f.astype(np.int64)
        if f.size and (f.min() < 0 or f.max() >= len(v)):
            bad = int(np.flatnonzero(((f < 0) | (f >= len(v))).any(axis=1))[0])
            raise ValueError(f"triangle_indices[{bad}] = {f[bad].tolist()} is out of range for {len(v)} vertices")
        # A vertex no triangle uses is never traced (Open3D takes a depth
        # image's NaN vertices); one a triangle uses must be finite.
        bad_rows = ~np.isfinite(v).all(axis=1)
        if bad_rows.any() and f.size:
            used_bad = bad_rows[f]
            if used_bad.any():
                face = int(np.flatnonzero(used_bad.any(axis=1))[0])
                bad = int(f[face][used_bad[face]][0])
                raise ValueError(
                    f"vertex_positions[{bad}] is not finite: {v[bad].tolist()} (triangle_indices[{face}] uses it)"
                )
        self._vertices.append(np.asarray(v, dtype=np.float64))
        self._faces.append(f)
        self._starts = np.append(self._starts, self._starts[-1] + len(f))
        self._mesh = None
        return len(self._faces) - 1

    # ------------------------------------------------------------ internals

    @property
    def mesh(self) -> Mesh:
        """The ``strata_rt.Mesh`` of every geometry, face ``k`` of geometry
        ``g`` being its face ``starts[g] + k``; built on first use."""
        if self._mesh is None:
            offsets = np.cumsum([0] + [len(v) for v in self._vertices])
            vertices = np.concatenate(self._vertices) if self._vertices else np.zeros((0, 3))
            faces = (
                np.concatenate([f + o for f, o in zip(self._faces, offsets)])
                if self._faces
                else np.zeros((0, 3), dtype=np.int64)
            )
            self._mesh = Mesh(vertices, faces)
            self._scene_vertices, self._scene_faces = vertices, faces
        return self._mesh

    def _ids(self, face: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """Geometry and primitive ids (uint32, INVALID_ID for -1) of scene faces."""
        if len(self._starts) == 2:
            # One geometry (id 0), whose faces are the scene's: -1 cast to
            # uint32 wraps to INVALID_ID. A tenth of cast_rays' time saved
            # on the dragon (no search, one pass for each array).
            return np.where(face >= 0, np.uint32(0), np.uint32(INVALID_ID)), face.astype(np.uint32)
        hit = face >= 0
        geometry = np.searchsorted(self._starts, face, side="right") - 1
        geometry_ids = np.where(hit, geometry, INVALID_ID).astype(np.uint32)
        primitive_ids = np.where(hit, face - self._starts[np.maximum(geometry, 0)], INVALID_ID).astype(np.uint32)
        return geometry_ids, primitive_ids

    def _normals(self, face: np.ndarray) -> np.ndarray:
        """Unit normals (right-hand rule, float32) of scene faces; 0 for -1."""
        self.mesh  # noqa: B018 - builds the scene's arrays
        hit = face >= 0
        if len(self._scene_faces) == 0:  # an empty scene: nothing to index, nothing hit
            return np.zeros(face.shape + (3,), dtype=np.float32)
        tri = self._scene_vertices[self._scene_faces[np.where(hit, face, 0)]]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        length = np.linalg.norm(n, axis=1, keepdims=True)
        n = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
        return np.where(hit[:, None], n, 0.0).astype(np.float32)

    def _query_threads(self, nthreads: Any) -> Optional[int]:
        own = _threads(nthreads)
        return self._nthreads if own is None else own

    def _out(self, given: Any, result: Any) -> Any:
        """A result as Open3D tensors where the input was one."""
        if not (_is_open3d(given) or self._tensors):
            return result
        o3d = sys.modules.get("open3d")
        if o3d is None:
            return result
        wrap = o3d.core.Tensor.from_numpy
        if isinstance(result, dict):
            return {k: wrap(np.ascontiguousarray(v)) for k, v in result.items()}
        return wrap(np.ascontiguousarray(result))

    def _rays(self, rays: Any) -> Tuple[np.ndarray, np.ndarray, Tuple[int, ...]]:
        r, shape = _rows(rays, 6, "rays")
        r = r if r.dtype.kind == "f" else r.astype(np.float64)
        return r[:, :3], r[:, 3:], shape

    # ------------------------------------------------------------- rays

    def cast_rays(self, rays: Any, nthreads: int = 0) -> Dict[str, Any]:
        """The first hit of each ray of ``rays`` ((..., 6): origin and
        direction; ``t`` in direction lengths): ``t_hit`` float32 (...)
        (inf on a miss), ``geometry_ids`` and ``primitive_ids`` uint32 (...)
        (INVALID_ID on a miss), ``primitive_uvs`` float32 (..., 2) and
        ``primitive_normals`` float32 (..., 3) (zeros on a miss)."""
        o, d, shape = self._rays(rays)
        hits = self.mesh.intersect(
            o, d, threads=self._query_threads(nthreads), bad_rays="miss", fields=("t", "prim", "u", "v", "normal"),
            zero_misses=True,
        )
        geometry_ids, primitive_ids = self._ids(hits.prim)
        uvs, normals = np.stack([hits.u, hits.v], axis=1), hits.normal
        return self._out(rays, {
            "t_hit": hits.t.reshape(shape),
            "geometry_ids": geometry_ids.reshape(shape),
            "primitive_ids": primitive_ids.reshape(shape),
            "primitive_uvs": uvs.reshape(shape + (2,)),
            "primitive_normals": normals.reshape(shape + (3,)),
        })

    def test_occlusions(self, rays: Any, tnear: float = 0.0, tfar: float = math.inf, nthreads: int = 0) -> Any:
        """Whether anything lies on each ray between ``tnear`` and ``tfar``
        (in direction lengths): bool (...)."""
        o, d, shape = self._rays(rays)
        if not (tnear >= 0 and math.isfinite(tnear)):
            raise ValueError(f"tnear must be a finite number >= 0; got {tnear}")
        if not tfar >= 0:
            raise ValueError(f"tfar must be a number >= 0 (inf for no limit); got {tfar}")
        blocked = self.mesh.occluded(
            o, d, t_max=tfar, t_min=tnear, threads=self._query_threads(nthreads), bad_rays="miss"
        )
        return self._out(rays, blocked.reshape(shape))

    def count_intersections(self, rays: Any, nthreads: int = 0) -> Any:
        """How many times each ray crosses the scene's surfaces: int32
        (...). A ray through an edge or vertex that triangles of a closed
        mesh share crosses once there."""
        o, d, shape = self._rays(rays)
        counts = self.mesh.count_hits(o, d, threads=self._query_threads(nthreads), bad_rays="miss")
        return self._out(rays, counts.astype(np.int32).reshape(shape))

    def list_intersections(self, rays: Any, nthreads: int = 0) -> Dict[str, Any]:
        """Every crossing of every ray, ray after ray, each ray's nearest
        first: ``ray_splits`` uint32 (n + 1,) (ray ``i``'s crossings are
        ``ray_splits[i]:ray_splits[i+1]``), ``ray_ids``, ``geometry_ids``,
        ``primitive_ids`` uint32, ``t_hit`` float32, ``primitive_uvs``
        float32 (h, 2). The uvs are computed in float64 where the ray meets
        the face's plane."""
        o, d, _ = self._rays(rays)
        found = self.mesh.all_hits(o, d, threads=self._query_threads(nthreads), bad_rays="miss", uv=True)
        geometry_ids, primitive_ids = self._ids(found.prim)
        uvs = np.stack([found.u, found.v], axis=1)
        uvs = np.clip(uvs, 0.0, 1.0, out=uvs).astype(np.float32)
        return self._out(rays, {
            "ray_splits": found.splits.astype(np.uint32),
            "ray_ids": found.ray.astype(np.uint32),
            "t_hit": found.t,
            "geometry_ids": geometry_ids,
            "primitive_ids": primitive_ids,
            "primitive_uvs": uvs,
        })

    # ----------------------------------------------------------- points

    def _closest(self, p: np.ndarray, threads: Optional[int]) -> Dict[str, np.ndarray]:
        """``Mesh.closest_point`` of each row of ``p`` (n, 3), as arrays of
        every row: a point with a NaN or infinite coordinate (which
        ``Mesh`` refuses) has none, as in an empty scene (point, u, v NaN,
        prim -1), at the distance Open3D gives it: NaN for a NaN
        coordinate, else inf."""
        finite = np.isfinite(p).all(axis=1)
        if finite.all():
            near = self.mesh.closest_point(p, threads=threads)
            return {k: near[k] for k in ("point", "distance", "prim", "u", "v")}
        out = {
            "point": np.full((len(p), 3), np.nan),
            "distance": np.where(np.isnan(p).any(axis=1), np.nan, np.inf),
            "prim": np.full(len(p), -1, dtype=np.int64),
            "u": np.full(len(p), np.nan),
            "v": np.full(len(p), np.nan),
        }
        if finite.any():
            near = self.mesh.closest_point(p[finite], threads=threads)
            for k in out:
                out[k][finite] = near[k]
        return out

    def compute_closest_points(self, query_points: Any, nthreads: int = 0) -> Dict[str, Any]:
        """The nearest surface point to each point of ``query_points``
        ((..., 3)): ``points`` float32 (..., 3), ``geometry_ids`` and
        ``primitive_ids`` uint32 (...), ``primitive_uvs`` float32 (..., 2)
        and ``primitive_normals`` float32 (..., 3) of its face. A query
        point with a NaN or infinite coordinate has none: INVALID_ID, as
        Open3D answers (whose points, uvs and normals are then whatever
        its memory held), with NaN points and uvs and zero normals."""
        p, shape = _rows(query_points, 3, "query_points")
        near = self._closest(p, self._query_threads(nthreads))
        geometry_ids, primitive_ids = self._ids(near["prim"])
        uvs = np.stack([near["u"], near["v"]], axis=1).astype(np.float32)
        return self._out(query_points, {
            "points": near["point"].astype(np.float32).reshape(shape + (3,)),
            "geometry_ids": geometry_ids.reshape(shape),
            "primitive_ids": primitive_ids.reshape(shape),
            "primitive_uvs": uvs.reshape(shape + (2,)),
            "primitive_normals": self._normals(near["prim"]).reshape(shape + (3,)),
        })

    def compute_distance(self, query_points: Any, nthreads: int = 0) -> Any:
        """The distance from each point to the nearest surface: float32
        (...); as Open3D's, NaN for a point with a NaN coordinate and inf
        for one with an infinite coordinate."""
        p, shape = _rows(query_points, 3, "query_points")
        distance = self._closest(p, self._query_threads(nthreads))["distance"]
        return self._out(query_points, distance.astype(np.float32).reshape(shape))

    def _inside(self, p: np.ndarray, nsamples: int, threads: Optional[int]) -> np.ndarray:
        """Inside or not: one exact parity (``Mesh.contains``), or the
        majority of ``nsamples`` parities along fixed directions. A point
        with a NaN or infinite coordinate is outside (Open3D's occupancy
        0 for it)."""
        finite = np.isfinite(p).all(axis=1)
        if not finite.all():
            inside = np.zeros(len(p), dtype=bool)
            inside[finite] = self._inside(p[finite], nsamples, threads)
            return inside
        if nsamples == 1:
            return self.mesh.contains(p, threads=threads)
        votes = np.zeros(len(p), dtype=np.int64)
        for direction in _vote_directions(nsamples):
            d = np.broadcast_to(direction, p.shape)
            votes += self.mesh.count_hits(p, d, threads=threads) % 2
        return votes * 2 > nsamples

    def compute_signed_distance(self, query_points: Any, nthreads: int = 0, nsamples: int = 1) -> Any:
        """The distance to the nearest surface, negative inside (meant for
        closed meshes that do not intersect one another): float32 (...).
        Inside is the parity of the crossings along a ray (``nsamples``
        rays, odd, by majority), exact on shared edges and vertices. A
        point with a NaN coordinate gives NaN, one with an infinite
        coordinate inf, as in Open3D."""
        p, shape = _rows(query_points, 3, "query_points")
        nsamples = _nsamples(nsamples)
        threads = self._query_threads(nthreads)
        distance = self._closest(p, threads)["distance"]
        inside = self._inside(p, nsamples, threads)
        signed = np.where(inside, -distance, distance).astype(np.float32)
        return self._out(query_points, signed.reshape(shape))

    def compute_occupancy(self, query_points: Any, nthreads: int = 0, nsamples: int = 1) -> Any:
        """1 inside, 0 outside, float32 (...): as ``compute_signed_distance``
        decides the sign (0 for a point with a NaN or infinite coordinate,
        as in Open3D)."""
        p, shape = _rows(query_points, 3, "query_points")
        inside = self._inside(p, _nsamples(nsamples), self._query_threads(nthreads))
        return self._out(query_points, inside.astype(np.float32).reshape(shape))

    # ----------------------------------------------------------- cameras

    @staticmethod
    def create_rays_pinhole(*args: Any, **kwargs: Any) -> Any:
        """Rays of a pinhole camera, float32 (height_px, width_px, 6), one
        through each pixel's centre, directions not normalised (their
        camera-space z is 1): an Open3D tensor, as Open3D's own answers,
        where the ``open3d`` module is imported (in ``sys.modules``: Open3D
        is in use, and a scene of its tensor meshes answers in tensors,
        which this camera's rays must index), else a numpy array. Either
        form of Open3D's:

        ``create_rays_pinhole(intrinsic_matrix, extrinsic_matrix, width_px,
        height_px)``: a 3x3 intrinsic matrix and a 4x4 world-to-camera map
        (camera looks along +z, y down the image);

        ``create_rays_pinhole(fov_deg, center, eye, up, width_px,
        height_px)``: the horizontal field of view in degrees, the point
        looked at, the camera's position and the up vector (as Open3D
        does it, row 0 of the rays is the one nearest ``up``'s opposite:
        image y runs along ``up``).
        """
        names_k = ["intrinsic_matrix", "extrinsic_matrix", "width_px", "height_px"]
        names_f = ["fov_deg", "center", "eye", "up", "width_px", "height_px"]
        by_matrix = "intrinsic_matrix" in kwargs or (args and np.ndim(_array(args[0], "intrinsic_matrix")) == 2)
        names = names_k if by_matrix else names_f
        if len(args) > len(names):
            raise TypeError(f"create_rays_pinhole takes {len(names)} arguments ({', '.join(names)}); got {len(args)}")
        given = dict(zip(names, args))
        for k, v in kwargs.items():
            if k not in names or k in given:
                raise TypeError(f"create_rays_pinhole got an unexpected or repeated argument {k!r} (takes {', '.join(names)})")
            given[k] = v
        missing = [n for n in names if n not in given]
        if missing:
            raise TypeError(f"create_rays_pinhole is missing {', '.join(missing)}")
        width, height = (_pixels(given[n], n) for n in ("width_px", "height_px"))
        if by_matrix:
            k = _matrix(given["intrinsic_matrix"], (3, 3), "intrinsic_matrix")
            e = _matrix(given["extrinsic_matrix"], (4, 4), "extrinsic_matrix")
            rays = _pinhole(k, e[:3, :3], e[:3, 3], width, height)
        else:
            rays = _look_at(given, width, height)
        # Open3D's tutorial passes lists and indexes these rays with the
        # scene's answers, tensors: only whether Open3D is loaded can tell
        # the two uses apart (and strata never imports it itself).
        o3d = sys.modules.get("open3d")
        if o3d is not None:
            return o3d.core.Tensor.from_numpy(rays)
        return rays


def _pixels(x: Any, name: str) -> int:
    if isinstance(x, bool) or not isinstance(x, (int, np.integer)) or x < 1:
        raise ValueError(f"{name} must be an int >= 1; got {x!r}")
    return int(x)


def _matrix(x: Any, shape: Tuple[int, int], name: str) -> np.ndarray:
    m = _array(x, name).astype(np.float64)
    if m.shape != shape or not np.isfinite(m).all():
        raise ValueError(f"{name} must be a finite {shape[0]}x{shape[1]} matrix; got shape {m.shape}")
    return m


def _pinhole(k: np.ndarray, rotation: np.ndarray, translation: np.ndarray, width: int, height: int) -> np.ndarray:
    """Rays through pixel centres of the camera ``k`` whose world-to-camera
    map is ``x ↦ rotation·x + translation``: origin the camera's centre
    (−Rᵀt), direction Rᵀ·K⁻¹·(u + ½, v + ½, 1)."""
    try:
        k_inv = np.linalg.inv(k)
    except np.linalg.LinAlgError:
        raise ValueError("intrinsic_matrix must be invertible") from None
    u, v = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    pixels = np.stack([u, v, np.ones_like(u)], axis=-1)
    directions = pixels @ (rotation.T @ k_inv).T
    origin = -rotation.T @ translation
    rays = np.empty((height, width, 6), dtype=np.float32)
    rays[..., :3] = origin
    rays[..., 3:] = directions
    return rays


def _look_at(given: Dict[str, Any], width: int, height: int) -> np.ndarray:
    """The fov form: a camera at ``eye`` looking at ``center``, image x
    along ``up × forward`` and image y along ``forward × x`` (``up`` made
    square to the view: Open3D's first row of rays is the bottom one), focal
    length ``width / 2 / tan(fov / 2)`` pixels, principal point the image's
    centre."""
    fov = float(given["fov_deg"])
    if not 0 < fov < 180:
        raise ValueError(f"fov_deg must be between 0 and 180 degrees; got {fov}")
    vec = {n: _array(given[n], n).astype(np.float64).reshape(-1) for n in ("center", "eye", "up")}
    for n, x in vec.items():
        if x.shape != (3,) or not np.isfinite(x).all():
            raise ValueError(f"{n} must be 3 finite numbers; got {given[n]!r}")
    forward = vec["center"] - vec["eye"]
    side = np.cross(vec["up"], forward)
    if np.linalg.norm(forward) == 0 or np.linalg.norm(side) == 0:
        raise ValueError("center must differ from eye, and up must not be along the view")
    forward /= np.linalg.norm(forward)
    side /= np.linalg.norm(side)
    along_y = np.cross(forward, side)
    focal = 0.5 * width / math.tan(math.radians(fov) / 2)
    k = np.array([[focal, 0, width / 2], [0, focal, height / 2], [0, 0, 1]])
    rotation = np.stack([side, along_y, forward])  # world to camera: rows are the camera's axes
    return _pinhole(k, rotation, -rotation @ vec["eye"], width, height)
