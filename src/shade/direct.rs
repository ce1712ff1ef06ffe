//! Direct light: one shadow ray per delta light and `shadow_samples`
//! stratified samples per area light, each weighted by the Phong BRDF.
//!
//! The hit points of one batch of camera samples are lit together, one
//! SIMD lane each ([`Light::seen_from_lanes`]): building and sampling a
//! rect light's spherical rectangle is a chain of dependent divisions and
//! square roots, and eight lanes run eight chains at once. Every lane's
//! numbers are exactly those of lighting its point alone.
//!
//! [`Light::seen_from_lanes`]: crate::light::Light::seen_from_lanes

use super::bsdf::phong_brdf;
use super::integrator::{ShadeLane, Shading};
use super::packets::SHADOW_PACKET_MIN;
use super::Integrator;
use crate::accel::PACKET_SIZE;
use crate::math::offset::spawn_origin;
use crate::math::Ray;
use crate::sampling::spherical_rect8::{mask_lanes, LANES};
use crate::sampling::Dim;
use glam::{Vec2, Vec3};

// A batch of camera samples is one lane of light sampling per sample.
const _: () = assert!(PACKET_SIZE == LANES);

impl Integrator<'_> {
    /// Phong direct lighting at each lane's hit (`shadings[i]` for
    /// `lanes[i]`; `None` where the ray hit nothing): one shadow ray per
    /// delta light, M stratified samples per area light.
    pub(super) fn direct_light(
        &mut self,
        depth: u32,
        lanes: &[ShadeLane],
        shadings: &[Option<Shading>],
    ) -> [Vec3; LANES] {
        let mut l = [Vec3::ZERO; LANES];
        // The lanes whose material has a lobe that direct light reaches.
        let mut lit = 0u32;
        let mut lobes = [(false, false); LANES];
        let mut points = [Vec3::ZERO; LANES];
        for (i, sh) in shadings.iter().enumerate().take(lanes.len()) {
            let Some(sh) = sh else { continue };
            let diffuse = sh.diffuse.max_element() > 0.0;
            let specular = sh.material.has_specular_lobe();
            if diffuse || specular {
                lit |= 1 << i;
                lobes[i] = (diffuse, specular);
                points[i] = sh.surface.p;
            }
        }
        if lit == 0 {
            return l;
        }
        let scene = self.scene;
        let method = scene.settings.light_sampling;
        let shading = |i: usize| shadings[i].as_ref().expect("a lit lane has a hit");
        for (light_index, light) in scene.lights.iter().enumerate() {
            let m_samples = if light.is_area() {
                scene.settings.shadow_samples
            } else {
                1
            };
            // A light all of whose samples would be rejected below is
            // skipped whole (same image: the draws are counter-based).
            let mut active = 0u32;
            for i in mask_lanes(lit) {
                if !light.hidden_from(points[i], shading(i).ng) {
                    active |= 1 << i;
                }
            }
            if active == 0 {
                continue;
            }
            let dim = Dim::light(depth, light_index as u32);
            let except = light.prim().unwrap_or(u32::MAX);
            // Where a batch may be traced as a packet, each lane's shadow
            // rays wait in its `batches` slot and are traced PACKET_SIZE at
            // a time; else each is traced at once. Contributions are added
            // in sample order either way.
            let full = (m_samples as usize).min(PACKET_SIZE);
            let mut batches = self
                .packets
                .use_packet(full, SHADOW_PACKET_MIN)
                .then(|| std::array::from_fn::<ShadowBatch, LANES, _>(|_| ShadowBatch::default()));
            let mut sum = [Vec3::ZERO; LANES];
            // What every sample of this light from a point shares (a rect
            // light's spherical rectangle), built once per lane.
            let seen = light.seen_from_lanes(&points, active, method);
            let mut u = [Vec2::ZERO; LANES];
            for j in 0..m_samples {
                if light.is_area() {
                    for i in mask_lanes(active) {
                        let ctx = lanes[i].ctx;
                        u[i] = ctx.sampler.get_2d(
                            dim,
                            ctx.index() * m_samples + j,
                            ctx.count() * m_samples,
                        );
                    }
                }
                let samples = seen.sample(active, &u);
                for i in mask_lanes(active) {
                    let Some(ls) = samples[i] else {
                        continue;
                    };
                    let sh = shading(i);
                    let s = sh.surface;
                    let cos_i = sh.ns.dot(ls.wi);
                    // Both normals must agree that the light is in front, or shading normals leak light.
                    if cos_i <= 0.0 || sh.ng.dot(ls.wi) <= 0.0 {
                        continue;
                    }
                    let (diffuse, specular) = lobes[i];
                    let f = phong_brdf(
                        sh.material,
                        sh.diffuse,
                        sh.wo,
                        ls.wi,
                        sh.ns,
                        diffuse,
                        specular,
                    );
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
                    match &mut batches {
                        Some(b) => {
                            let b = &mut b[i];
                            b.rays[b.len] = shadow;
                            b.contribution[b.len] = f * ls.weight * cos_i;
                            b.len += 1;
                            if b.len == PACKET_SIZE {
                                self.flush_shadows(b, except, &mut sum[i]);
                            }
                        }
                        None => {
                            if !scene.geometry.occluded_except(&shadow, except) {
                                sum[i] += f * ls.weight * cos_i;
                            }
                        }
                    }
                }
            }
            for i in mask_lanes(active) {
                if let Some(b) = &mut batches {
                    self.flush_shadows(&mut b[i], except, &mut sum[i]);
                }
                l[i] += sum[i] / m_samples as f32;
            }
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
