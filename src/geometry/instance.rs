//! Instances: a mesh stored once, in its own object space under its own
//! tree (a *prototype*, itself a [`Geometry`] of triangles only), placed
//! any number of times by an affine map each. The scene's tree holds one
//! primitive per instance; a ray that reaches one enters the prototype's
//! tree in object space, as Embree's instances, pbrt-v4's
//! `ObjectInstance` and Mitsuba 3's `instance` of a `shapegroup` do.
//!
//! The object-space ray keeps its unnormalised direction, so its t is the
//! world t and hits compare across instances and world triangles as they
//! are. A hit's point is interpolated from the prototype's vertices and
//! moved to world space with its error bound (pbrt-v4 section 6.8.6), to
//! which [`Instance::surface`] adds what moving the spawned ray's origin
//! back into object space may cost, so that a ray leaving an instanced
//! surface starts on its side in object space too (no acne, no leaks).

use super::{Found, Geometry, GeometryParts, Surface};
use crate::accel::{BuildQuality, Bvh8, PrimHit};
use crate::math::offset::{gamma, transformed_error};
use crate::math::{Aabb, Ray, Transform};
use glam::{Affine3A, Mat3, Vec3};

/// No material of its own: an instance takes its mesh's materials.
pub const NO_MATERIAL: u32 = u32::MAX;

/// One placement of a prototype: 84 bytes (its world-to-object map, its
/// world box, three indices). The object-to-world map, which only a hit's
/// surface and the build need, is the f64 inverse of the world-to-object
/// one ([`Instance::affine`]), so it is not stored: 48 bytes less each.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Instance {
    /// The prototype's box in world space ([`Instance::bounds`]), which a
    /// ray must meet before it is moved into object space: a leaf of the
    /// scene's tree may hold eight instances, a ray rarely meets them all.
    pub world_bounds: Aabb,
    /// World to object: the linear part and the translation.
    pub to_object: Mat3,
    pub to_object_translation: Vec3,
    /// Index into [`Geometry::prototypes`].
    pub prototype: u32,
    /// The object's own `material`, which replaces all of its mesh's, or
    /// [`NO_MATERIAL`].
    pub material: u32,
    /// The material of the mesh's triangles that have none of their own
    /// (the one the object inherits from its group).
    pub inherited: u32,
}

impl Instance {
    /// The material this placement shows where its prototype's mesh
    /// has `mesh_material` ([`NO_MATERIAL`]: none): its own, else the
    /// mesh's, else the inherited one.
    pub fn material_of(&self, mesh_material: u32) -> u32 {
        if self.material != NO_MATERIAL {
            self.material
        } else if mesh_material != NO_MATERIAL {
            mesh_material
        } else {
            self.inherited
        }
    }

    /// `None` where `to_world` is singular or not finite (as
    /// [`Transform::new`] decides: the inverse is computed in f64, so it
    /// is the correctly rounded inverse of the f32 map).
    pub fn new(to_world: Affine3A, prototype: u32, material: u32, inherited: u32) -> Option<Self> {
        let t = Transform::new(to_world)?;
        Some(Self {
            world_bounds: Aabb::EMPTY,
            to_object: Mat3::from(t.to_object.matrix3),
            to_object_translation: t.to_object.translation.into(),
            prototype,
            material,
            inherited,
        })
    }

    /// The object-to-world map: the world-to-object map inverted in f64
    /// and rounded, the map the rays walked in object space see, within
    /// the f32 rounding of the placement the scene gave.
    pub fn affine(&self) -> Affine3A {
        let to_object = Affine3A::from_mat3_translation(self.to_object, self.to_object_translation);
        Transform::new(to_object)
            .expect("the inverse of an invertible map is invertible")
            .to_object
    }

    /// The object-to-world map in f64 (the exact inverse of the
    /// world-to-object map, as far as f64 goes), for checks.
    pub fn affine_f64(&self) -> glam::DAffine3 {
        glam::DAffine3::from_mat3_translation(
            self.to_object.as_dmat3(),
            self.to_object_translation.as_dvec3(),
        )
        .inverse()
    }

    /// Whether `ray` may meet the instance's world box, and true where it
    /// cannot tell (NaN): a culled hit would be a leak. The interval is
    /// widened by 1e-5 of its ends, far past the walks' 2γ(3) (Ize 2013):
    /// moving the ray into object space rounds its origin by about
    /// γ(3)·|M⁻¹|·|origin|, which a map with a condition number in the
    /// tens turns into more than 2γ(3) of the distance in world space.
    #[inline(always)]
    pub fn may_hit(&self, ray: &Ray) -> bool {
        const WIDEN: f32 = 1e-5;
        let inv = ray.direction.recip();
        let t0 = (self.world_bounds.min - ray.origin) * inv;
        let t1 = (self.world_bounds.max - ray.origin) * inv;
        let near = t0.min(t1).max_element().max(ray.tmin);
        let far = t0.max(t1).min_element().min(ray.tmax);
        !(near - WIDEN * near.abs() > far + WIDEN * far.abs())
    }

    /// `ray` in the prototype's object space, its direction not
    /// renormalised so that its t is the world t.
    #[inline(always)]
    pub fn object_ray(&self, ray: &Ray) -> Ray {
        Ray {
            origin: self.to_object * ray.origin + self.to_object_translation,
            direction: self.to_object * ray.direction,
            tmin: ray.tmin,
            tmax: ray.tmax,
        }
    }

    /// The world-space box of `prototype` under this placement: the
    /// prototype root's child boxes moved and joined (tighter than its
    /// whole box's corners under a rotation), each grown by the rounding
    /// of moving its corners.
    pub fn bounds(&self, prototype: &Geometry) -> Aabb {
        let m = self.affine();
        // Each corner moved, its rounding (pbrt-v4 6.8.6) added around it.
        let moved = |b: Aabb| {
            b.corners().iter().fold(Aabb::EMPTY, |out, &c| {
                let (w, e) = (m.transform_point3(c), transformed_error(&m, c, Vec3::ZERO));
                out.grow(w - e).grow(w + e)
            })
        };
        prototype
            .bvh
            .root_boxes()
            .fold(Aabb::EMPTY, |out, child| out.union(moved(child)))
    }

    /// The world-space surface of a hit on this instance: `hit.part` is
    /// the prototype's leaf slot, as a world triangle's is the scene's.
    pub fn surface(&self, prototype: &Geometry, ray: &Ray, hit: &PrimHit) -> Surface {
        let inner = PrimHit {
            prim: prototype.slot_prim(hit.part),
            ..*hit
        };
        let local = prototype.surface(&self.object_ray(ray), &inner);
        let m = self.affine();
        let p = m.transform_point3(local.p);
        // Moving the point to world space rounds it (pbrt-v4 6.8.6); a ray
        // spawned from it is moved back with `to_object`, which rounds
        // again by up to γ(4)(|M⁻¹||p| + |t⁻¹|) in object space (three
        // operations, and the f32 inverse's own half ulp). That error,
        // moved to world space with |M|, joins the bound, so an offset
        // along the normal past it is past it in object space too.
        let abs = |a: Mat3| Mat3::from_cols(a.x_axis.abs(), a.y_axis.abs(), a.z_axis.abs());
        let back = gamma(4) * (abs(self.to_object) * p.abs() + self.to_object_translation.abs());
        let p_error =
            transformed_error(&m, local.p, local.p_error) + abs(Mat3::from(m.matrix3)) * back;
        let normal_to_world = self.to_object.transpose();
        let ng = (normal_to_world * local.geometric_normal).normalize_or(Vec3::Z);
        let ns = (normal_to_world * local.shading_normal).normalize_or(ng);
        let material = self.material_of(local.material);
        Surface {
            p,
            p_error,
            geometric_normal: ng,
            shading_normal: ns,
            material,
            uv: local.uv,
        }
    }
}

/// A scene of `prototype` (a mesh's geometry, triangles only) placed once
/// by each of `placements`, as the scene file's `instances =` places a
/// mesh: instance `k` is primitive `k`. `Err(k)` names the first map that
/// is singular or not finite, or that carries the mesh past f32's range.
pub fn placed(
    prototype: Geometry,
    placements: &[Affine3A],
    quality: BuildQuality,
) -> Result<Geometry, usize> {
    let mut instances = Vec::with_capacity(placements.len());
    let mut boxes = Vec::with_capacity(placements.len());
    for (k, &m) in placements.iter().enumerate() {
        let mut instance = Instance::new(m, 0, NO_MATERIAL, 0).ok_or(k)?;
        instance.world_bounds = instance.bounds(&prototype);
        if !instance.world_bounds.is_finite() && prototype.triangle_count > 0 {
            return Err(k);
        }
        boxes.push(instance.world_bounds);
        instances.push(instance);
    }
    if prototype.triangle_count == 0 {
        instances.clear();
        boxes.clear();
    }
    let bvh = Bvh8::build_from_with_others(boxes, quality, 0);
    let parts = GeometryParts {
        instances,
        prototypes: vec![prototype],
        ..GeometryParts::default()
    };
    // No triangle of its own: every slot holds an instance.
    Ok(Geometry::new(parts, bvh, |_| [Vec3::NAN; 3]))
}

impl Geometry {
    /// The first primitive id of an instance: they follow the triangles
    /// and the analytic shapes.
    #[inline(always)]
    pub fn first_instance(&self) -> u32 {
        self.triangle_count + self.shapes.len() as u32
    }

    /// The instance a primitive id names, with its prototype.
    #[inline(always)]
    pub fn instance(&self, prim: u32) -> (&Instance, &Geometry) {
        let instance = &self.instances[(prim - self.first_instance()) as usize];
        (instance, &self.prototypes[instance.prototype as usize])
    }

    /// The closest hit of `ray` on instance primitive `id`: the walk of
    /// its prototype's tree in object space, reported as the instance
    /// (`prim`), with the prototype's leaf slot in `part`.
    #[inline]
    pub(crate) fn hit_instance(&self, id: u32, ray: &Ray) -> Option<PrimHit> {
        let (instance, prototype) = self.instance(id);
        if !instance.may_hit(ray) {
            return None;
        }
        let hit = prototype.intersect_open_end(&instance.object_ray(ray))?;
        Some(PrimHit { prim: id, ..hit })
    }

    /// Whether anything of instance primitive `id` blocks `ray`.
    #[inline]
    pub(crate) fn instance_blocks(&self, id: u32, ray: &Ray) -> bool {
        let (instance, prototype) = self.instance(id);
        instance.may_hit(ray) && prototype.occluded_open_end(&instance.object_ray(ray))
    }

    /// The closest hit on a primitive that is not a world triangle.
    #[inline]
    pub(crate) fn hit_other(&self, id: u32, ray: &Ray) -> Option<PrimHit> {
        if id < self.first_instance() {
            self.hit_analytic(id, ray)
        } else {
            self.hit_instance(id, ray)
        }
    }

    /// Whether a primitive that is not a world triangle blocks `ray`.
    #[inline]
    pub(crate) fn other_blocks(&self, id: u32, ray: &Ray) -> bool {
        if id < self.first_instance() {
            self.hit_analytic(id, ray).is_some()
        } else {
            self.instance_blocks(id, ray)
        }
    }

    /// Triangles stored: the scene's own and each prototype's once.
    pub fn unique_triangles(&self) -> u64 {
        u64::from(self.triangle_count)
            + self
                .prototypes
                .iter()
                .map(|p| u64::from(p.triangle_count))
                .sum::<u64>()
    }

    /// Bytes the instances cost: their records and their share of the
    /// scene's tree (its nodes and leaf slots, by primitive count).
    pub fn instance_bytes(&self) -> usize {
        let share = self.traversal_bytes() as f64 * self.instances.len() as f64
            / self.primitive_count().max(1) as f64;
        std::mem::size_of_val(self.instances.as_slice()) + share as usize
    }

    /// Triangles the instances place, counted once per instance.
    pub fn instanced_triangles(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| u64::from(self.prototypes[i.prototype as usize].triangle_count))
            .sum()
    }

    /// Where each instance's triangles start among the ids of
    /// [`Geometry::flat_prim`]: one entry per instance, and the total.
    pub fn flat_offsets(&self) -> Vec<u64> {
        let mut next = u64::from(self.first_instance());
        let mut out = Vec::with_capacity(self.instances.len() + 1);
        out.push(next);
        for i in &self.instances {
            next += u64::from(self.prototypes[i.prototype as usize].triangle_count);
            out.push(next);
        }
        out
    }

    /// A triangle's primitive id as if every instance were a copy in world
    /// space: the scene's own primitives keep theirs, and instance `k`'s
    /// triangle `j` is `offsets[k] + j` ([`Geometry::flat_offsets`]), after
    /// the triangles of the instances before it. What `strata trace`
    /// writes, and what Embree's instances of one mesh of T triangles give
    /// as `instID · T + primID`. Inlined: a few instructions a hit, which
    /// a binding's column writer calls for every ray.
    #[inline]
    pub fn flat_prim(&self, found: &impl Found, offsets: &[u64]) -> u64 {
        match self.placed_in(found) {
            Some(k) => offsets[k] + u64::from(self.inner_prim(found)),
            None => u64::from(found.prim()),
        }
    }

    /// The instance `found` lies on (its index), or `None` for anything
    /// of the scene's own (a plane too).
    #[inline(always)]
    fn placed_in(&self, found: &impl Found) -> Option<usize> {
        let prim = found.prim();
        let own = prim < self.first_instance() || self.plane_index(prim).is_some();
        (!own).then(|| (prim - self.first_instance()) as usize)
    }

    /// The triangle's id in the tree that stores it: its prototype's
    /// triangle id for an instance's, the primitive itself otherwise.
    #[inline]
    pub fn inner_prim(&self, found: &impl Found) -> u32 {
        match self.placed_in(found) {
            Some(k) => {
                let prototype = &self.prototypes[self.instances[k].prototype as usize];
                prototype.slot_prim(Geometry::slot_of(found))
            }
            None => found.prim(),
        }
    }

    /// The vertices of a triangle found, where it is stored: a world
    /// triangle's in world space, an instance's in its prototype's space.
    pub fn object_triangle(&self, found: &impl Found) -> [Vec3; 3] {
        match self.placed_in(found) {
            Some(k) => {
                let prototype = &self.prototypes[self.instances[k].prototype as usize];
                prototype.slot_triangle(Geometry::slot_of(found))
            }
            None => self.triangle(found),
        }
    }

    /// Asks the CPU to fetch the leaf block holding the triangle `found`
    /// lies on (what [`Geometry::world_triangle`] reads), without waiting:
    /// a caller about to read the triangles of many hits, each likely a
    /// miss of every cache on a large mesh, issues every fetch first and
    /// waits once.
    #[inline(always)]
    pub fn prefetch_triangle(&self, found: &impl Found) {
        let tree = match self.placed_in(found) {
            Some(k) => &self.prototypes[self.instances[k].prototype as usize],
            None => self,
        };
        let slot = Geometry::slot_of(found) as usize;
        if let Some(block) = tree.leaf_blocks.get(slot / crate::math::lanes::LANES) {
            crate::accel::prefetch::prefetch(block);
        }
    }

    /// The vertices of a triangle found, in world space: an instance's
    /// moved by its map ([`Instance::affine`]'s `transform_point3`, vertex by
    /// vertex), as a mesh of the copies would hold them.
    pub fn world_triangle(&self, found: &impl Found) -> [Vec3; 3] {
        let own = self.object_triangle(found);
        match self.placed_in(found) {
            Some(k) => {
                let m = self.instances[k].affine();
                own.map(|p| m.transform_point3(p))
            }
            None => own,
        }
    }
}
