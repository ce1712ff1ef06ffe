"""strata_rt: strata's ray queries and renders, numpy in and numpy out.

strata is a CPU ray tracer with a watertight ray-triangle test: a ray
through a shared edge or vertex of a closed mesh crosses it once, never
zero times and never twice. This package builds a mesh's BVH once and
answers queries on whole arrays of rays or points, with the GIL released,
on every core::

    import numpy as np
    import strata_rt

    mesh = strata_rt.Mesh(vertices, faces)        # or strata_rt.Mesh.load("bunny.obj")
    hits = mesh.intersect(origins, directions)    # hits.t, .prim, .u, .v, .normal, .point
    blocked = mesh.occluded(origins, directions, t_max=1.0)
    splits, t, prim = mesh.all_hits(origins, directions)   # or .splits, .t, .prim, .ray
    counts = mesh.count_hits(origins, directions)
    inside = mesh.contains(points)
    near = mesh.closest_point(points, signed=True)
    placed = mesh.place(transforms)               # stored once, placed n times: instances

    image = strata_rt.render("scenes/seed.toml", spp=16)   # float32 (height, width, 3)

``strata_rt.trimesh.RayMeshIntersector`` puts the same engine behind
trimesh's ray interface (``mesh.ray = RayMeshIntersector(mesh)``), and
``strata_rt.open3d.RaycastingScene`` behind Open3D's.
"""

try:
    from ._native import ClosestPoints, Crossings, Hits, InputError, Mesh, __version__, render
except ImportError as e:  # pragma: no cover - depends on how Python was started
    import os as _os

    _here = _os.path.dirname(_os.path.abspath(__file__))
    raise ImportError(
        f"strata_rt was imported from its source folder ({_here}), which has no compiled "
        "module: start Python outside python/ to use the package `pip install ./python` "
        "installed, or build it in place with `maturin develop --release`"
    ) from e

__all__ = ["ClosestPoints", "Crossings", "Hits", "InputError", "Mesh", "__version__", "render"]
