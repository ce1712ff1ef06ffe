"""trimesh's ray interface on strata.

``RayMeshIntersector(mesh)`` has the methods, arguments and return
conventions of trimesh's own intersectors (``trimesh.ray.ray_pyembree``
and ``trimesh.ray.ray_triangle``), so that::

    import trimesh
    from strata_rt.trimesh import RayMeshIntersector

    mesh = trimesh.load("bunny.obj")
    mesh.ray = RayMeshIntersector(mesh)
    mesh.ray.intersects_location(origins, directions)
    mesh.contains(points)          # trimesh asks mesh.ray.contains_points

swaps the engine under every trimesh call that casts rays. What differs
is what strata does better: every hit along a ray comes from one
traversal (``Mesh.all_hits``), not from re-casting each ray from its last
hit plus an offset, so a ray through a shared edge or vertex of a closed
mesh is reported once, never zero times or twice, at any scale; and each
ray's hits come together, nearest first (index_ray ascending).

Conventions kept from trimesh: indices are int64, locations float64
(computed in float64 on the mesh's own triangles, so they lie on the
face's plane at any coordinates), -1 marks a miss in
``intersects_first``, ``max_hits`` caps the hits of one ray, and a ray
with a zero-length direction, or a NaN or infinite coordinate, hits
nothing (as with trimesh's embreex engine), where ``strata_rt.Mesh``
itself raises naming the bad row; a point that is not finite is not
contained. The first hit ``intersects_first`` reports is always the first
of the ray's hits in ``intersects_id`` and ``intersects_location``, even
for a ray that only grazes a corner. trimesh is not imported: any object
with ``vertices`` (n, 3) and ``faces`` (m, 3) works.
"""

from __future__ import annotations

from typing import Any, Optional, Tuple, Union

import numpy as np

from ._native import Mesh

__all__ = ["RayMeshIntersector"]


class RayMeshIntersector:
    """strata behind trimesh's ray queries on ``mesh`` (a ``trimesh.Trimesh``).

    The BVH is built on first use and rebuilt when the mesh's vertices or
    faces change (trimesh's content hash). ``threads`` limits the threads
    every query runs on (``None``: every core).
    """

    def __init__(self, mesh: Any, threads: Optional[int] = None) -> None:
        """Intersect rays with ``mesh``; nothing is built until the first query."""
        self.mesh = mesh
        self.threads = threads
        self._key: Any = None
        self._strata: Optional[Mesh] = None

    @property
    def strata_mesh(self) -> Mesh:
        """The ``strata_rt.Mesh`` of the current vertices and faces."""
        try:
            key = hash(self.mesh)
        except TypeError:
            key = None
        if self._strata is None or key != self._key or key is None:
            self._strata = Mesh(np.asarray(self.mesh.vertices), np.asarray(self.mesh.faces))
            self._key = key
        return self._strata

    def _rays(self, ray_origins: Any, ray_directions: Any) -> Tuple[np.ndarray, np.ndarray]:
        """Origins and directions as arrays of the same shape; float64
        unless given as float32 (strata reads either where it lies)."""
        origins = np.asarray(ray_origins)
        directions = np.asarray(ray_directions)
        if origins.dtype.kind != "f" or origins.dtype.itemsize < 4:
            origins = origins.astype(np.float64)
        if directions.dtype.kind != "f" or directions.dtype.itemsize < 4:
            directions = directions.astype(np.float64)
        if origins.shape != directions.shape:
            raise ValueError(
                f"ray_origins and ray_directions must have the same shape; "
                f"got {origins.shape} and {directions.shape}"
            )
        if origins.size == 0:
            origins = origins.reshape((0, 3))
            directions = directions.reshape((0, 3))
        return origins, directions

    def _locations(
        self, origins: np.ndarray, directions: np.ndarray, index_ray: np.ndarray, index_tri: np.ndarray
    ) -> np.ndarray:
        """Where each ray meets its triangle's plane, in float64 on the
        mesh's own vertices (Cramer's rule, as Möller and Trumbore 1997):
        on the face's plane to float64's precision at any coordinates."""
        tri = np.asarray(self.mesh.vertices, dtype=np.float64)[np.asarray(self.mesh.faces)[index_tri]]
        o = origins[index_ray].astype(np.float64)
        d = directions[index_ray].astype(np.float64)
        a = tri[:, 0]
        e1, e2 = tri[:, 1] - a, tri[:, 2] - a
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        s = o - a
        q = np.cross(s, e1)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.einsum("ij,ij->i", e2, q) / det
        return o + d * t[:, None]

    def intersects_id(
        self,
        ray_origins: Any,
        ray_directions: Any,
        multiple_hits: bool = True,
        max_hits: Optional[int] = 100,
        return_locations: bool = False,
    ) -> Union[Tuple[np.ndarray, np.ndarray], Tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """The triangles the rays hit: ``(index_tri, index_ray)``, int64 (h,)
        each, and with ``return_locations`` the hit points, float64 (h, 3),
        computed in float64 on the mesh's own triangles.

        ``multiple_hits``: every hit along each ray (at most ``max_hits``,
        ``None`` for no limit), else only the first. Hits are grouped by
        ray, rays in ascending order, each ray's hits nearest first. A ray
        that only touches the surface (at a silhouette edge or corner) has
        its first hit listed where its crossings would not list it, so the
        first of a ray's hits is always ``intersects_first``'s.
        """
        origins, directions = self._rays(ray_origins, ray_directions)
        mesh = self.strata_mesh
        first = mesh.intersect(origins, directions, threads=self.threads, bad_rays="miss", fields=("t", "prim"))
        if multiple_hits:
            splits, t, prim = mesh.all_hits(origins, directions, threads=self.threads, bad_rays="miss")
            splits, t, prim = _with_first_hits(splits, t, prim, first.t, first.prim)
            counts = np.diff(splits)
            index_ray = np.repeat(np.arange(len(counts), dtype=np.int64), counts)
            if max_hits is not None:
                rank = np.arange(len(t), dtype=np.int64) - np.repeat(splits[:-1], counts)
                keep = rank < max_hits
                prim, index_ray = prim[keep], index_ray[keep]
        else:
            index_ray = np.flatnonzero(first.prim >= 0).astype(np.int64)
            prim = first.prim[index_ray]
        index_tri = prim.astype(np.int64)
        if not return_locations:
            return index_tri, index_ray
        return index_tri, index_ray, self._locations(origins, directions, index_ray, index_tri)

    def intersects_location(
        self, ray_origins: Any, ray_directions: Any, multiple_hits: bool = True
    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where the rays hit: ``(locations, index_ray, index_tri)``, float64
        (h, 3), int64 (h,) and int64 (h,); ordered as ``intersects_id``."""
        index_tri, index_ray, locations = self.intersects_id(
            ray_origins, ray_directions, multiple_hits=multiple_hits, return_locations=True
        )
        return locations, index_ray, index_tri

    def intersects_first(self, ray_origins: Any, ray_directions: Any) -> np.ndarray:
        """The first triangle each ray hits: int64 (n,), -1 for a miss."""
        origins, directions = self._rays(ray_origins, ray_directions)
        hits = self.strata_mesh.intersect(origins, directions, threads=self.threads, bad_rays="miss", fields=("prim",))
        return hits.prim

    def intersects_any(self, ray_origins: Any, ray_directions: Any) -> np.ndarray:
        """Whether each ray hits the mesh at all: bool (n,)."""
        origins, directions = self._rays(ray_origins, ray_directions)
        return self.strata_mesh.occluded(origins, directions, threads=self.threads, bad_rays="miss")

    def contains_points(self, points: Any) -> np.ndarray:
        """Whether each point is inside the mesh: bool (n,), by the parity of
        surface crossings along one ray (``Mesh.contains``; a closed mesh is
        assumed, and points on the surface may go either way). A point with
        a NaN or infinite coordinate is not contained."""
        points = np.asarray(points, dtype=np.float64)
        finite = np.isfinite(points).all(axis=-1) if points.ndim == 2 else None
        if finite is None or finite.all():
            return self.strata_mesh.contains(points, threads=self.threads)
        inside = np.zeros(len(points), dtype=bool)
        inside[finite] = self.strata_mesh.contains(points[finite], threads=self.threads)
        return inside


def _with_first_hits(
    splits: np.ndarray, t: np.ndarray, prim: np.ndarray, first_t: np.ndarray, first_prim: np.ndarray
) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every ray's crossings, led by its first hit: where the first
    crossing is at the first hit's t but names another face of the edge or
    corner there, the first hit's face; where the crossings start later
    (or not at all), the first hit put in front (a ray that touches the
    surface at a silhouette edge or corner before, or without, crossing it)."""
    counts = np.diff(splits)
    has = counts > 0
    starts = splits[:-1]
    first_crossing = np.full(len(counts), np.inf, dtype=np.float32)
    first_crossing[has] = t[starts[has]]
    hit = first_prim >= 0
    same_t = hit & has & (first_t == first_crossing)
    prim = prim.copy()
    prim[starts[same_t]] = first_prim[same_t]
    touch = hit & (first_t < first_crossing)
    if not touch.any():
        return splits, t, prim
    rays = np.flatnonzero(touch)
    at = starts[rays]
    t = np.insert(t, at, first_t[rays])
    prim = np.insert(prim, at, first_prim[rays])
    counts = counts + touch
    splits = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return splits, t, prim
