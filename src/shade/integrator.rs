//! The distribution ray tracer: Whitted's recursion (1980) with Cook's
//! distributed effects (Cook, Porter and Carpenter 1984).
//!
//! At each hit: emitted radiance, direct light from every light through
//! shadow rays (radiometric Phong: ρ/π diffuse plus the normalised lobe
//! (n+2)/(2π) k_s cosⁿα), then a mirror ray weighted by `reflectivity` and a
//! refracted ray weighted by `transparency` (Snell's law, total internal
//! reflection sends the refracted weight into the reflection).
//! Recursion stops at `max_depth` or when the path weight falls below 1e-3.
//!
//! Distributed effects, each stratified over the pixel's one sample set:
//! area lights take `shadow_samples` M samples per hit; a glossy surface
//! (`glossiness` n > 0) replaces the mirror ray by rays importance-sampled
//! from the normalised cosⁿ lobe around the mirror direction (Lafortune and
//! Willems 1994), and the reflected radiance is the lobe-weighted average of
//! incoming radiance. The first glossy hit of a path branches into
//! `reflection_samples` K rays; deeper glossy hits trace one ray each, so
//! the cost grows by K once, not Kᵈᵉᵖᵗʰ. Lobe directions that fall below the
//! surface are rejected (they contribute nothing) and counted.
//!
//! Coherent batches are traced as packets ([`PacketMode`]): the camera rays
//! of neighbouring samples ([`Integrator::camera_batch`]) and the shadow rays
//! from one hit point towards one light. Packets return exactly the hits of
//! single rays and every batch is shaded in sample order, so the image is
//! bit-identical with packets on or off.

use crate::accel::PrimHit;
use crate::accel::PACKET_SIZE;
use crate::geometry::Surface;
use crate::material::Material;
use crate::math::offset::spawn_origin;
use crate::math::{Frame, Ray};
use crate::sampling::warp::{phong_lobe, phong_lobe_pdf, uniform_hemisphere};
use crate::sampling::{Dim, PixelSampler};
use crate::scene::settings::GlossySampling;
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Paths whose weight falls below this stop.
pub const MIN_PATH_WEIGHT: f32 = 1e-3;

/// Rays traced, by kind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct RayCounts {
    pub camera: u64,
    pub shadow: u64,
    pub reflection: u64,
    pub refraction: u64,
    /// Glossy directions that fell below the surface (not traced, not leaked).
    pub glossy_rejected: u64,
}

impl RayCounts {
    pub fn total(&self) -> u64 {
        self.camera + self.shadow + self.reflection + self.refraction
    }

    pub fn add(&mut self, o: &RayCounts) {
        self.camera += o.camera;
        self.shadow += o.shadow;
        self.reflection += o.reflection;
        self.refraction += o.refraction;
        self.glossy_rejected += o.glossy_rejected;
    }
}

crate::mode::mode_enum! {
    /// Whether coherent batches of rays are traced as packets.
    #[derive(Default)]
    pub enum PacketMode("packet mode") {
        /// Packets where they were measured to pay: camera batches of at least
        /// [`CAMERA_PACKET_MIN`] rays, and shadow batches of at least
        /// [`SHADOW_PACKET_MIN`] rays (never). Single rays otherwise.
        #[default]
        Auto = "auto",
        /// Every batch as a packet, however few rays it holds.
        On = "on",
        /// Single rays only.
        Off = "off",
    }
}

// The `auto` thresholds, from the packet/single throughput of the renderer's
// own batches (README, "Packets in the renderer"; reproduce with `cargo test
// --release --test render_packets -- --ignored --nocapture`), medians of 15
// alternating runs on a shared 2-core machine. Re-measured after packets
// began testing each leaf triangle against all their rays at once:
// - camera batches (one pixel's pixel and lens samples): at 8 rays 1.15x
//   (bunny, thin lens), 1.44x (bunny, pinhole), 1.13x (scenes/thin-lens.toml,
//   one node) and 1.66x (scenes/mesh.toml); at 7 rays 1.00-1.37x; at 6 rays
//   1.00-1.25x; below 6 rays 0.3-1.0x. Scene size no longer matters;
// - shadow batches (8 stratified samples from one hit towards a rect
//   light): 0.83-1.05x at every size, never a clear gain; about half of
//   them differed in direction sign (the light straddles the point) and
//   then fell back to single rays inside `Scene::occluded_packet`.
// (Before that change packets lost below 8 camera rays everywhere and won
// only on 1000+ node scenes at 8, so `auto` needed a node threshold.)
// Re-measured after packets began travelling with mixed signs and
// measuring slabs from an apex: camera batches at 8 rays 1.14-2.50x, at 7
// rays 1.00-1.67x, at 6 rays 1.00-1.67x; shadow batches 0.76-0.87x at 3
// to 8 rays (one origin, but eight points on the light spread too wide).
// The thresholds stand.

/// Fewest rays a camera batch must hold for `auto` to trace it as a packet.
pub const CAMERA_PACKET_MIN: usize = 7;
/// Fewest rays a shadow batch must hold for `auto` to trace it as a packet:
/// more than a packet holds, so never (see above).
pub const SHADOW_PACKET_MIN: usize = PACKET_SIZE + 1;

impl PacketMode {
    /// Trace a batch of `live` rays as a packet, where `auto` asks for at
    /// least `auto_min`?
    #[inline]
    pub fn use_packet(self, live: usize, auto_min: usize) -> bool {
        match self {
            Self::Auto => live >= auto_min,
            Self::On => live > 0,
            Self::Off => false,
        }
    }
}

/// One camera sample of a batch: its context and film position.
#[derive(Debug, Clone, Copy)]
pub struct CameraSample {
    pub ctx: SampleContext,
    pub film: Vec2,
}

/// Identifies one camera sample and, after a glossy branch, one of its K
/// branches: everything random in the path derives from this.
#[derive(Debug, Clone, Copy)]
pub struct SampleContext {
    pub sampler: PixelSampler,
    pub sample: u32,
    pub spp: u32,
    /// Which branch of the first glossy split this path follows, of `branches`.
    pub branch: u32,
    pub branches: u32,
}

impl SampleContext {
    pub fn new(sampler: PixelSampler, sample: u32, spp: u32) -> Self {
        Self {
            sampler,
            sample,
            spp,
            branch: 0,
            branches: 1,
        }
    }

    /// This path's index in the pixel's set of `count()` paths.
    #[inline]
    pub fn index(&self) -> u32 {
        self.sample * self.branches + self.branch
    }

    #[inline]
    pub fn count(&self) -> u32 {
        self.spp * self.branches
    }
}

/// One path vertex, for `--debug-sample` replays.
#[derive(Debug, Clone)]
pub struct PathEvent {
    pub depth: u32,
    pub kind: &'static str,
    pub ray: Ray,
    pub hit: Option<(f32, u32, Vec3)>,
    pub radiance: Vec3,
}

/// The shading point with its normals turned towards the incoming ray.
struct Shading<'s> {
    surface: &'s Surface,
    material: &'s Material,
    wo: Vec3,
    ng: Vec3,
    ns: Vec3,
    entering: bool,
}

pub struct Integrator<'a> {
    pub scene: &'a Scene,
    pub counts: RayCounts,
    /// Packets or single rays for coherent batches (the image is the same).
    pub packets: PacketMode,
    /// When set, every path vertex is recorded (slow; for debugging one sample).
    pub trace: Option<Vec<PathEvent>>,
}

impl<'a> Integrator<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        Self {
            scene,
            counts: RayCounts::default(),
            packets: PacketMode::Auto,
            trace: None,
        }
    }

    pub fn with_packets(scene: &'a Scene, packets: PacketMode) -> Self {
        Self {
            packets,
            ..Self::new(scene)
        }
    }

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
    /// `self.packets` says so. Samples are shaded in batch order.
    pub fn camera_batch(&mut self, batch: &[CameraSample], out: &mut [Vec3]) {
        let n = batch.len();
        assert!(n <= PACKET_SIZE && out.len() >= n);
        if !self.packets.use_packet(n, CAMERA_PACKET_MIN) {
            for (o, s) in out.iter_mut().zip(batch) {
                *o = self.camera_sample(&s.ctx, s.film);
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
            out[i] = self.shade(&batch[i].ctx, &rays[i], hits[i], 0, 1.0, slot);
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
        let sh = Shading {
            surface: &surface,
            material,
            wo,
            ng,
            ns,
            entering,
        };

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

    /// Phong direct lighting: one shadow ray per delta light, M stratified
    /// samples per area light.
    fn direct_light(&mut self, ctx: &SampleContext, depth: u32, sh: &Shading) -> Vec3 {
        let m = sh.material;
        let diffuse = m.diffuse.max_element() > 0.0;
        let specular = m.has_specular_lobe();
        if !diffuse && !specular {
            return Vec3::ZERO;
        }
        let scene = self.scene;
        let s = sh.surface;
        let method = scene.settings.light_sampling;
        let mut l = Vec3::ZERO;
        for (light_index, light) in scene.lights.iter().enumerate() {
            let m_samples = if light.is_area() {
                scene.settings.shadow_samples
            } else {
                1
            };
            let dim = Dim::light(depth, light_index as u32);
            let except = light.prim().unwrap_or(u32::MAX);
            // Where a batch may be traced as a packet, shadow rays wait in
            // `batch` and are traced PACKET_SIZE at a time; else each is
            // traced at once. Contributions are added in sample order either way.
            let full = (m_samples as usize).min(PACKET_SIZE);
            let mut batch = self
                .packets
                .use_packet(full, SHADOW_PACKET_MIN)
                .then(ShadowBatch::default);
            let mut sum = Vec3::ZERO;
            for j in 0..m_samples {
                let u = if light.is_area() {
                    ctx.sampler
                        .get_2d(dim, ctx.index() * m_samples + j, ctx.count() * m_samples)
                } else {
                    Vec2::ZERO
                };
                let Some(ls) = light.sample(s.p, u, method) else {
                    continue;
                };
                let cos_i = sh.ns.dot(ls.wi);
                // Both normals must agree that the light is in front, or shading normals leak light.
                if cos_i <= 0.0 || sh.ng.dot(ls.wi) <= 0.0 {
                    continue;
                }
                let f = phong_brdf(m, sh.wo, ls.wi, sh.ns, diffuse, specular);
                if f.max_element() <= 0.0 {
                    continue;
                }
                self.counts.shadow += 1;
                let origin = spawn_origin(s.p, s.p_error, sh.ng, ls.wi);
                let tmax = if ls.distance.is_finite() {
                    (ls.distance - (origin - s.p).length()).max(0.0)
                } else {
                    f32::INFINITY
                };
                let shadow = Ray::segment(origin, ls.wi, tmax);
                match &mut batch {
                    Some(b) => {
                        b.rays[b.len] = shadow;
                        b.contribution[b.len] = f * ls.weight * cos_i;
                        b.len += 1;
                        if b.len == PACKET_SIZE {
                            self.flush_shadows(b, except, &mut sum);
                        }
                    }
                    None => {
                        if !scene.geometry.occluded_except(&shadow, except) {
                            sum += f * ls.weight * cos_i;
                        }
                    }
                }
            }
            if let Some(b) = &mut batch {
                self.flush_shadows(b, except, &mut sum);
            }
            l += sum / m_samples as f32;
        }
        l
    }

    /// Trace the waiting shadow rays (ignoring primitive `except`, the
    /// light's own surface) and add the contributions of those that reach
    /// the light to `sum`, in order.
    fn flush_shadows(&mut self, batch: &mut ShadowBatch, except: u32, sum: &mut Vec3) {
        let n = batch.len;
        if n == 0 {
            return;
        }
        let rays = &batch.rays[..n];
        let mut blocked = [false; PACKET_SIZE];
        if self.packets.use_packet(n, SHADOW_PACKET_MIN) {
            self.scene
                .geometry
                .occluded_packet(rays, except, &mut blocked[..n]);
        } else {
            for (b, r) in blocked.iter_mut().zip(rays) {
                *b = self.scene.geometry.occluded_except(r, except);
            }
        }
        for (c, b) in batch.contribution[..n].iter().zip(&blocked) {
            if !b {
                *sum += *c;
            }
        }
        batch.len = 0;
    }

    /// Mirror (or glossy) reflection and refraction.
    fn specular_transport(
        &mut self,
        ctx: &SampleContext,
        sh: &Shading,
        depth: u32,
        weight: f32,
    ) -> Vec3 {
        let (m, s, wo, ng, ns) = (sh.material, sh.surface, sh.wo, sh.ng, sh.ns);
        let mut kr = m.reflectivity;
        let mut kt = m.transparency;
        let mut refracted = None;
        if kt > 0.0 {
            let eta = if sh.entering { 1.0 / m.ior } else { m.ior };
            match refract(wo, ns, eta) {
                Some(t) => {
                    if m.fresnel {
                        let f = schlick(wo.dot(ns), if sh.entering { m.ior } else { 1.0 / m.ior });
                        kr += kt * f;
                        kt *= 1.0 - f;
                    }
                    refracted = Some(t);
                }
                None => {
                    // Total internal reflection: all transmitted energy reflects.
                    kr += kt;
                    kt = 0.0;
                }
            }
        }
        let mut l = Vec3::ZERO;
        if kr > 0.0 && weight * kr >= MIN_PATH_WEIGHT {
            let mirror = 2.0 * ns.dot(wo) * ns - wo;
            if m.glossiness > 0.0 {
                l += kr * self.glossy(ctx, s, m.glossiness, mirror, ng, depth, weight * kr);
            } else if mirror.dot(ng) > 0.0 {
                self.counts.reflection += 1;
                let ray = Ray::new(spawn_origin(s.p, s.p_error, ng, mirror), mirror);
                l += kr * self.radiance(ctx, &ray, depth + 1, weight * kr, "reflection");
            }
        }
        if let Some(dir) = refracted {
            if kt > 0.0 && weight * kt >= MIN_PATH_WEIGHT {
                self.counts.refraction += 1;
                let ray = Ray::new(spawn_origin(s.p, s.p_error, ng, dir), dir);
                l += kt * self.radiance(ctx, &ray, depth + 1, weight * kt, "refraction");
            }
        }
        l
    }

    /// Lobe-weighted average of incoming radiance around `mirror`, with K
    /// branches at the first glossy hit of the path and one ray after that.
    #[allow(clippy::too_many_arguments)]
    fn glossy(
        &mut self,
        ctx: &SampleContext,
        s: &Surface,
        exponent: f32,
        mirror: Vec3,
        ng: Vec3,
        depth: u32,
        weight: f32,
    ) -> Vec3 {
        let k = if ctx.branches == 1 {
            self.scene.settings.reflection_samples
        } else {
            1
        };
        let lobe = Frame::from_z(mirror);
        let hemisphere = Frame::from_z(ng);
        let mut sum = Vec3::ZERO;
        for b in 0..k {
            let child = if k > 1 {
                SampleContext {
                    branch: b,
                    branches: k,
                    ..*ctx
                }
            } else {
                *ctx
            };
            let u = ctx
                .sampler
                .get_2d(Dim::glossy(depth), child.index(), child.count());
            let (dir, w) = match self.scene.settings.glossy_sampling {
                GlossySampling::Lobe => (lobe.to_world(phong_lobe(u, exponent)), 1.0),
                GlossySampling::Uniform => {
                    let d = hemisphere.to_world(uniform_hemisphere(u));
                    // Lobe density over the uniform density 1/(2π).
                    (d, phong_lobe_pdf(d.dot(mirror), exponent) * 2.0 * PI)
                }
            };
            if dir.dot(ng) <= 0.0 {
                self.counts.glossy_rejected += 1;
                continue;
            }
            if !(w > 0.0) {
                continue;
            }
            self.counts.reflection += 1;
            let ray = Ray::new(spawn_origin(s.p, s.p_error, ng, dir), dir);
            sum += w * self.radiance(&child, &ray, depth + 1, weight, "glossy");
        }
        sum / k as f32
    }
}

/// Shadow rays from one hit point towards one light, waiting to be traced,
/// with what each adds if it reaches the light.
struct ShadowBatch {
    rays: [Ray; PACKET_SIZE],
    contribution: [Vec3; PACKET_SIZE],
    len: usize,
}

impl Default for ShadowBatch {
    fn default() -> Self {
        Self {
            rays: [Ray::new(Vec3::ZERO, Vec3::Z); PACKET_SIZE],
            contribution: [Vec3::ZERO; PACKET_SIZE],
            len: 0,
        }
    }
}

/// ρ/π + k_s (n+2)/(2π) cosⁿα, α between the mirror of `wi` and `wo`.
#[inline]
fn phong_brdf(m: &Material, wo: Vec3, wi: Vec3, n: Vec3, diffuse: bool, specular: bool) -> Vec3 {
    let mut f = if diffuse { m.diffuse / PI } else { Vec3::ZERO };
    if specular {
        let r = 2.0 * n.dot(wi) * n - wi;
        let cos_a = r.dot(wo);
        if cos_a > 0.0 {
            f += m.specular * ((m.shininess + 2.0) / (2.0 * PI) * cos_a.powf(m.shininess));
        }
    }
    f
}

/// Snell's law: the refracted direction of `wo` (pointing away from the
/// surface, on the side of `n`) for relative index `eta` = n_outside/n_inside,
/// or `None` on total internal reflection.
pub fn refract(wo: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = n.dot(wo);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-eta * wo + (eta * cos_i - cos_t) * n).normalize())
}

/// Schlick 1994, "An Inexpensive BRDF Model for Physically-based
/// Rendering": F = F0 + (1 − F0)(1 − cosθ)⁵, for relative index `ior`.
pub fn schlick(cos_i: f32, ior: f32) -> f32 {
    let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
    f0 + (1.0 - f0) * (1.0 - cos_i.clamp(0.0, 1.0)).powi(5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snell_bends_towards_the_normal_and_reflects_totally_past_the_critical_angle() {
        let n = Vec3::Y;
        let theta = 30f32.to_radians();
        let wo = Vec3::new(theta.sin(), theta.cos(), 0.0);
        let t = refract(wo, n, 1.0 / 1.5).unwrap();
        let sin_t = t.x.abs();
        assert!((sin_t - theta.sin() / 1.5).abs() < 1e-6);
        assert!(
            t.y < 0.0 && t.x < 0.0,
            "goes through, on the other side of the normal"
        );
        // From inside glass at 60° (> critical 41.8°).
        let theta = 60f32.to_radians();
        let wo = Vec3::new(theta.sin(), theta.cos(), 0.0);
        assert!(refract(wo, n, 1.5).is_none());
    }

    #[test]
    fn schlick_matches_normal_incidence_and_grazing_limits() {
        assert!((schlick(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((schlick(0.0, 1.5) - 1.0).abs() < 1e-6);
    }
}
