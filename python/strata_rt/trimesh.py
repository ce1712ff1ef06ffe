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

Conventions kept from trimesh: indices are int64, locations float64,
-1 marks a miss in ``intersects_first``, ``max_hits`` caps the hits of
one ray, and a ray with a zero-length direction, or a NaN or infinite
coordinate, hits nothing (as with trimesh's embreex engine), where
``strata_rt.Mesh`` itself raises naming the bad row; a point that is not
finite is not contained. trimesh is not
imported: any object with ``vertices`` (n, 3) and ``faces`` (m, 3) works.
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

    def _rays(
        self, ray_origins: Any, ray_directions: Any
    ) -> Tuple[np.ndarray, np.ndarray, Optional[np.ndarray]]:
        """float64 origins and directions, and the indices of the rays that
        can hit anything: a finite origin and a finite, non-zero direction
        (``None``: all of them)."""
        origins = np.asarray(ray_origins, dtype=np.float64)
        directions = np.asarray(ray_directions, dtype=np.float64)
        if origins.shape != directions.shape:
            raise ValueError(
                f"ray_origins and ray_directions must have the same shape; "
                f"got {origins.shape} and {directions.shape}"
            )
        if origins.size == 0:
            origins = origins.reshape((0, 3))
            directions = directions.reshape((0, 3))
        if directions.ndim != 2:
            # Mesh's own error names the shape it wants.
            return origins, directions, None
        live = (
            np.any(directions != 0.0, axis=1)
            & np.isfinite(directions).all(axis=1)
            & np.isfinite(origins).all(axis=1)
        )
        if live.all():
            return origins, directions, None
        return origins, directions, np.flatnonzero(live)

    def intersects_id(
        self,
        ray_origins: Any,
        ray_directions: Any,
        multiple_hits: bool = True,
        max_hits: Optional[int] = 100,
        return_locations: bool = False,
    ) -> Union[Tuple[np.ndarray, np.ndarray], Tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """The triangles the rays hit: ``(index_tri, index_ray)``, int64 (h,)
        each, and with ``return_locations`` the hit points, float64 (h, 3).

        ``multiple_hits``: every hit along each ray (at most ``max_hits``,
        ``None`` for no limit), else only the first. Hits are grouped by
        ray, rays in ascending order, each ray's hits nearest first.
        """
        origins, directions, live = self._rays(ray_origins, ray_directions)
        o, d = (origins, directions) if live is None else (origins[live], directions[live])
        if multiple_hits:
            splits, t, prim = self.strata_mesh.all_hits(o, d, threads=self.threads)
            counts = np.diff(splits)
            index_ray = np.repeat(np.arange(len(counts), dtype=np.int64), counts)
            if max_hits is not None:
                rank = np.arange(len(t), dtype=np.int64) - np.repeat(splits[:-1], counts)
                keep = rank < max_hits
                t, prim, index_ray = t[keep], prim[keep], index_ray[keep]
        else:
            hits = self.strata_mesh.intersect(o, d, threads=self.threads)
            index_ray = np.flatnonzero(hits.prim >= 0).astype(np.int64)
            t, prim = hits.t[index_ray], hits.prim[index_ray]
        index_tri = prim.astype(np.int64)
        if live is not None:
            index_ray = live[index_ray].astype(np.int64)
        if not return_locations:
            return index_tri, index_ray
        locations = origins[index_ray] + directions[index_ray] * t.astype(np.float64)[:, None]
        return index_tri, index_ray, locations

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
        origins, directions, live = self._rays(ray_origins, ray_directions)
        if live is None:
            return self.strata_mesh.intersect(origins, directions, threads=self.threads).prim
        first = np.full(len(origins), -1, dtype=np.int64)
        first[live] = self.strata_mesh.intersect(
            origins[live], directions[live], threads=self.threads
        ).prim
        return first

    def intersects_any(self, ray_origins: Any, ray_directions: Any) -> np.ndarray:
        """Whether each ray hits the mesh at all: bool (n,)."""
        origins, directions, live = self._rays(ray_origins, ray_directions)
        if live is None:
            return self.strata_mesh.occluded(origins, directions, threads=self.threads)
        hit = np.zeros(len(origins), dtype=bool)
        hit[live] = self.strata_mesh.occluded(origins[live], directions[live], threads=self.threads)
        return hit

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
