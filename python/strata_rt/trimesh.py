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
ray's hits come together, nearest first (index_ray ascending). Also
different: a ray starting exactly on the surface does not hit it there
(strata's rays cover (0, t_max], so that a ray leaving a surface does not
hit it again; both of trimesh's engines report that face, at t = 0);
and ``contains_points`` follows trimesh's rule (both ways along a ray)
on an open mesh, but asks one ray on a closed one, whose parity is exact
and the same both ways.

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

from typing import Any, Callable, Optional, Tuple, Union

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
        self._closed: Optional[bool] = None
        self._face_bounds: Tuple[np.ndarray, np.ndarray] = (np.zeros(3), np.zeros(3))

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
            self._closed = None
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
        if origins.ndim != 2 or origins.shape[1] != 3:
            # Hits are listed by ray (index_ray): one row per ray, as trimesh has them.
            raise ValueError(f"ray_origins and ray_directions must have shape (n, 3); got {origins.shape}")
        return origins, directions

    def _corners(self, faces: np.ndarray) -> np.ndarray:
        """float64 (k, 3, 3): the corners of ``faces``, as the mesh gives them."""
        return np.asarray(self.mesh.vertices, dtype=np.float64)[np.asarray(self.mesh.faces)[faces]]

    def _locations(
        self, origins: np.ndarray, directions: np.ndarray, index_ray: np.ndarray, index_tri: np.ndarray
    ) -> np.ndarray:
        """Where each ray meets its triangle's plane, in float64 on the
        mesh's own vertices (Cramer's rule, as Möller and Trumbore 1997):
        on the face's plane to float64's precision at any coordinates."""
        tri = self._corners(index_tri)
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
        ray, rays in ascending order, each ray's hits nearest first. A
        crossing through an edge or a vertex that faces share is listed
        once (as ``Mesh.count_hits`` counts it), under
        ``intersects_first``'s face where it is the ray's first; a ray that
        only touches the surface (at a silhouette edge or corner) has its
        first hit listed where its crossings would not list it, so the
        first of a ray's hits is always ``intersects_first``'s.
        """
        origins, directions = self._rays(ray_origins, ray_directions)
        mesh = self.strata_mesh
        first = mesh.intersect(origins, directions, threads=self.threads, bad_rays="miss", fields=("t", "prim"))
        if multiple_hits:
            splits, t, prim = mesh.all_hits(origins, directions, threads=self.threads, bad_rays="miss")
            splits, t, prim = _with_first_hits(
                splits, t, prim, first.t, first.prim, self._corners, origins, directions
            )
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
        """Whether each point is inside the mesh: bool (n,) (or the points'
        leading shape). A point with a NaN or infinite coordinate is not
        contained; a point on the surface may go either way.

        On a closed mesh (each edge shared by an even number of faces)
        one ray's parity of crossings (``Mesh.contains``) is exact, and is
        what trimesh's rule below gives, as both ways along a line through
        a closed surface have the same parity. On an open mesh it follows
        trimesh's ``contains_points``: a point not strictly inside the
        faces' bounding box is outside; else it counts crossings along a
        fixed direction and its opposite, and is inside where both counts
        are odd, outside where both are even or either is 0; where they
        disagree and neither is 0, it asks once more along a second fixed
        direction (trimesh draws a random one) and counts a point whose
        two counts still disagree as outside."""
        points = np.asarray(points, dtype=np.float64)
        if points.ndim == 0 or points.shape[-1] != 3:
            raise ValueError(f"points must have shape (n, 3); got {points.shape}")
        mesh = self.strata_mesh
        flat = points.reshape(-1, 3)
        finite = np.isfinite(flat).all(axis=1)
        inside = np.zeros(len(flat), dtype=bool)
        if self._is_closed():
            if finite.all():
                return mesh.contains(points, threads=self.threads)
            inside[finite] = mesh.contains(flat[finite], threads=self.threads)
        else:
            lo, hi = self._face_bounds
            box = finite & (flat > lo).all(axis=1) & (flat < hi).all(axis=1)
            inside[box] = self._contains_open(mesh, flat[box])
        return inside.reshape(points.shape[:-1])

    def _is_closed(self) -> bool:
        """Whether every edge of the faces (by vertex index) is an edge of
        an even number of them: a closed surface, whose crossings along
        a line have the same parity either way from any point off it.
        Worked out once per mesh (a sort of its edges; ``strata_mesh``
        forgets it when the mesh changes)."""
        if self._closed is None:
            faces = np.asarray(self.mesh.faces, dtype=np.int64).reshape(-1, 3)
            edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
            keys = np.sort(edges[:, 0] * (int(edges.max(initial=0)) + 1) + edges[:, 1])
            # Sorted, every run of equal keys is of even length exactly when
            # there are evenly many and they pair off, 0 with 1, 2 with 3, ...
            self._closed = len(keys) % 2 == 0 and bool((keys[0::2] == keys[1::2]).all())
            if not self._closed:  # so not empty: the box trimesh's rule asks first
                corners = np.asarray(self.mesh.vertices, dtype=np.float64)[faces.reshape(-1)]
                self._face_bounds = (corners.min(axis=0), corners.max(axis=0))
        return self._closed

    def _contains_open(self, mesh: Mesh, points: np.ndarray) -> np.ndarray:
        """trimesh's two-way parity rule (``contains_points``) on points
        inside the faces' bounding box."""
        inside, unsure = self._both_ways(mesh, points, _CONTAINS_DIRECTION)
        if unsure.any():
            again, still = self._both_ways(mesh, points[unsure], _CONTAINS_RETRY)
            inside[unsure] = again & ~still
        return inside

    def _both_ways(self, mesh: Mesh, points: np.ndarray, direction: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """Inside (both crossing counts odd) and unsure (their parities
        disagree and neither is 0), along ``direction`` and its opposite."""
        d = np.broadcast_to(direction, points.shape)
        ahead = mesh.count_hits(points, d, threads=self.threads)
        behind = mesh.count_hits(points, -d, threads=self.threads)
        odd_ahead, odd_behind = ahead % 2 == 1, behind % 2 == 1
        inside = odd_ahead & odd_behind
        unsure = (odd_ahead != odd_behind) & (ahead > 0) & (behind > 0)
        return inside, unsure


#: trimesh's direction for contains_points (trimesh.ray.ray_util): the
#: same first question, so that answers match trimesh's.
_CONTAINS_DIRECTION = np.array([0.4395064455, 0.617598629942, 0.652231566745])
#: The second direction, for points whose two counts disagree: fixed, where
#: trimesh draws a random one, so that the same points get the same answer.
_CONTAINS_RETRY = np.array([-0.5773502692, 0.2113248654, 0.7886751346])


#: How far apart, relative to the ray's reach (below), two hits on faces
#: that share a corner may lie along the ray and still be one point of the
#: surface: 2**-16, 128 float32 steps (2**-23). Two faces' t at the same
#: point differ by the rounding of strata's float32 arithmetic on each
#: face's corners relative to the origin, a step or two of the reach (2 at
#: most on rays through every vertex and edge of icospheres); grazing
#: angles magnify it, hence the margin. A touch and a crossing on
#: neighbouring faces this close (1.5e-5 of the reach) list as one hit.
_TIE = 2.0**-16


def _with_first_hits(
    splits: np.ndarray,
    t: np.ndarray,
    prim: np.ndarray,
    first_t: np.ndarray,
    first_prim: np.ndarray,
    corners: Callable[[np.ndarray], np.ndarray],
    origins: np.ndarray,
    directions: np.ndarray,
) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every ray's crossings (``Mesh.all_hits``), led by its first hit
    (``Mesh.intersect``), each crossing listed once.

    At a crossing through an edge or a vertex that several faces share,
    ``intersect`` accepts every one of them and keeps the least t, while
    ``all_hits`` lists the one face that owns the crossing (so that it is
    counted once); each computes t on its own face's corners, so the two
    t may differ by a float32 step or two, either way. The first hit is
    the first crossing, relabelled with the first hit's face, where
    - it names the same face, or
    - its t is not below the crossing's (``intersect`` would have kept
      the crossing's face had it been nearer: only rounding puts it
      beyond), or
    - its face shares a corner with the crossing's (the only faces that
      can meet the ray at one point of an edge or vertex) and the two t
      are within ``_TIE`` of the ray's reach: the largest distance, in
      direction lengths, from the origin to the two faces' corners, the
      scale of the rounding of t on them.
    Any other first hit is a touch of the surface (a silhouette edge or
    corner, which crosses nothing) before the crossings, or without any,
    and is put in front of them, so that ``intersects_first`` always
    names the first of a ray's hits."""
    counts = np.diff(splits)
    has = counts > 0
    starts = splits[:-1]
    cross_t = np.full(len(counts), np.inf, dtype=np.float32)
    cross_t[has] = t[starts[has]]
    cross_prim = np.full(len(counts), -1, dtype=np.int64)
    cross_prim[has] = prim[starts[has]]
    hit = first_prim >= 0
    same = hit & has & ((first_prim == cross_prim) | (first_t >= cross_t))
    rays = np.flatnonzero(hit & has & ~same)
    if len(rays):
        a, b = corners(first_prim[rays]), corners(cross_prim[rays])
        share = (a[:, :, None, :] == b[:, None, :, :]).all(axis=-1).any(axis=(1, 2))
        o = origins[rays].astype(np.float64)[:, None, :]
        length = np.linalg.norm(directions[rays].astype(np.float64), axis=1)
        reach = np.linalg.norm(np.concatenate([a, b], axis=1) - o, axis=2).max(axis=1) / length
        gap = cross_t[rays].astype(np.float64) - first_t[rays].astype(np.float64)
        same[rays] = share & (gap <= _TIE * reach)
    prim = prim.copy()
    relabel = same & (first_prim != cross_prim)
    if relabel.any():
        # Where the ray only touches an edge or a vertex, all_hits may list
        # two faces there (a touch crosses twice or not at all), the first
        # hit's face second: the two swap, so that no face is listed twice.
        owner = np.repeat(np.arange(len(counts)), counts)
        later = np.ones(len(prim), dtype=bool)
        later[starts[has]] = False
        match = np.flatnonzero(later & relabel[owner] & (prim == first_prim[owner]))
        match = match[np.unique(owner[match], return_index=True)[1]]  # the first match of each ray
        prim[match] = cross_prim[owner[match]]
        prim[starts[relabel]] = first_prim[relabel]
    touch = hit & ~same
    if not touch.any():
        return splits, t, prim
    rays = np.flatnonzero(touch)
    at = starts[rays]
    t = np.insert(t, at, first_t[rays])
    prim = np.insert(prim, at, first_prim[rays])
    counts = counts + touch
    splits = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return splits, t, prim
