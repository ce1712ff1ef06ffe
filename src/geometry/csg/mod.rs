//! Constructive solid geometry: union, intersection and difference of
//! closed solids, by ray classification (Roth 1982, "Ray Casting for
//! Modeling Solids", Computer Graphics and Image Processing 18(2)).
//!
//! ```toml
//! [[objects]]                  # a biconvex lens: the overlap of two spheres
//! material = "glass"           # optional: overrides every operand's material
//! [objects.csg]
//! op = "intersection"          # "union" | "intersection" | "difference" (a minus b)
//! a = { sphere = { center = [0.0, 0.0, -0.75], radius = 1.0 } }
//! b = { sphere = { center = [0.0, 0.0, 0.75], radius = 1.0 } }
//!
//! [[objects]]                  # a die: a cube (a closed OBJ) minus a group of spheres
//! csg = { op = "difference", a = { mesh = "meshes/cube.obj" }, b = { group = [ { sphere = { center = [0.0, 0.0, 1.1], radius = 0.2 } } ] } }
//! ```
//!
//! Operands are spheres, capped cylinders, closed triangle meshes, groups
//! (the union of their members) and other CSG nodes, each with its own
//! `transform` and `material`. For each ray every operand reports where the
//! whole line is inside it, as sorted half-open spans (see [`interval`]);
//! the spans are combined up the tree by the operators, and the first
//! boundary after `tmin` is the hit. Classifying the whole line, not just
//! the part after `tmin`, is what makes rays that start inside a solid (a
//! refraction or shadow ray) see the right surface.
//!
//! - Normals point out of the result: a surface of a subtracted operand has
//!   its normal flipped ([`interval::FLIP`]).
//! - Each surface keeps its operand's material unless the CSG object names one.
//! - The whole tree is one BVH primitive whose box is the intersection of
//!   the operands' boxes for `intersection`, `a`'s box for `difference` and
//!   the union for `union`. Each node's box also culls its subtree per ray.
//!
//! Leaves carry their full object-to-world transform (the scene compiler
//! folds the transforms of the enclosing nodes into them), so evaluation
//! moves the ray once per leaf and t is the world t everywhere.

pub mod interval;
pub mod mesh;

use crate::accel::PrimHit;
use crate::accel::{BuildQuality, Bvh8};
use crate::math::offset::{barycentric_error, gamma, transformed_error};
use crate::math::{Aabb, Ray, Transform};
use crate::shape::cylinder::Cylinder;
use crate::shape::sphere::Sphere;
use glam::Vec3;
pub use interval::CsgOp;
use interval::{combine, push_span, Boundary, Span, FLIP};
use std::cell::RefCell;

/// Meshes with more triangles than this get their own BVH.
const MESH_BVH_THRESHOLD: usize = 32;

/// A closed triangle mesh operand: a range of [`Csg::triangles`], already in
/// world space, with its own BVH when it is large.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosedMesh {
    pub first: u32,
    pub count: u32,
    /// Index into [`Csg::mesh_bvhs`].
    pub bvh: Option<u32>,
}

/// The solid of a leaf, in the leaf's object space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Solid {
    Sphere(Sphere),
    /// Always capped: an open cylinder bounds no solid.
    Cylinder(Cylinder),
    Mesh(ClosedMesh),
}

impl Solid {
    /// How many part ids the solid's surfaces use.
    fn parts(&self) -> u32 {
        match self {
            Solid::Sphere(_) => 1,
            Solid::Cylinder(_) => 3,
            Solid::Mesh(m) => m.count,
        }
    }
}

/// An operand that is not itself an operation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leaf {
    pub solid: Solid,
    /// Object to world; `None` for world-space solids.
    pub transform: Option<Transform>,
    /// The material of its surfaces (meshes: see [`Csg::triangle_materials`]).
    pub material: u32,
    /// Its surfaces are parts `first_part .. first_part + parts`.
    pub first_part: u32,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NodeKind {
    Leaf(u32),
    Op { op: CsgOp, a: u32, b: u32 },
}

/// A node of a CSG tree with its world-space bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CsgNode {
    pub kind: NodeKind,
    /// Conservative: padded a little beyond the solid, or empty if the
    /// solid is provably empty.
    pub bounds: Aabb,
}

/// Every CSG tree of a scene in flat arrays. A tree is named by its root
/// node; nodes refer to their operands by index.
#[derive(Debug, Clone, Default)]
pub struct Csg {
    pub nodes: Vec<CsgNode>,
    pub leaves: Vec<Leaf>,
    /// Triangles of mesh operands in world space; not BVH primitives of the scene.
    pub triangles: Vec<[Vec3; 3]>,
    pub triangle_materials: Vec<u32>,
    pub mesh_bvhs: Vec<Bvh8>,
}

/// A surface of a CSG tree: which leaf, which of its parts, and whether
/// the normal is flipped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PartRef {
    pub leaf: u32,
    pub part: u32,
    pub flip: bool,
}

/// Per-thread scratch space, so evaluating a tree allocates nothing once warm.
#[derive(Default)]
struct Scratch {
    /// A stack of span lists: each node appends its result here.
    spans: Vec<Span>,
    combined: Vec<Span>,
    crossings: Vec<(u32, mesh::TriCrossing)>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Pad a box by a relative hair so that rounding in the slab test never
/// culls a surface the operand's own test would find.
fn padded(b: Aabb) -> Aabb {
    if b.is_empty() {
        return Aabb::EMPTY;
    }
    let pad = gamma(16) * (b.min.abs().max(b.max.abs())) + 1e-4 * b.diagonal();
    Aabb::new(b.min - pad, b.max + pad)
}

/// Whether the line through `ray` may meet `b` for t in `[tmin, tmax]`.
fn line_meets_box(b: &Aabb, ray: &Ray) -> bool {
    if b.is_empty() {
        return false;
    }
    let (mut near, mut far) = (ray.tmin, ray.tmax);
    for axis in 0..3 {
        let (o, d) = (ray.origin[axis], ray.direction[axis]);
        if d == 0.0 {
            if o < b.min[axis] || o > b.max[axis] {
                return false;
            }
            continue;
        }
        let (t0, t1) = ((b.min[axis] - o) / d, (b.max[axis] - o) / d);
        near = near.max(t0.min(t1));
        far = far.min(t0.max(t1));
    }
    near - far <= gamma(3) * (near.abs() + far.abs())
}

impl Csg {
    /// Add a sphere leaf; returns its node.
    pub fn push_sphere(&mut self, s: Sphere, transform: Option<Transform>, material: u32) -> u32 {
        self.push_analytic(Solid::Sphere(s), s.bounds(), transform, material)
    }

    /// Add a capped cylinder leaf; returns its node.
    pub fn push_cylinder(
        &mut self,
        c: Cylinder,
        transform: Option<Transform>,
        material: u32,
    ) -> u32 {
        debug_assert!(c.caps, "an open cylinder bounds no solid");
        self.push_analytic(Solid::Cylinder(c), c.bounds(), transform, material)
    }

    fn push_analytic(
        &mut self,
        solid: Solid,
        local: Aabb,
        transform: Option<Transform>,
        material: u32,
    ) -> u32 {
        let bounds = match &transform {
            Some(t) => Aabb::from_points(&local.corners().map(|c| t.point(c))),
            None => local,
        };
        self.push_leaf(solid, transform, material, bounds)
    }

    /// Add a closed mesh leaf from world-space triangles, one material
    /// each; returns its node. The caller has checked it is closed.
    pub fn push_mesh(&mut self, tris: Vec<[Vec3; 3]>, materials: Vec<u32>) -> u32 {
        debug_assert_eq!(tris.len(), materials.len());
        let bounds = tris
            .iter()
            .fold(Aabb::EMPTY, |b, t| b.union(Aabb::from_points(t)));
        let bvh = (tris.len() > MESH_BVH_THRESHOLD).then(|| {
            let boxes: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
            self.mesh_bvhs
                .push(Bvh8::build(&boxes, BuildQuality::Medium));
            self.mesh_bvhs.len() as u32 - 1
        });
        let solid = Solid::Mesh(ClosedMesh {
            first: self.triangles.len() as u32,
            count: tris.len() as u32,
            bvh,
        });
        self.triangles.extend(tris);
        self.triangle_materials.extend(materials);
        self.push_leaf(solid, None, 0, bounds)
    }

    fn push_leaf(
        &mut self,
        solid: Solid,
        transform: Option<Transform>,
        material: u32,
        bounds: Aabb,
    ) -> u32 {
        let first_part = self
            .leaves
            .last()
            .map_or(0, |l| l.first_part + l.solid.parts());
        self.leaves.push(Leaf {
            solid,
            transform,
            material,
            first_part,
        });
        self.push_node(NodeKind::Leaf(self.leaves.len() as u32 - 1), padded(bounds))
    }

    /// Add `a op b`; returns its node.
    pub fn push_op(&mut self, op: CsgOp, a: u32, b: u32) -> u32 {
        let (ba, bb) = (self.nodes[a as usize].bounds, self.nodes[b as usize].bounds);
        let bounds = match op {
            CsgOp::Union => ba.union(bb),
            CsgOp::Intersection => ba.intersection(bb),
            CsgOp::Difference => ba,
        };
        let bounds = if bounds.is_empty() {
            Aabb::EMPTY
        } else {
            bounds
        };
        self.push_node(NodeKind::Op { op, a, b }, bounds)
    }

    fn push_node(&mut self, kind: NodeKind, bounds: Aabb) -> u32 {
        self.nodes.push(CsgNode { kind, bounds });
        self.nodes.len() as u32 - 1
    }

    /// How many part ids all leaves use; must stay below 2³¹.
    pub fn part_count(&self) -> u64 {
        self.leaves
            .last()
            .map_or(0, |l| l.first_part as u64 + l.solid.parts() as u64)
    }

    pub fn bounds(&self, root: u32) -> Aabb {
        self.nodes[root as usize].bounds
    }

    /// Which leaf, part and flip a hit's `part` code names.
    pub fn decode(&self, code: u32) -> PartRef {
        let id = code & !FLIP;
        let leaf = self
            .leaves
            .partition_point(|l| l.first_part + l.solid.parts() <= id);
        PartRef {
            leaf: leaf as u32,
            part: id - self.leaves[leaf].first_part,
            flip: code & FLIP != 0,
        }
    }

    /// The first boundary of tree `root` in `(ray.tmin, ray.tmax)`. The hit's
    /// `part` is a code for [`Csg::decode`]; `u`, `v` are barycentrics for
    /// mesh triangles. `prim` is left 0 for the caller to fill in.
    pub fn intersect(&self, root: u32, ray: &Ray) -> Option<PrimHit> {
        SCRATCH.with(|scratch| {
            let s = &mut *scratch.borrow_mut();
            s.spans.clear();
            self.spans(root, ray, s);
            let first = s
                .spans
                .iter()
                .find_map(|span| [span.start, span.end].into_iter().find(|b| b.t > ray.tmin))?;
            (first.t < ray.tmax).then_some(PrimHit {
                t: first.t,
                prim: 0,
                u: first.u,
                v: first.v,
                part: first.code,
            })
        })
    }

    /// Append node's spans that reach into `(tmin, tmax)` to `s.spans`.
    /// Spans wholly outside that range cannot change a boundary inside it
    /// (every boundary of the result is a boundary of an operand, and
    /// membership inside the range depends only on spans that reach it),
    /// so leaves drop them early.
    fn spans(&self, node: u32, ray: &Ray, s: &mut Scratch) {
        let n = &self.nodes[node as usize];
        if !line_meets_box(&n.bounds, ray) {
            return;
        }
        match n.kind {
            NodeKind::Leaf(leaf) => self.leaf_spans(leaf, ray, s),
            NodeKind::Op { op, a, b } => {
                let start = s.spans.len();
                self.spans(a, ray, s);
                let mid = s.spans.len();
                if mid == start && op != CsgOp::Union {
                    // ∅ ∩ b = ∅ − b = ∅.
                    return;
                }
                self.spans(b, ray, s);
                let end = s.spans.len();
                if end == mid && op != CsgOp::Intersection {
                    // a ∪ ∅ = a − ∅ = a, already in place.
                    return;
                }
                if mid == start {
                    // ∅ ∪ b = b, already in place.
                    return;
                }
                s.combined.clear();
                combine(
                    op,
                    &s.spans[start..mid],
                    &s.spans[mid..end],
                    &mut s.combined,
                );
                s.spans.truncate(start);
                s.spans.extend_from_slice(&s.combined);
            }
        }
    }

    fn leaf_spans(&self, index: u32, ray: &Ray, s: &mut Scratch) {
        let leaf = &self.leaves[index as usize];
        let local = leaf_ray(leaf, ray);
        let keep = |a: f32, b: f32| b > ray.tmin && a < ray.tmax;
        let from = s.spans.len();
        match leaf.solid {
            Solid::Sphere(sphere) => {
                if let Some((t0, t1)) = sphere.roots(&local) {
                    if keep(t0, t1) {
                        let b = |t| Boundary::new(t, leaf.first_part);
                        push_span(&mut s.spans, from, b(t0), b(t1));
                    }
                }
            }
            Solid::Cylinder(cylinder) => {
                if let Some(((t0, p0), (t1, p1))) = cylinder.solid_span(&local) {
                    if keep(t0, t1) {
                        let b0 = Boundary::new(t0, leaf.first_part + p0);
                        let b1 = Boundary::new(t1, leaf.first_part + p1);
                        push_span(&mut s.spans, from, b0, b1);
                    }
                }
            }
            Solid::Mesh(m) => {
                let tris = &self.triangles[m.first as usize..(m.first + m.count) as usize];
                let bvh = m.bvh.map(|i| &self.mesh_bvhs[i as usize]);
                s.crossings.clear();
                mesh::crossings(tris, bvh, &local, &mut s.crossings);
                if !s.crossings.len().is_multiple_of(2) {
                    // A crossing was lost or doubled (a line in the plane of
                    // a face can do that): parity is unknown, so the mesh
                    // sits this ray out rather than turn the line inside out.
                    return;
                }
                s.crossings.sort_unstable_by(|a, b| a.1.t.total_cmp(&b.1.t));
                for pair in s.crossings.chunks_exact(2) {
                    if !keep(pair[0].1.t, pair[1].1.t) {
                        continue;
                    }
                    // Entering, the outward normal faces the ray; leaving, it
                    // faces away. Flip the winding normal where it disagrees.
                    let boundary = |(i, c): (u32, mesh::TriCrossing), entering: bool| Boundary {
                        t: c.t,
                        code: (leaf.first_part + i) | if entering != c.toward { FLIP } else { 0 },
                        u: c.u,
                        v: c.v,
                    };
                    push_span(
                        &mut s.spans,
                        from,
                        boundary(pair[0], true),
                        boundary(pair[1], false),
                    );
                }
            }
        }
    }

    /// World-space point, error bound, outward unit normal of the result
    /// solid, and material at a hit that [`Csg::intersect`] reported.
    pub fn surface_at(&self, ray: &Ray, hit: &PrimHit) -> (Vec3, Vec3, Vec3, u32) {
        let r = self.decode(hit.part);
        let leaf = &self.leaves[r.leaf as usize];
        let local = leaf_ray(leaf, ray);
        let (p, err, n, material) = match leaf.solid {
            Solid::Sphere(sphere) => {
                let (p, e, n) = sphere.surface_at(local.at(hit.t));
                (p, e, n, leaf.material)
            }
            Solid::Cylinder(cylinder) => {
                let (p, e, n) = cylinder.surface_at(local.at(hit.t), r.part);
                (p, e, n, leaf.material)
            }
            Solid::Mesh(m) => {
                let i = (m.first + r.part) as usize;
                let v = self.triangles[i];
                let b = [1.0 - hit.u - hit.v, hit.u, hit.v];
                let p = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
                let n = crate::shape::triangle::unit_normal(&v).unwrap_or(Vec3::Z);
                (p, barycentric_error(b, v), n, self.triangle_materials[i])
            }
        };
        let (p, err, n) = match &leaf.transform {
            None => (p, err, n),
            Some(t) => (
                t.point(p),
                transformed_error(&t.to_world, p, err),
                t.normal(n),
            ),
        };
        (p, err, if r.flip { -n } else { n }, material)
    }
}

/// The ray in a leaf's object space; the direction is not renormalised, so
/// t is still the world t.
#[inline]
fn leaf_ray(leaf: &Leaf, ray: &Ray) -> Ray {
    match &leaf.transform {
        None => *ray,
        Some(t) => Ray {
            origin: t.to_object.transform_point3(ray.origin),
            direction: t.to_object.transform_vector3(ray.direction),
            tmin: ray.tmin,
            tmax: ray.tmax,
        },
    }
}
