//! The [`Integrator`]: camera samples (alone or in packets), and the
//! recursion from a hit to its emitted, direct and specular light.

use super::sample::draw_2d_lanes;
use super::{BatchRays, CameraSample, FirstHit, PacketMode, PathEvent, RayCounts, SampleContext};
use crate::accel::{PrimHit, PACKET_SIZE};
use crate::geometry::Surface;
use crate::light::Environment;
use crate::material::Material;
use crate::math::Ray;
use crate::sampling::Dim;
use crate::scene::settings::IntegratorKind;
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

impl<'s> Shading<'s> {
    /// The hit `surface` of `ray`, with its material and its normals faced
    /// towards the viewer. Inlined, so that the shading is built where the
    /// caller keeps it rather than returned through memory and copied:
    /// dragon-rect render 2% faster (docs/mitsuba.md, "What was tried for
    /// the render").
    #[inline(always)]
    fn new(scene: &'s Scene, surface: &'s Surface, ray: &Ray) -> Self {
        let material = &scene.materials[surface.material as usize];
        let wo = -ray.direction.normalize();
        let (entering, ng, ns) = surface.facing(wo);
        // One texture lookup per hit, and none on untextured surfaces.
        let diffuse = match (material.diffuse_texture, surface.uv) {
            (Some(texture), Some(uv)) => material.diffuse * scene.textures.sample(texture, uv),
            _ => material.diffuse,
        };
        Self {
            surface,
            material,
            diffuse,
            wo,
            ng,
            ns,
            entering,
        }
    }
}

pub struct Integrator<'a> {
    pub scene: &'a Scene,
    pub counts: RayCounts,
    /// Packets or single rays for coherent batches (the image is the same).
    pub packets: PacketMode,
    /// When set, every path vertex is recorded (slow; for debugging one sample).
    pub trace: Option<Vec<PathEvent>>,
    /// The scene's environment light, if it has one: what rays that hit
    /// nothing see instead of the background.
    pub(super) environment: Option<&'a Environment>,
}

/// One ray to shade, with its closest hit: a lane of [`Integrator::shade`].
#[derive(Clone, Copy)]
pub(super) struct ShadeLane<'c> {
    pub(super) ctx: &'c SampleContext,
    ray: Ray,
    hit: Option<PrimHit>,
    /// The path's weight so far.
    weight: f32,
    /// What the environment's radiance counts for if the ray hits nothing:
    /// 1, or a glossy ray's multiple importance sampling weight.
    escape: f32,
    /// Where [`Integrator::begin_record`] put this ray's event.
    slot: usize,
}

impl<'a> Integrator<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        Self {
            scene,
            counts: RayCounts::default(),
            packets: PacketMode::Auto,
            trace: None,
            environment: scene.lights.iter().find_map(|l| l.environment()),
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
    pub(super) fn camera_ray(&self, ctx: &SampleContext, film: Vec2) -> Ray {
        let lens = if self.scene.camera.uses_lens() {
            ctx.sampler.get_2d(Dim::LENS, ctx.sample, ctx.spp)
        } else {
            Vec2::splat(0.5)
        };
        self.scene.camera.generate_ray(film, lens)
    }

    /// Radiance of one camera sample at film position `film`.
    pub fn camera_sample(&mut self, ctx: &SampleContext, film: Vec2) -> Vec3 {
        let mut out = [Vec3::ZERO];
        self.camera_batch(&[CameraSample { ctx: *ctx, film }], &mut out, None);
        out[0]
    }

    /// Radiance of up to [`PACKET_SIZE`] camera samples, `out[i]` for
    /// `batch[i]`: exactly what [`Integrator::camera_sample`] returns for
    /// each, with the primary rays traced together as a packet when
    /// `self.packets` says so, and the hits shaded together (their light
    /// samples in SIMD lanes). With `first`, `first[i]` receives what
    /// sample `i`'s camera ray hit.
    pub fn camera_batch(
        &mut self,
        batch: &[CameraSample],
        out: &mut [Vec3],
        mut first: Option<&mut [FirstHit]>,
    ) {
        let n = batch.len();
        assert!(n <= PACKET_SIZE && out.len() >= n);
        if n == 0 {
            return;
        }
        if self.scene.settings.integrator == IntegratorKind::Path {
            return self.path_batch(batch, out, first);
        }
        if self.trace.is_some() && n > 1 {
            // A replay records each path's vertices in pre-order, one
            // sample after the other.
            for i in 0..n {
                let first_i = first.as_deref_mut().map(|f| &mut f[i..=i]);
                self.camera_batch(&batch[i..=i], &mut out[i..=i], first_i);
            }
            return;
        }
        if n == 1 {
            // One sample: shaded as one lane, without a batch's arrays.
            let ray = self.camera_ray(&batch[0].ctx, batch[0].film);
            self.counts.camera += 1;
            out[0] = self.trace_and_shade(&batch[0].ctx, &ray, 0, 1.0, 1.0, "camera", first);
            return;
        }
        let (rays, hits) = self.camera_hits(batch);
        let rays = &rays[..n];
        // (Lanes past `n` repeat the last one, unused.)
        let mut lanes: [_; PACKET_SIZE] = std::array::from_fn(|i| {
            let i = i.min(n - 1);
            ShadeLane {
                ctx: &batch[i].ctx,
                ray: rays[i],
                hit: hits[i],
                weight: 1.0,
                escape: 1.0,
                slot: usize::MAX,
            }
        });
        for lane in &mut lanes[..n] {
            lane.slot = self.begin_record(0, "camera", &lane.ray);
        }
        self.shade::<PACKET_SIZE>(0, &lanes[..n], out, first);
    }

    /// The camera rays of a batch of two or more samples and their first
    /// hits, each bit for bit what `camera_ray` and `intersect` give it
    /// alone: the rays made eight at a time in lanes, traced as one packet
    /// where [`PacketMode`] says a packet pays. Lanes past the batch
    /// repeat its last sample, unused.
    pub(super) fn camera_hits(
        &mut self,
        batch: &[CameraSample],
    ) -> ([Ray; PACKET_SIZE], [Option<PrimHit>; PACKET_SIZE]) {
        let n = batch.len();
        // The lens samples as `camera_ray` draws them, eight at a time.
        let lens = if self.scene.camera.uses_lens() {
            let at = |i: usize| (batch[i].ctx.sample, batch[i].ctx.spp);
            draw_2d_lanes((1 << n) - 1, |i| &batch[i].ctx, Dim::LENS, at)
        } else {
            [Vec2::splat(0.5); PACKET_SIZE]
        };
        let film = std::array::from_fn(|i| batch[i.min(n - 1)].film);
        let rays = self.scene.camera.generate_rays(&film, &lens);
        let mut hits = [None; PACKET_SIZE];
        if self.packets.use_packet(BatchRays::Camera, n) {
            self.scene
                .geometry
                .intersect_packet(&rays[..n], &mut hits[..n]);
        } else {
            for (h, r) in hits.iter_mut().zip(&rays[..n]) {
                *h = self.scene.geometry.intersect(r);
            }
        }
        self.counts.camera += n as u64;
        (rays, hits)
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
        self.trace_and_shade(ctx, ray, depth, weight, 1.0, kind, None)
    }

    /// [`Integrator::radiance`] with the environment seen through weight
    /// `escape` if the ray hits nothing (a glossy ray's multiple importance
    /// sampling weight).
    pub(super) fn radiance_escaping(
        &mut self,
        ctx: &SampleContext,
        ray: &Ray,
        depth: u32,
        weight: f32,
        escape: f32,
    ) -> Vec3 {
        self.trace_and_shade(ctx, ray, depth, weight, escape, "glossy", None)
    }

    /// [`Integrator::radiance`], and at depth 0, with `first`, what the
    /// ray hit into `first[0]`.
    #[allow(clippy::too_many_arguments)]
    fn trace_and_shade(
        &mut self,
        ctx: &SampleContext,
        ray: &Ray,
        depth: u32,
        weight: f32,
        escape: f32,
        kind: &'static str,
        first: Option<&mut [FirstHit]>,
    ) -> Vec3 {
        let slot = self.begin_record(depth, kind, ray);
        let hit = self.scene.geometry.intersect(ray);
        let lane = ShadeLane {
            ctx,
            ray: *ray,
            hit,
            weight,
            escape,
            slot,
        };
        let mut out = [Vec3::ZERO];
        self.shade::<1>(depth, &[lane], &mut out, first);
        out[0]
    }

    /// Radiance arriving along each lane's ray at path depth `depth`,
    /// given its closest hit (traced by the caller, alone or in a packet),
    /// into `out`; at depth 0, with `first`, what each ray hit first.
    /// The lanes' direct light is computed together; each lane's result
    /// is exactly what shading it alone gives. `N` bounds the lanes: the
    /// per-lane arrays are that long, so one ray pays for one lane.
    fn shade<const N: usize>(
        &mut self,
        depth: u32,
        lanes: &[ShadeLane],
        out: &mut [Vec3],
        first: Option<&mut [FirstHit]>,
    ) {
        let scene = self.scene;
        // Filled in place, slot by slot: built through `array::from_fn`
        // and `?`, each element was written into a temporary and copied
        // with wide loads that waited on its narrower stores (docs/mitsuba.md,
        // "What was tried for the render").
        let mut surfaces: [Option<Surface>; N] = [None; N];
        for (surface, lane) in surfaces.iter_mut().zip(lanes) {
            if let Some(hit) = &lane.hit {
                let mut s = scene.geometry.surface(&lane.ray, hit);
                // Only where a file gave a normal or bump map.
                let m = &scene.materials[s.material as usize];
                if m.maps.normal.is_some() {
                    let wo = -lane.ray.direction.normalize();
                    super::maps::apply_normal_map(scene, m, &mut s, hit, wo);
                }
                *surface = Some(s);
            }
        }
        let mut shadings: [Option<Shading>; N] = std::array::from_fn(|_| None);
        for ((shading, surface), lane) in shadings.iter_mut().zip(&surfaces).zip(lanes) {
            if let Some(surface) = surface {
                *shading = Some(Shading::new(scene, surface, &lane.ray));
            }
        }
        if let Some(first) = first.filter(|_| depth == 0) {
            for (i, lane) in lanes.iter().enumerate() {
                first[i] = match (&shadings[i], lane.hit) {
                    (Some(sh), Some(hit)) => FirstHit {
                        albedo: sh.diffuse,
                        normal: sh.surface.shading_normal,
                        depth: hit.t * lane.ray.direction.length(),
                    },
                    _ => FirstHit::MISS,
                };
            }
        }
        let direct = self.direct_light(depth, lanes, &shadings);
        for (i, lane) in lanes.iter().enumerate() {
            let (Some(sh), Some(hit)) = (&shadings[i], lane.hit) else {
                let l = match self.environment {
                    Some(env) => env.radiance(lane.ray.direction) * lane.escape,
                    None => scene.settings.background,
                };
                self.finish_record(lane.slot, None, l);
                out[i] = l;
                continue;
            };
            let material = sh.material;
            let mut l = if sh.entering || !material.one_sided {
                super::maps::emission(scene, material, sh.surface.uv)
            } else {
                Vec3::ZERO
            };
            l += direct[i];
            // A material without mirror or glass layers (most of them)
            // skips the call, which then returns zero.
            if depth < scene.settings.max_depth && material.transports_specular() {
                l += self.specular_transport(lane.ctx, sh, depth, lane.weight);
            }
            self.finish_record(lane.slot, Some((hit.t, hit.prim, sh.surface.p)), l);
            out[i] = l;
        }
    }

    /// Path vertices are recorded in pre-order (a parent before its
    /// children), so a replayed path prints as a tree.
    pub(super) fn begin_record(&mut self, depth: u32, kind: &'static str, ray: &Ray) -> usize {
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

    pub(super) fn finish_record(
        &mut self,
        slot: usize,
        hit: Option<(f32, u32, Vec3)>,
        radiance: Vec3,
    ) {
        if let Some(e) = self.trace.as_mut().and_then(|t| t.get_mut(slot)) {
            e.hit = hit;
            e.radiance = radiance;
        }
    }
}
