//! The [`Integrator`]: camera samples (alone or in packets), and the
//! recursion from a hit to its emitted, direct and specular light.

use super::packets::CAMERA_PACKET_MIN;
use super::{CameraSample, FirstHit, PacketMode, PathEvent, RayCounts, SampleContext};
use crate::accel::{PrimHit, PACKET_SIZE};
use crate::geometry::Surface;
use crate::material::Material;
use crate::math::Ray;
use crate::sampling::Dim;
use crate::scene::Scene;
use glam::{Vec2, Vec3};

/// Paths whose weight falls below this stop.
pub const MIN_PATH_WEIGHT: f32 = 1e-3;

/// The shading point with its normals turned towards the incoming ray.
pub(super) struct Shading<'s> {
    pub(super) surface: &'s Surface,
    pub(super) material: &'s Material,
    /// The diffuse albedo ρ here: the material's, times its texture where
    /// the surface has texture coordinates. Read it, not `material.diffuse`.
    pub(super) diffuse: Vec3,
    pub(super) wo: Vec3,
    pub(super) ng: Vec3,
    pub(super) ns: Vec3,
    pub(super) entering: bool,
}

pub struct Integrator<'a> {
    pub scene: &'a Scene,
    pub counts: RayCounts,
    /// Packets or single rays for coherent batches (the image is the same).
    pub packets: PacketMode,
    /// When set, every path vertex is recorded (slow; for debugging one sample).
    pub trace: Option<Vec<PathEvent>>,
    /// The first hit of the camera ray being shaded, recorded only while a
    /// caller of [`Integrator::camera_batch`] asks for them (AOVs).
    first_hit: Option<FirstHit>,
}

impl<'a> Integrator<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        Self {
            scene,
            counts: RayCounts::default(),
            packets: PacketMode::Auto,
            trace: None,
            first_hit: None,
        }
    }

    pub fn with_packets(scene: &'a Scene, packets: PacketMode) -> Self {
        Self {
            packets,
            ..Self::new(scene)
        }
    }
}

impl Integrator<'_> {
    /// The primary ray of one camera sample.
    #[inline]
    fn camera_ray(&self, ctx: &SampleContext, film: Vec2) -> Ray {
        let lens = if self.scene.camera.uses_lens() {
            ctx.sampler.get_2d(Dim::LENS, ctx.sample, ctx.spp)
        } else {
            Vec2::splat(0.5)
        };
        self.scene.camera.generate_ray(film, lens)
    }

    /// Radiance of one camera sample at film position `film`.
    pub fn camera_sample(&mut self, ctx: &SampleContext, film: Vec2) -> Vec3 {
        let ray = self.camera_ray(ctx, film);
        self.counts.camera += 1;
        self.radiance(ctx, &ray, 0, 1.0, "camera")
    }

    /// Radiance of up to [`PACKET_SIZE`] camera samples, `out[i]` for
    /// `batch[i]`: exactly what [`Integrator::camera_sample`] returns for
    /// each, with the primary rays traced together as a packet when
    /// `self.packets` says so. Samples are shaded in batch order. With
    /// `first`, `first[i]` receives what sample `i`'s camera ray hit.
    pub fn camera_batch(
        &mut self,
        batch: &[CameraSample],
        out: &mut [Vec3],
        mut first: Option<&mut [FirstHit]>,
    ) {
        let n = batch.len();
        assert!(n <= PACKET_SIZE && out.len() >= n);
        let recording = first.is_some();
        let mut record = |i: usize, hit: Option<FirstHit>| {
            if let (Some(first), Some(hit)) = (first.as_deref_mut(), hit) {
                first[i] = hit;
            }
        };
        if !self.packets.use_packet(n, CAMERA_PACKET_MIN) {
            for (i, (o, s)) in out.iter_mut().zip(batch).enumerate() {
                self.first_hit = recording.then_some(FirstHit::MISS);
                *o = self.camera_sample(&s.ctx, s.film);
                record(i, self.first_hit.take());
            }
            return;
        }
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET_SIZE];
        for (r, s) in rays.iter_mut().zip(batch) {
            *r = self.camera_ray(&s.ctx, s.film);
        }
        let rays = &rays[..n];
        let mut hits = [None; PACKET_SIZE];
        self.scene.geometry.intersect_packet(rays, &mut hits[..n]);
        self.counts.camera += n as u64;
        for i in 0..n {
            let slot = self.begin_record(0, "camera", &rays[i]);
            self.first_hit = recording.then_some(FirstHit::MISS);
            out[i] = self.shade(&batch[i].ctx, &rays[i], hits[i], 0, 1.0, slot);
            record(i, self.first_hit.take());
        }
    }

    /// Radiance arriving along `ray` at path depth `depth`.
    pub fn radiance(
        &mut self,
        ctx: &SampleContext,
        ray: &Ray,
        depth: u32,
        weight: f32,
        kind: &'static str,
    ) -> Vec3 {
        let slot = self.begin_record(depth, kind, ray);
        let hit = self.scene.geometry.intersect(ray);
        self.shade(ctx, ray, hit, depth, weight, slot)
    }

    /// Radiance arriving along `ray`, given its closest hit (traced by the
    /// caller, alone or in a packet); `slot` is its [`Integrator::begin_record`].
    fn shade(
        &mut self,
        ctx: &SampleContext,
        ray: &Ray,
        hit: Option<PrimHit>,
        depth: u32,
        weight: f32,
        slot: usize,
    ) -> Vec3 {
        let scene = self.scene;
        let Some(hit) = hit else {
            self.finish_record(slot, None, scene.settings.background);
            return scene.settings.background;
        };
        let surface = scene.geometry.surface(ray, &hit);
        let material = &scene.materials[surface.material as usize];
        let wo = -ray.direction.normalize();
        // Face the normals towards the viewer.
        let entering = surface.geometric_normal.dot(wo) >= 0.0;
        let (ng, ns) = if entering {
            (surface.geometric_normal, surface.shading_normal)
        } else {
            (-surface.geometric_normal, -surface.shading_normal)
        };
        // One texture lookup per hit, and none on untextured surfaces.
        let diffuse = match (material.diffuse_texture, surface.uv) {
            (Some(texture), Some(uv)) => material.diffuse * scene.textures.sample(texture, uv),
            _ => material.diffuse,
        };
        let sh = Shading {
            surface: &surface,
            material,
            diffuse,
            wo,
            ng,
            ns,
            entering,
        };
        if depth == 0 {
            if let Some(first) = &mut self.first_hit {
                *first = FirstHit {
                    albedo: diffuse,
                    normal: surface.shading_normal,
                    depth: hit.t * ray.direction.length(),
                };
            }
        }

        let mut l = if entering || !material.one_sided {
            material.emission
        } else {
            Vec3::ZERO
        };
        l += self.direct_light(ctx, depth, &sh);
        if depth < scene.settings.max_depth {
            l += self.specular_transport(ctx, &sh, depth, weight);
        }
        self.finish_record(slot, Some((hit.t, hit.prim, surface.p)), l);
        l
    }

    /// Path vertices are recorded in pre-order (a parent before its
    /// children), so a replayed path prints as a tree.
    fn begin_record(&mut self, depth: u32, kind: &'static str, ray: &Ray) -> usize {
        match &mut self.trace {
            Some(trace) => {
                trace.push(PathEvent {
                    depth,
                    kind,
                    ray: *ray,
                    hit: None,
                    radiance: Vec3::ZERO,
                });
                trace.len() - 1
            }
            None => usize::MAX,
        }
    }

    fn finish_record(&mut self, slot: usize, hit: Option<(f32, u32, Vec3)>, radiance: Vec3) {
        if let Some(e) = self.trace.as_mut().and_then(|t| t.get_mut(slot)) {
            e.hit = hit;
            e.radiance = radiance;
        }
    }
}
