//! Direct light: one shadow ray per delta light and `shadow_samples`
//! stratified samples per area light, each weighted by the Phong BRDF.

use super::bsdf::phong_brdf;
use super::integrator::Shading;
use super::packets::SHADOW_PACKET_MIN;
use super::{Integrator, SampleContext};
use crate::accel::PACKET_SIZE;
use crate::math::offset::spawn_origin;
use crate::math::Ray;
use crate::sampling::Dim;
use glam::{Vec2, Vec3};

impl Integrator<'_> {
    /// Phong direct lighting: one shadow ray per delta light, M stratified
    /// samples per area light.
    pub(super) fn direct_light(&mut self, ctx: &SampleContext, depth: u32, sh: &Shading) -> Vec3 {
        let m = sh.material;
        let diffuse = sh.diffuse.max_element() > 0.0;
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
            // A light all of whose samples would be rejected below is
            // skipped whole (same image: the draws are counter-based).
            if light.hidden_from(s.p, sh.ng) {
                continue;
            }
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
            // What every sample of this light from this point shares (the
            // spherical rectangle of a rect light), built once.
            let seen = light.seen_from(s.p, method);
            for j in 0..m_samples {
                let u = if light.is_area() {
                    ctx.sampler
                        .get_2d(dim, ctx.index() * m_samples + j, ctx.count() * m_samples)
                } else {
                    Vec2::ZERO
                };
                let Some(ls) = seen.sample(u) else {
                    continue;
                };
                let cos_i = sh.ns.dot(ls.wi);
                // Both normals must agree that the light is in front, or shading normals leak light.
                if cos_i <= 0.0 || sh.ng.dot(ls.wi) <= 0.0 {
                    continue;
                }
                let f = phong_brdf(m, sh.diffuse, sh.wo, ls.wi, sh.ns, diffuse, specular);
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
