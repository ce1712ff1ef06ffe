//! Direct light: one shadow ray per delta light and `shadow_samples`
//! stratified samples per area light, each weighted by the Phong BRDF.
//!
//! The hit points of one batch of camera samples are lit together, one
//! SIMD lane each ([`Light::seen_from_lanes`]): building and sampling a
//! rect light's spherical rectangle is a chain of dependent divisions and
//! square roots, and eight lanes run eight chains at once. Every lane's
//! numbers are exactly those of lighting its point alone.
//!
//! Their shadow rays are then the batch's shadow rays towards one light
//! sample: sample `j` of one light from every lane, gathered first and
//! traced back to back (a packet only under `--packets on`; see
//! [`BatchRays::auto`](crate::geometry::travel::BatchRays::auto)). Traced together rather than between the shading
//! of each hit, they leave one another's tree nodes in the caches (3–7%
//! off a render on one thread; docs/mitsuba.md, "What was tried for the
//! whole process"), and each lane still adds its contributions in sample
//! order.
//!
//! An environment light is drawn lane by lane with each hit's normal
//! ([`crate::light::Environment::light_sample`]); its shadow rays are
//! occlusion rays to infinity.
//!
//! A single hit lit with several samples of an area light (a reflected
//! or refracted ray's hit) would leave seven lanes idle, so its
//! samples fill the lanes instead, eight per round (docs/mitsuba.md,
//! "What was tried for the render").
//!
//! [`Light::seen_from_lanes`]: crate::light::Light::seen_from_lanes

use super::bsdf::phong_brdf;
use super::integrator::{ShadeLane, Shading};
use super::sample::draw_2d_lanes;
use super::{BatchRays, Integrator};
use crate::accel::PACKET_SIZE;
use crate::math::lanes::{mask_lanes, LANES};
use crate::math::offset::spawn_origin;
use crate::math::Ray;
use crate::sampling::Dim;
use glam::{Vec2, Vec3};

// A batch of camera samples is one lane of light sampling per sample.
const _: () = assert!(PACKET_SIZE == LANES);

/// The mask of every lane.
const ALL_LANES: u32 = u32::MAX >> (32 - LANES);

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
            let mut sum = [Vec3::ZERO; LANES];
            // The SIMD lanes hold either the batch's hits, one sample `j`
            // of each per round, or, where a single hit is lit with several
            // samples (a reflected or refracted ray's hit), that
            // hit's samples, eight per round. Each hit's contributions are
            // added in sample order either way, so the sums are the same.
            let one_hit = (active.count_ones() == 1 && m_samples > 1)
                .then(|| active.trailing_zeros() as usize);
            // What every sample of this light from a point shares (a rect
            // light's spherical rectangle), built once per lane.
            let seen = match one_hit {
                Some(h) => light.seen_from_lanes(&[points[h]; LANES], ALL_LANES, method),
                None => light.seen_from_lanes(&points, active, method),
            };
            let rounds = match one_hit {
                Some(_) => m_samples.div_ceil(LANES as u32),
                None => m_samples,
            };
            let mut shadow = ShadowRays::default();
            let mut u = [Vec2::ZERO; LANES];
            for round in 0..rounds {
                // The slots of this round, and each slot's hit and sample.
                let (slots, hit, j): (u32, [usize; LANES], [u32; LANES]) = match one_hit {
                    Some(h) => {
                        let first = round * LANES as u32;
                        let live = (m_samples - first).min(LANES as u32);
                        let j = std::array::from_fn(|k| first + k as u32);
                        (u32::MAX >> (32 - live), [h; LANES], j)
                    }
                    None => (active, std::array::from_fn(|k| k), [round; LANES]),
                };
                if light.is_area() {
                    let at = |k: usize| {
                        let ctx = lanes[hit[k]].ctx;
                        (ctx.index() * m_samples + j[k], ctx.count() * m_samples)
                    };
                    u = draw_2d_lanes(slots, |k| lanes[hit[k]].ctx, dim, at);
                }
                let samples = match light.environment() {
                    // An environment is drawn with each hit's normal (a
                    // constant one by the cosine about it), lane by lane:
                    // the same numbers alone or in a batch.
                    Some(env) => {
                        let mut out = [None; LANES];
                        for k in mask_lanes(slots) {
                            let ng = shading(hit[k]).ng;
                            out[k] = env.light_sample(Some(ng), u[k], method);
                        }
                        out
                    }
                    None => seen.sample(slots, &u),
                };
                shadow.len = 0;
                for k in mask_lanes(slots) {
                    let Some(ls) = samples[k] else {
                        continue;
                    };
                    let i = hit[k];
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
                    let n = shadow.len;
                    shadow.rays[n] = Ray::segment(origin, ls.wi, tmax);
                    shadow.contribution[n] = f * ls.weight * cos_i;
                    shadow.lane[n] = i as u8;
                    shadow.len += 1;
                }
                self.trace_shadow_rays(&shadow, except, &mut sum);
            }
            for i in mask_lanes(active) {
                l[i] += sum[i] / m_samples as f32;
            }
        }
        l
    }

    /// Trace one sample's shadow rays from every lane (ignoring primitive
    /// `except`, the light's own surface) and add the contributions of those
    /// that reach the light to their lanes' sums.
    fn trace_shadow_rays(&mut self, shadow: &ShadowRays, except: u32, sum: &mut [Vec3; LANES]) {
        let n = shadow.len;
        if n == 0 {
            return;
        }
        let rays = &shadow.rays[..n];
        let mut blocked = [false; PACKET_SIZE];
        if self.packets.use_packet(BatchRays::Shadow, n) {
            self.scene
                .geometry
                .occluded_packet(rays, except, &mut blocked[..n]);
        } else {
            // One ray at a time, not `occluded_stream`: these rays start
            // close together and head for one light, so they share cached
            // nodes and interleaving their walks only adds work
            // (docs/mitsuba.md, "What was tried for the render").
            for (b, r) in blocked.iter_mut().zip(rays) {
                *b = self.scene.geometry.occluded_except(r, except);
            }
        }
        for ((c, &lane), b) in shadow
            .contribution
            .iter()
            .zip(&shadow.lane)
            .zip(&blocked[..n])
        {
            if !b {
                sum[lane as usize] += *c;
            }
        }
    }
}

/// The shadow rays of a batch towards one light sample, one from each
/// lane's hit point (or, for a single hit, one per sample of the round),
/// waiting to be traced, with what each adds if it reaches the light.
struct ShadowRays {
    rays: [Ray; PACKET_SIZE],
    contribution: [Vec3; PACKET_SIZE],
    lane: [u8; PACKET_SIZE],
    len: usize,
}

impl Default for ShadowRays {
    fn default() -> Self {
        Self {
            rays: [Ray::new(Vec3::ZERO, Vec3::Z); PACKET_SIZE],
            contribution: [Vec3::ZERO; PACKET_SIZE],
            lane: [0; PACKET_SIZE],
            len: 0,
        }
    }
}
