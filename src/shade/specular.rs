//! Specular transport: the mirror ray (or, on a glossy surface, rays
//! importance-sampled from the cosⁿ lobe) and the refracted ray.

use super::bsdf::mirror_and_glass;
use super::integrator::{Shading, MIN_PATH_WEIGHT};
use super::{Integrator, SampleContext};
use crate::geometry::Surface;
use crate::light::Environment;
use crate::math::offset::spawn_origin;
use crate::math::{Frame, Ray};
use crate::sampling::mis::power_heuristic;
use crate::sampling::warp::{phong_lobe, phong_lobe_pdf, uniform_hemisphere};
use crate::sampling::Dim;
use crate::scene::settings::GlossySampling;
use glam::Vec3;
use std::f32::consts::PI;

impl Integrator<'_> {
    /// Mirror (or glossy) reflection and refraction.
    pub(super) fn specular_transport(
        &mut self,
        ctx: &SampleContext,
        sh: &Shading,
        depth: u32,
        weight: f32,
    ) -> Vec3 {
        let (m, s, wo, ng, ns) = (sh.material, sh.surface, sh.wo, sh.ng, sh.ns);
        let (kr, kt, refracted) = mirror_and_glass(m, wo, ns, sh.entering);
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
    ///
    /// Under an environment map, each branch also draws one direction from
    /// the map, and the two strategies' estimates of the environment's
    /// share are combined by multiple importance sampling with the power
    /// heuristic (Veach and Guibas 1995, "Optimally Combining Sampling
    /// Techniques for Monte Carlo Rendering"): the lobe's ray counts what
    /// it sees of the environment with weight p_lobe² / (p_lobe² + p_env²),
    /// the map's direction (one occlusion ray to infinity) with
    /// p_env² / (p_lobe² + p_env²). The lobe alone finds a small bright sun
    /// rarely, the map alone a sharp lobe rarely. Light that the lobe's
    /// ray finds on a surface is the lobe's alone. A constant environment
    /// is sampled by the lobe alone: there the lobe's density is
    /// proportional to the integrand already.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn glossy(
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
        let settings = &self.scene.settings;
        let (glossy_sampling, light_sampling) = (settings.glossy_sampling, settings.light_sampling);
        let map = self.environment.filter(|e| e.has_map());
        // The density of the lobe's strategy for direction `d`.
        let lobe_pdf = |d: Vec3| match glossy_sampling {
            GlossySampling::Lobe => phong_lobe_pdf(d.dot(mirror), exponent),
            GlossySampling::Uniform => 0.5 / PI,
        };
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
            if let Some(env) = map {
                sum += self.glossy_environment(
                    &child,
                    env,
                    s,
                    (exponent, mirror, ng),
                    depth,
                    &lobe_pdf,
                );
            }
            let (dir, w) = match glossy_sampling {
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
            let escape = match map {
                Some(env) => power_heuristic(lobe_pdf(dir), env.pdf(None, dir, light_sampling)),
                None => 1.0,
            };
            sum += w * self.radiance_escaping(&child, &ray, depth + 1, weight, escape);
        }
        sum / k as f32
    }

    /// One branch's draw from the environment map `env` for the glossy
    /// lobe (`exponent` around `mirror`, above `ng`) at `s`: the lobe's
    /// density times the radiance over the map's density, times the map's
    /// power-heuristic weight against `lobe_pdf`, if nothing blocks the
    /// direction.
    fn glossy_environment(
        &mut self,
        ctx: &SampleContext,
        env: &Environment,
        s: &Surface,
        (exponent, mirror, ng): (f32, Vec3, Vec3),
        depth: u32,
        lobe_pdf: &impl Fn(Vec3) -> f32,
    ) -> Vec3 {
        let method = self.scene.settings.light_sampling;
        let u = ctx
            .sampler
            .get_2d(Dim::glossy_environment(depth), ctx.index(), ctx.count());
        let Some(e) = env.sample(None, u, method) else {
            return Vec3::ZERO;
        };
        let lobe = phong_lobe_pdf(e.wi.dot(mirror), exponent);
        if e.wi.dot(ng) <= 0.0 || !(lobe > 0.0) || e.radiance.max_element() <= 0.0 {
            return Vec3::ZERO;
        }
        let l = e.radiance * (lobe / e.pdf * power_heuristic(e.pdf, lobe_pdf(e.wi)));
        if !l.is_finite() {
            return Vec3::ZERO;
        }
        self.counts.shadow += 1;
        let ray = Ray::new(spawn_origin(s.p, s.p_error, ng, e.wi), e.wi);
        if self.scene.geometry.occluded(&ray) {
            Vec3::ZERO
        } else {
            l
        }
    }
}
