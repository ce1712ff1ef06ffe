//! The compiled scene: flat arrays the hot loop reads, and the three
//! queries the integrator needs (closest hit, occlusion, surface).

use crate::accel::traverse::closer;
use crate::accel::{Bvh8, Packet, PACKET_SIZE};
use crate::camera::Camera;
use crate::math::offset::{barycentric_error, transformed_error};
use crate::math::ray::ray_lanes;
use crate::math::{Aabb, Ray, Transform};
use crate::sampling::SamplerKind;
use crate::scene::asset::MeshNormals;
use crate::shade::light::Light;
use crate::shade::material::Material;
use crate::shape::csg::Csg;
use crate::shape::cylinder::Cylinder;
use crate::shape::disk::Disk;
use crate::shape::plane::Plane;
use crate::shape::rect::Rect;
use crate::shape::sphere::Sphere;
use crate::shape::triangle::{self, ShearedRay};
use crate::shape::triangle8::{self, ShearedRays, TriangleBlock, LANES};
use crate::shape::{PrimHit, Surface};
use glam::Vec3;

/// An analytic shape in its own object space. Closed set: the hot loop matches on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    Sphere(Sphere),
    Cylinder(Cylinder),
    /// The visible surface of a `rect` area light.
    Rect(Rect),
    /// The visible surface of a `disk` area light.
    Disk(Disk),
    /// The root node of a tree in [`Scene::csg`].
    Csg(u32),
}

impl Shape {
    /// The first hit in `(tmin, tmax)`; the caller fills in `prim`.
    #[inline]
    fn intersect(&self, ray: &Ray, csg: &Csg) -> Option<PrimHit> {
        let (t, part) = match self {
            Shape::Sphere(s) => (s.intersect(ray)?, 0),
            Shape::Cylinder(c) => c.intersect(ray)?,
            Shape::Rect(r) => (r.intersect(ray)?, 0),
            Shape::Disk(d) => (d.intersect(ray)?, 0),
            Shape::Csg(root) => return csg.intersect(*root, ray),
        };
        Some(PrimHit {
            t,
            prim: 0,
            u: 0.0,
            v: 0.0,
            part,
        })
    }

    /// Object-space point, error bound and outward normal, and the material
    /// if the shape chooses it per part.
    fn surface_at(&self, ray: &Ray, hit: &PrimHit, csg: &Csg) -> (Vec3, Vec3, Vec3, Option<u32>) {
        let (p, err, n) = match self {
            Shape::Sphere(s) => s.surface_at(ray.at(hit.t)),
            Shape::Cylinder(c) => c.surface_at(ray.at(hit.t), hit.part),
            Shape::Rect(r) => r.surface_at(ray.at(hit.t)),
            Shape::Disk(d) => d.surface_at(ray.at(hit.t)),
            Shape::Csg(_) => {
                let (p, err, n, material) = csg.surface_at(ray, hit);
                return (p, err, n, Some(material));
            }
        };
        (p, err, n, None)
    }

    pub fn bounds(&self, csg: &Csg) -> Aabb {
        match self {
            Shape::Sphere(s) => s.bounds(),
            Shape::Cylinder(c) => c.bounds(),
            Shape::Rect(r) => r.bounds(),
            Shape::Disk(d) => d.bounds(),
            Shape::Csg(root) => csg.bounds(*root),
        }
    }
}

pub const NO_TRANSFORM: u32 = u32::MAX;

/// A bounded analytic primitive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalyticPrim {
    pub shape: Shape,
    /// Index into [`Scene::transforms`], or [`NO_TRANSFORM`].
    pub transform: u32,
    pub material: u32,
}

/// A run of triangles from one mesh, sharing one material.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshRange {
    pub name: String,
    pub first: u32,
    pub count: u32,
    pub material: u32,
    /// Shading normals, only when the file had them.
    pub normals: Option<MeshNormals>,
}

/// Render settings after the scene file and the command line are merged.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub shadow_samples: u32,
    pub reflection_samples: u32,
    pub max_depth: u32,
    pub sampler: SamplerKind,
    pub seed: u32,
    pub background: Vec3,
    pub light_sampling: crate::shade::light::LightSampling,
    pub glossy_sampling: crate::shade::integrator::GlossySampling,
}

#[derive(Debug, Clone)]
pub struct Scene {
    /// The BVH's leaves, eight slots to a block: slot `s` is lane `s % 8`
    /// of block `s / 8` and holds primitive `id[lane]` with, for a
    /// triangle (an id below `triangle_count`), its world-space vertices,
    /// stored once, in the order traversal reads them. The slots of
    /// analytic shapes and padding hold NaN vertices. These ids are the
    /// BVH's leaf order (its own `prim_ids` is emptied once they are
    /// here). Triangle ids stay in file order: triangle `i` of the scene's
    /// meshes is primitive `i`. Use [`Scene::triangle`] for a hit's
    /// vertices and [`Scene::file_order_triangles`] for a copy in file
    /// order.
    pub leaf_blocks: Vec<TriangleBlock>,
    /// Triangles in the scene: primitives `0..triangle_count`.
    pub triangle_count: u32,
    /// Sorted by `first`; covers every triangle.
    pub meshes: Vec<MeshRange>,
    /// Primitive `triangles.len() + i`.
    pub shapes: Vec<AnalyticPrim>,
    pub transforms: Vec<Transform>,
    /// The CSG trees that [`Shape::Csg`] primitives name, with their operands.
    pub csg: Csg,
    /// Unbounded, outside the BVH.
    pub planes: Vec<Plane>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub settings: RenderSettings,
    pub bvh: Bvh8,
}

/// The packet of up to [`PACKET_SIZE`] rays, whose lanes a leaf test makes
/// the per-lane shears from ([`ShearedRays::from_lanes`]) once a leaf is
/// reached; `None` where the rays cannot travel as a packet (see
/// [`Packet::new`]).
#[inline(always)]
fn packet_of(rays: &[Ray]) -> Option<Packet<'_>> {
    if rays.is_empty() || rays.len() > PACKET_SIZE {
        return None;
    }
    Packet::from_lanes(rays, &ray_lanes(rays))
}

impl Scene {
    pub fn primitive_count(&self) -> usize {
        self.triangle_count as usize + self.shapes.len()
    }

    /// The vertices of a triangle hit (its `part` is the leaf slot).
    #[inline]
    pub fn triangle(&self, hit: &PrimHit) -> [Vec3; 3] {
        let block = &self.leaf_blocks[hit.part as usize / LANES];
        debug_assert_eq!(block.id[hit.part as usize % LANES], hit.prim);
        block.triangle(hit.part as usize % LANES)
    }

    /// Every triangle in file order (a copy; for tools, not the hot loop).
    pub fn file_order_triangles(&self) -> Vec<[Vec3; 3]> {
        let mut out = vec![[Vec3::ZERO; 3]; self.triangle_count as usize];
        for block in &self.leaf_blocks {
            for (lane, &id) in block.id.iter().enumerate() {
                if id < self.triangle_count {
                    out[id as usize] = block.triangle(lane);
                }
            }
        }
        out
    }

    /// Bytes held by the per-triangle structures that tracing and shading
    /// read: BVH nodes, the leaf blocks (vertices and ids) and the shading
    /// normals of meshes that have them (materials are per mesh).
    pub fn accel_bytes(&self) -> usize {
        let normals: usize = self
            .meshes
            .iter()
            .filter_map(|m| m.normals.as_ref())
            .map(|n| {
                n.values.len() * std::mem::size_of::<Vec3>()
                    + n.indices.len() * std::mem::size_of::<[u32; 3]>()
            })
            .sum();
        self.traversal_bytes() + normals
    }

    /// Bytes traversal reads: BVH nodes and leaf blocks (what decides
    /// whether it prefetches, see [`crate::accel::prefetch`]).
    pub fn traversal_bytes(&self) -> usize {
        self.bvh.memory_bytes() + std::mem::size_of_val(self.leaf_blocks.as_slice())
    }

    #[inline]
    fn object_ray(&self, prim: &AnalyticPrim, ray: &Ray) -> Ray {
        if prim.transform == NO_TRANSFORM {
            *ray
        } else {
            let m = &self.transforms[prim.transform as usize].to_object;
            // The direction is not renormalised, so t stays the world t.
            Ray {
                origin: m.transform_point3(ray.origin),
                direction: m.transform_vector3(ray.direction),
                tmin: ray.tmin,
                tmax: ray.tmax,
            }
        }
    }

    /// Test analytic primitive `id` (not a triangle).
    #[inline]
    fn hit_analytic(&self, id: u32, ray: &Ray) -> Option<PrimHit> {
        let prim = &self.shapes[(id - self.triangle_count) as usize];
        let local = self.object_ray(prim, ray);
        let hit = prim.shape.intersect(&local, &self.csg)?;
        Some(PrimHit { prim: id, ..hit })
    }

    /// The lanes of leaf `start..start + count` in its block.
    #[inline(always)]
    fn leaf_lanes(start: u32, count: u32) -> (usize, u32) {
        let lo = start % LANES as u32;
        ((start / LANES as u32) as usize, ((1u32 << count) - 1) << lo)
    }

    /// The closest hit in leaf `start..start + count`: its triangles in one
    /// 8-wide test, then any analytic shapes it holds. A triangle hit
    /// records its slot in `part`, so [`Scene::surface`] finds its vertices.
    #[inline(always)]
    fn hit_leaf(&self, start: u32, count: u32, ray: &Ray, sheared: &ShearedRay) -> Option<PrimHit> {
        let (b, lanes) = Self::leaf_lanes(start, count);
        let block = &self.leaf_blocks[b];
        let mut best = triangle8::closest(ray, sheared, block, lanes).map(|h| PrimHit {
            t: h.t,
            prim: block.id[h.lane],
            u: h.u,
            v: h.v,
            part: (b * LANES + h.lane) as u32,
        });
        if !self.shapes.is_empty() {
            let mut ray = Ray {
                tmax: best.map_or(ray.tmax, |h| h.t.next_up()),
                ..*ray
            };
            let mut m = lanes;
            while m != 0 {
                let id = block.id[m.trailing_zeros() as usize];
                m &= m - 1;
                if id >= self.triangle_count {
                    if let Some(h) = self.hit_analytic(id, &ray) {
                        if closer(&h, best.as_ref()) {
                            ray.tmax = h.t.next_up();
                            best = Some(h);
                        }
                    }
                }
            }
        }
        best
    }

    /// True if something in leaf `start..start + count` other than
    /// primitive `except` blocks the ray.
    #[inline(always)]
    fn blocks_leaf(
        &self,
        start: u32,
        count: u32,
        ray: &Ray,
        sheared: &ShearedRay,
        except: u32,
    ) -> bool {
        let (b, lanes) = Self::leaf_lanes(start, count);
        let block = &self.leaf_blocks[b];
        let mut hit = triangle8::intersect(ray, sheared, block, lanes).0;
        while hit != 0 {
            let lane = hit.trailing_zeros() as usize;
            hit &= hit - 1;
            if block.id[lane] != except {
                return true;
            }
        }
        if !self.shapes.is_empty() {
            let mut m = lanes;
            while m != 0 {
                let id = block.id[m.trailing_zeros() as usize];
                m &= m - 1;
                if id >= self.triangle_count && id != except && self.hit_analytic(id, ray).is_some()
                {
                    return true;
                }
            }
        }
        false
    }

    /// [`Scene::hit_leaf`] for the packet rays in the bits of `rays_mask`:
    /// each triangle of the leaf against all those rays in one 8-wide test
    /// (rays in lanes), updating `out[ray]` with any hit [`closer`] than
    /// it. Returns whether any changed. The result per ray is the minimum
    /// of the same total order over the same candidates as
    /// [`Scene::hit_leaf`], so it is bit for bit the single-ray answer.
    #[inline(always)]
    fn hit_leaf_packet(
        &self,
        rays: &[Ray],
        sheared: &ShearedRays,
        start: u32,
        count: u32,
        rays_mask: u32,
        out: &mut [Option<PrimHit>],
    ) -> bool {
        let (b, lanes) = Self::leaf_lanes(start, count);
        let block = &self.leaf_blocks[b];
        let mut changed = false;
        // Each ray's interval: up to and including its best t, for ties.
        let mut tmax = [f32::NEG_INFINITY; PACKET_SIZE];
        for (i, r) in rays.iter().enumerate() {
            tmax[i] = out[i].map_or(r.tmax, |h| h.t.next_up());
        }
        let mut m = lanes;
        while m != 0 {
            let lane = m.trailing_zeros() as usize;
            m &= m - 1;
            let id = block.id[lane];
            if id < self.triangle_count {
                let tri = block.triangle(lane);
                let (mut hit, t, u, v) = sheared.intersect(&tri, tmax.into(), rays_mask);
                while hit != 0 {
                    let i = hit.trailing_zeros() as usize;
                    hit &= hit - 1;
                    let h = PrimHit {
                        t: t[i],
                        prim: id,
                        u: u[i],
                        v: v[i],
                        part: (b * LANES + lane) as u32,
                    };
                    if closer(&h, out[i].as_ref()) {
                        out[i] = Some(h);
                        tmax[i] = h.t.next_up();
                        changed = true;
                    }
                }
            } else {
                let mut r = rays_mask;
                while r != 0 {
                    let i = r.trailing_zeros() as usize;
                    r &= r - 1;
                    let ray = Ray {
                        tmax: tmax[i],
                        ..rays[i]
                    };
                    if let Some(h) = self.hit_analytic(id, &ray) {
                        if closer(&h, out[i].as_ref()) {
                            out[i] = Some(h);
                            tmax[i] = h.t.next_up();
                            changed = true;
                        }
                    }
                }
            }
        }
        changed
    }

    /// [`Scene::blocks_leaf`] for the packet rays in the bits of
    /// `rays_mask`; returns the rays blocked.
    #[inline(always)]
    fn blocks_leaf_packet(
        &self,
        rays: &[Ray],
        sheared: &ShearedRays,
        start: u32,
        count: u32,
        rays_mask: u32,
        except: u32,
    ) -> u32 {
        let (b, lanes) = Self::leaf_lanes(start, count);
        let block = &self.leaf_blocks[b];
        let mut tmax = [f32::NEG_INFINITY; PACKET_SIZE];
        for (i, r) in rays.iter().enumerate() {
            tmax[i] = r.tmax;
        }
        let tmax = tmax.into();
        let mut open = rays_mask;
        let mut m = lanes;
        while m != 0 && open != 0 {
            let lane = m.trailing_zeros() as usize;
            m &= m - 1;
            let id = block.id[lane];
            if id == except {
                continue;
            }
            if id < self.triangle_count {
                open &= !sheared.intersect(&block.triangle(lane), tmax, open).0;
            } else {
                let mut r = open;
                while r != 0 {
                    let i = r.trailing_zeros() as usize;
                    r &= r - 1;
                    if self.hit_analytic(id, &rays[i]).is_some() {
                        open &= !(1 << i);
                    }
                }
            }
        }
        rays_mask & !open
    }

    /// The closest hit in `(ray.tmin, ray.tmax)`. Planes report prim ids
    /// `u32::MAX - plane index`.
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        // The shear is made at the first leaf: most rays of a sparse view
        // miss every leaf box.
        let mut sheared = None;
        let best = self.bvh.closest(ray, &self.leaf_blocks, |start, count, r| {
            let s = sheared.get_or_insert_with(|| ShearedRay::new(ray));
            self.hit_leaf(start, count, r, s)
        });
        self.closest_plane(ray, best)
    }

    /// `best`, or a plane hit nearer than it.
    #[inline]
    fn closest_plane(&self, ray: &Ray, mut best: Option<PrimHit>) -> Option<PrimHit> {
        let mut tmax = best.map_or(ray.tmax, |h| h.t);
        for (i, plane) in self.planes.iter().enumerate() {
            let r = Ray { tmax, ..*ray };
            if let Some(t) = plane.intersect(&r) {
                tmax = t;
                best = Some(PrimHit {
                    t,
                    prim: u32::MAX - i as u32,
                    u: 0.0,
                    v: 0.0,
                    part: 0,
                });
            }
        }
        best
    }

    /// Closest hits of up to [`PACKET_SIZE`] rays: `out[i]` is bit for bit
    /// `self.intersect(&rays[i])`. The rays traverse as one packet unless
    /// [`Packet::new`] refuses them (directions differing in sign on every
    /// axis).
    pub fn intersect_packet(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        let Some(packet) = packet_of(rays) else {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.intersect(r);
            }
            return;
        };
        let mut sheared = None;
        self.bvh.closest_packet(
            &packet,
            out,
            &self.leaf_blocks,
            |start, count, lanes, out| {
                let s = sheared.get_or_insert_with(|| ShearedRays::from_lanes(packet.lanes()));
                self.hit_leaf_packet(rays, s, start, count, lanes, out)
            },
        );
        if !self.planes.is_empty() {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.closest_plane(r, *o);
            }
        }
    }

    /// True if anything blocks the ray in `(ray.tmin, ray.tmax)`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        // No primitive has id u32::MAX (planes count down from it, outside the BVH).
        self.occluded_except(ray, u32::MAX)
    }

    /// Occlusion of up to [`PACKET_SIZE`] rays, ignoring primitive `except`
    /// (`u32::MAX`: none): `out[i]` is exactly
    /// `self.occluded_except(&rays[i], except)`. One packet unless the
    /// rays' directions differ in sign on every axis ([`Packet::new`]).
    pub fn occluded_packet(&self, rays: &[Ray], except: u32, out: &mut [bool]) {
        let Some(packet) = packet_of(rays) else {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.occluded_except(r, except);
            }
            return;
        };
        let mut sheared = None;
        self.bvh
            .any_hit_packet(&packet, out, &self.leaf_blocks, |start, count, lanes| {
                let s = sheared.get_or_insert_with(|| ShearedRays::from_lanes(packet.lanes()));
                self.blocks_leaf_packet(rays, s, start, count, lanes, except)
            });
        if !self.planes.is_empty() {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = *o || self.planes.iter().any(|p| p.intersect(r).is_some());
            }
        }
    }

    /// Planes are reported with ids counting down from `u32::MAX`.
    pub fn plane_index(&self, prim: u32) -> Option<usize> {
        let i = (u32::MAX - prim) as usize;
        (i < self.planes.len()).then_some(i)
    }

    /// True if anything other than primitive `except` (the light being
    /// sampled) blocks the ray. Skipping the light's own primitive is exact,
    /// where stopping the shadow ray a little short of it would need an epsilon.
    pub fn occluded_except(&self, ray: &Ray, except: u32) -> bool {
        if self.planes.iter().any(|p| p.intersect(ray).is_some()) {
            return true;
        }
        let mut sheared = None;
        self.bvh.any_hit(ray, &self.leaf_blocks, |start, count, r| {
            let s = sheared.get_or_insert_with(|| ShearedRay::new(ray));
            self.blocks_leaf(start, count, r, s, except)
        })
    }

    /// The mesh a triangle belongs to.
    pub fn mesh_of(&self, tri: u32) -> &MeshRange {
        let i = self.meshes.partition_point(|m| m.first + m.count <= tri);
        &self.meshes[i]
    }

    /// Full geometry of a hit, computed once per closest hit.
    pub fn surface(&self, ray: &Ray, hit: &PrimHit) -> Surface {
        let n_tris = self.triangle_count;
        if let Some(i) = self.plane_index(hit.prim) {
            let plane = &self.planes[i];
            let (p, p_error) = plane.surface_at(ray.at(hit.t));
            return Surface {
                p,
                p_error,
                geometric_normal: plane.normal,
                shading_normal: plane.normal,
                material: plane.material,
            };
        }
        if hit.prim < n_tris {
            let v = self.triangle(hit);
            let b = [1.0 - hit.u - hit.v, hit.u, hit.v];
            let p = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
            let ng = triangle::geometric_normal(&v).normalize_or(Vec3::Z);
            let mesh = self.mesh_of(hit.prim);
            let mut ns = ng;
            if let Some(normals) = &mesh.normals {
                let idx = normals.indices[(hit.prim - mesh.first) as usize];
                let n = b[0] * normals.values[idx[0] as usize]
                    + b[1] * normals.values[idx[1] as usize]
                    + b[2] * normals.values[idx[2] as usize];
                if let Some(n) = n.try_normalize() {
                    // Keep the shading normal on the geometric side.
                    ns = if n.dot(ng) < 0.0 { -n } else { n };
                }
            }
            return Surface {
                p,
                p_error: barycentric_error(b, v),
                geometric_normal: ng,
                shading_normal: ns,
                material: mesh.material,
            };
        }
        let prim = &self.shapes[(hit.prim - n_tris) as usize];
        let local = self.object_ray(prim, ray);
        let (p, err, n, material) = prim.shape.surface_at(&local, hit, &self.csg);
        let (p, p_error, n) = if prim.transform == NO_TRANSFORM {
            (p, err, n)
        } else {
            let tr = &self.transforms[prim.transform as usize];
            (
                tr.point(p),
                transformed_error(&tr.to_world, p, err),
                tr.normal(n),
            )
        };
        Surface {
            p,
            p_error,
            geometric_normal: n,
            shading_normal: n,
            material: material.unwrap_or(prim.material),
        }
    }
}
