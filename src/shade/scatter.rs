//! The BSDF the path integrator shades a hit with: evaluated for light
//! samples, sampled for the path's next direction, with the density of
//! each for multiple importance sampling.
//!
//! **Phong keys.** A Phong material reads as a mix of lobes, each of which
//! conserves energy alone: Lambert's ρ/π (`diffuse`); the normalised Phong
//! lobe k_s (n+2)/(2π) cosⁿα of the highlight (`specular`, `shininess`;
//! Lafortune and Willems 1994); a fuzzy reflection of the same form with
//! weight k_r and exponent g (`reflectivity`, `glossiness` > 0), or a
//! mirror (glossiness 0); glass (`transparency`, `ior`, `fresnel`: Snell's
//! law, with Schlick's Fresnel moving weight from the refraction to the
//! mirror, and total internal reflection all of it). Where a channel's
//! ρ + k_s + k_r + k_t passes 1, every weight is scaled down so that it is
//! 1: no surface reflects more than it receives.
//!
//! **Metallic-roughness** ([`crate::material::MetallicRoughness`], glTF
//! 2.0 Appendix B): f = (1 − F(wi))(1 − F(wo)) c_diff/π + F D G₂ /
//! (4 |n·wi| |n·wo|), with c_diff = base (1 − metallic), F Schlick's with
//! F0 = mix(0.04, base, metallic) (at the half vector in the coat; at
//! each direction's own angle for the base, where glTF writes 1 − F at
//! the half vector: that sum reflects more than arrives at grazing
//! angles), D GGX with α = roughness², G₂ Smith's height-correlated
//! ([`super::microfacet`]). Sampled by picking the
//! specular lobe with the chance of its Fresnel weight at wo, then a
//! visible normal (Heitz 2018); else the cosine hemisphere.

use super::bsdf::mirror_and_glass;
use super::microfacet::{
    ggx_d, ggx_g2, reflected_pdf, sample_visible_normal, schlick_rgb, MIN_ALPHA,
};
use crate::material::{Material, MetallicRoughness};
use crate::math::Frame;
use crate::sampling::warp::{phong_lobe, phong_lobe_pdf};
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, PI};

/// A direction drawn from the BSDF.
#[derive(Debug, Clone, Copy)]
pub struct BsdfSample {
    pub wi: Vec3,
    /// f · |cos θ_i| / pdf: what the path's throughput is multiplied by.
    pub weight: Vec3,
    /// The density it was drawn with (per steradian); 0 for a delta lobe.
    pub pdf: f32,
    /// Drawn from a mirror or glass lobe: no light sample could find it.
    pub delta: bool,
}

/// One hit's BSDF, its lobes' weights worked out once.
#[derive(Debug, Clone, Copy)]
pub struct Bsdf {
    /// z the shading normal, turned towards wo.
    frame: Frame,
    /// The geometric normal, turned towards wo.
    ng: Vec3,
    /// wo in the local frame.
    wo: Vec3,
    lobes: Lobes,
}

#[derive(Debug, Clone, Copy)]
enum Lobes {
    /// A Phong material with no lobe but the diffuse one (every wall of
    /// cornell-planes, dragon-gold's floor): the few numbers that
    /// [`Phong`]'s sample and eval read of it, worked out as it would.
    Lambert(Lambert),
    Phong(Phong),
    MetallicRoughness(Microfacet),
}

/// What a [`Phong`] whose weights other than ρ are all zero reads: ρ
/// after the energy scale, and the sum of its weights (its `cdf`'s every
/// entry). Built, sampled and evaluated with the same operations in the
/// same order as [`Phong`], so every number is bit for bit the same
/// (`scatter_tests`), with a fifth of the bytes to write: the vertex's
/// BSDF was the largest part of building a vertex.
#[derive(Debug, Clone, Copy)]
struct Lambert {
    diffuse: Vec3,
    total: f32,
}

#[derive(Debug, Clone, Copy)]
struct Phong {
    diffuse: Vec3,
    specular: Vec3,
    shininess: f32,
    glossy: f32,
    glossiness: f32,
    mirror: f32,
    transmit: f32,
    /// wi of the refraction, where there is one (world space).
    refracted: Option<Vec3>,
    /// Cumulative chances of diffuse, highlight, glossy, mirror, glass.
    cdf: [f32; 5],
}

#[derive(Debug, Clone, Copy)]
struct Microfacet {
    c_diff: Vec3,
    f0: Vec3,
    alpha: f32,
    /// The chance of drawing from the specular lobe.
    p_spec: f32,
}

/// The mean of the three channels: how lobes are weighed for sampling.
fn mean(c: Vec3) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

impl Bsdf {
    /// The BSDF of `m` at a hit seen along `wo` (unit, away from the
    /// surface), with normals `ng`, `ns` turned towards `wo`; `entering`
    /// when wo is on the outside; `texel` what the texture says there (1
    /// without one): it multiplies ρ, or the base colour.
    #[inline(always)]
    pub fn new(m: &Material, texel: Vec3, wo: Vec3, ng: Vec3, ns: Vec3, entering: bool) -> Self {
        Self::build(m, texel, wo, ng, ns, entering, true)
    }

    /// Whether this BSDF holds its lobes as [`Lambert`].
    #[cfg(test)]
    pub(super) fn is_lambert(&self) -> bool {
        matches!(self.lobes, Lobes::Lambert(_))
    }

    /// [`Bsdf::new`], with a Lambertian Phong material held as [`Lambert`]
    /// where `lambert` says so, else as the general Phong mix (what the
    /// tests compare [`Lambert`] with).
    #[inline(always)]
    pub(super) fn build(
        m: &Material,
        texel: Vec3,
        wo: Vec3,
        ng: Vec3,
        ns: Vec3,
        entering: bool,
        lambert: bool,
    ) -> Self {
        let frame = Frame::from_z(ns);
        let wo_local = to_local(&frame, wo);
        // Each kind of lobes writes only its own fields: one write of
        // the whole enum after the match wrote every Phong field, a
        // Lambertian BSDF's too.
        let with = |lobes| Self {
            frame,
            ng,
            wo: wo_local,
            lobes,
        };
        match m.pbr {
            Some(pbr) => with(Lobes::MetallicRoughness(Microfacet::new(
                &pbr, texel, wo_local,
            ))),
            None if lambert && Lambert::fits(m) => with(Lobes::Lambert(Lambert::new(m, texel))),
            None => with(Lobes::Phong(Phong::new(m, texel, wo, ns, entering))),
        }
    }

    /// Whether any lobe can be lit by a light sample (not only mirror or glass).
    pub fn has_smooth_lobe(&self) -> bool {
        match &self.lobes {
            Lobes::Lambert(l) => l.total > 0.0,
            Lobes::Phong(p) => p.cdf[2] > 0.0,
            Lobes::MetallicRoughness(_) => true,
        }
    }

    /// cos θ_i against the shading normal.
    pub fn cos(&self, wi: Vec3) -> f32 {
        self.frame.z.dot(wi)
    }

    /// f(wo, wi) and the density [`Bsdf::sample`] draws `wi` with (world
    /// space, unit); zero below the surface, where both normals must
    /// agree that `wi` is above it.
    // Inlined, with the Lambertian lobe: called with the direction just
    // written by a light's sample, a call read it back from memory before
    // the stores had landed (a third of the call's time). The other lobes
    // stay calls of their own.
    #[inline(always)]
    pub fn eval(&self, wi: Vec3) -> (Vec3, f32) {
        if self.ng.dot(wi) <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let wi = to_local(&self.frame, wi);
        if wi.z <= 0.0 || self.wo.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        match &self.lobes {
            Lobes::Lambert(l) => l.eval(wi),
            Lobes::Phong(p) => p.eval(self.wo, wi),
            Lobes::MetallicRoughness(m) => m.eval(self.wo, wi),
        }
    }

    /// A direction drawn with `choice` (picks the lobe) and `u`, both
    /// uniform; `None` where the lobe's direction falls below the surface
    /// or nothing scatters.
    // Inlined, with the Lambertian lobe, as `eval`: returned through
    // memory, the sample was read back before its stores had landed.
    #[inline(always)]
    pub fn sample(&self, choice: f32, u: Vec2) -> Option<BsdfSample> {
        match &self.lobes {
            Lobes::Lambert(l) => {
                // Phong's draw of its first lobe; x past it (a choice
                // that rounds up to the total) finds no other lobe.
                let total = l.total;
                if !(total > 0.0) {
                    return None;
                }
                let x = choice * total;
                if !(x < total) {
                    return None;
                }
                self.lambert_sample(l, cosine_hemisphere(u))
            }
            Lobes::Phong(p) => self.sample_phong(p, choice, u),
            Lobes::MetallicRoughness(m) => self.sample_microfacet(m, choice, u),
        }
    }

    #[inline(never)]
    fn sample_microfacet(&self, m: &Microfacet, choice: f32, u: Vec2) -> Option<BsdfSample> {
        if self.wo.z <= 0.0 {
            return None;
        }
        let wi = if choice < m.p_spec {
            let h = sample_visible_normal(self.wo, m.alpha, u);
            2.0 * self.wo.dot(h) * h - self.wo
        } else {
            cosine_hemisphere(u)
        };
        self.smooth_sample(self.frame.to_world(wi))
    }

    /// The sample of a smooth lobe's direction `wi`: the whole BSDF and
    /// its whole density there (one-sample MIS over the lobes).
    fn smooth_sample(&self, wi: Vec3) -> Option<BsdfSample> {
        let (f, pdf) = self.eval(wi);
        if !(pdf > 0.0) {
            return None;
        }
        let weight = f * (self.frame.z.dot(wi) / pdf);
        weight.is_finite().then_some(BsdfSample {
            wi,
            weight,
            pdf,
            delta: false,
        })
    }

    /// A cosine-weighted direction `local` (in the shading frame) of a
    /// [`Lambert`] BSDF: f·cos/pdf is ρ exactly, and the density cos/π,
    /// without [`Bsdf::eval`]'s work; `None` where `local` (or the view)
    /// is not above both normals, as [`Bsdf::eval`] would find it.
    #[inline(always)]
    fn lambert_sample(&self, l: &Lambert, local: Vec3) -> Option<BsdfSample> {
        let wi = self.frame.to_world(local);
        if !(local.z > 0.0 && self.wo.z > 0.0 && self.ng.dot(wi) > 0.0) {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: l.diffuse,
            pdf: local.z * FRAC_1_PI,
            delta: false,
        })
    }

    #[inline(never)]
    fn sample_phong(&self, p: &Phong, choice: f32, u: Vec2) -> Option<BsdfSample> {
        let total = p.cdf[4];
        if !(total > 0.0) {
            return None;
        }
        let x = choice * total;
        let ns = self.frame.z;
        let wo = self.frame.to_world(self.wo);
        let mirror = 2.0 * ns.dot(wo) * ns - wo;
        if x < p.cdf[0] {
            return self.smooth_sample(self.frame.to_world(cosine_hemisphere(u)));
        }
        if x < p.cdf[1] {
            let lobe = Frame::from_z(mirror).to_world(phong_lobe(u, p.shininess));
            return self.smooth_sample(lobe);
        }
        if x < p.cdf[2] {
            let lobe = Frame::from_z(mirror).to_world(phong_lobe(u, p.glossiness));
            return self.smooth_sample(lobe);
        }
        if x < p.cdf[3] {
            if mirror.dot(self.ng) <= 0.0 {
                return None;
            }
            let chance = (p.cdf[3] - p.cdf[2]) / total;
            return Some(BsdfSample {
                wi: mirror,
                weight: Vec3::splat(p.mirror / chance),
                pdf: 0.0,
                delta: true,
            });
        }
        let wi = p.refracted?;
        let chance = (p.cdf[4] - p.cdf[3]) / total;
        Some(BsdfSample {
            wi,
            weight: Vec3::splat(p.transmit / chance),
            pdf: 0.0,
            delta: true,
        })
    }
}

impl Lambert {
    /// Whether [`Phong::new`] would give `m` no weight but ρ's: no
    /// highlight, reflection or glass.
    fn fits(m: &Material) -> bool {
        (m.specular == Vec3::ZERO || m.shininess < 0.0)
            && m.reflectivity == 0.0
            && m.transparency == 0.0
    }

    /// [`Phong::new`]'s arithmetic for such a material: its energy scale
    /// and its cumulative weights, every one of which is ρ's mean.
    fn new(m: &Material, texel: Vec3) -> Self {
        let diffuse = m.diffuse * texel;
        let sum =
            (diffuse + m.specular + Vec3::splat(m.reflectivity + m.transparency)).max_element();
        let scale = if sum > 1.0 { 1.0 / sum } else { 1.0 };
        // Phong's running sum: 0 + max(w, 0), then + 0 four times.
        let total = 0.0 + mean(diffuse * scale).max(0.0);
        Self {
            diffuse: diffuse * scale,
            total,
        }
    }

    /// [`Phong::eval`] with its highlight and glossy lobes of no chance.
    #[inline(always)]
    fn eval(&self, wi: Vec3) -> (Vec3, f32) {
        let f = self.diffuse * FRAC_1_PI;
        (
            f,
            if self.total > 0.0 {
                wi.z * FRAC_1_PI
            } else {
                0.0
            },
        )
    }
}

impl Phong {
    fn new(m: &Material, texel: Vec3, wo: Vec3, ns: Vec3, entering: bool) -> Self {
        // The mirror and glass weights after Fresnel and total internal
        // reflection, as the distribution integrator splits them.
        let (kr, kt, refracted) = mirror_and_glass(m, wo, ns, entering);
        let diffuse = m.diffuse * texel;
        // Energy conservation: the weights of the brightest channel sum to at most 1.
        let sum =
            (diffuse + m.specular + Vec3::splat(m.reflectivity + m.transparency)).max_element();
        let scale = if sum > 1.0 { 1.0 / sum } else { 1.0 };
        let (glossy, mirror) = if m.glossiness > 0.0 {
            (kr * scale, 0.0)
        } else {
            (0.0, kr * scale)
        };
        let specular = if m.shininess >= 0.0 {
            m.specular * scale
        } else {
            Vec3::ZERO
        };
        let weights = [
            mean(diffuse * scale),
            mean(specular),
            glossy,
            mirror,
            if refracted.is_some() { kt * scale } else { 0.0 },
        ];
        let mut cdf = [0.0; 5];
        let mut running = 0.0;
        for (c, w) in cdf.iter_mut().zip(weights) {
            running += w.max(0.0);
            *c = running;
        }
        Self {
            diffuse: diffuse * scale,
            specular,
            shininess: m.shininess,
            glossy,
            glossiness: m.glossiness,
            mirror,
            transmit: kt * scale,
            refracted,
            cdf,
        }
    }

    /// Local wo and wi, both above.
    #[inline(never)]
    fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let total = self.cdf[4];
        let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
        let cos_a = wi.dot(mirror);
        let mut f = self.diffuse * FRAC_1_PI;
        let mut pdf = self.cdf[0] * wi.z * FRAC_1_PI;
        for (k, weight, n) in [
            (1, self.specular, self.shininess),
            (2, Vec3::splat(self.glossy), self.glossiness),
        ] {
            let chance = self.cdf[k] - self.cdf[k - 1];
            if chance > 0.0 && cos_a > 0.0 {
                let c = cos_a.powf(n);
                f += weight * ((n + 2.0) / (2.0 * PI) * c);
                pdf += chance * phong_lobe_pdf(cos_a, n);
            }
        }
        (f, if total > 0.0 { pdf / total } else { 0.0 })
    }
}

impl Microfacet {
    fn new(m: &MetallicRoughness, texel: Vec3, wo: Vec3) -> Self {
        let base = m.base_color * texel;
        let c_diff = base * (1.0 - m.metallic);
        let f0 = Vec3::splat(0.04).lerp(base, m.metallic);
        let alpha = (m.roughness * m.roughness).max(MIN_ALPHA);
        let fo = schlick_rgb(f0, wo.z);
        let (spec, diff) = (mean(fo), mean(c_diff * (Vec3::ONE - fo)));
        let p_spec = if diff > 0.0 {
            (spec / (spec + diff)).clamp(0.05, 1.0)
        } else {
            1.0
        };
        Self {
            c_diff,
            f0,
            alpha,
            p_spec,
        }
    }

    /// Local wo and wi, both above.
    #[inline(never)]
    fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let h = (wo + wi).normalize();
        let f = schlick_rgb(self.f0, wo.dot(h));
        let spec = f * (ggx_d(h, self.alpha) * ggx_g2(wo, wi, self.alpha) / (4.0 * wi.z * wo.z));
        // The base under the coat: what Fresnel lets in at wi and out at
        // wo (not glTF's 1 − F at the half vector, whose sum with the
        // coat reflects 4.5% more than arrives at 80° for a white rough
        // dielectric; scatter_tests). Symmetric, so still reciprocal.
        let through =
            (Vec3::ONE - schlick_rgb(self.f0, wi.z)) * (Vec3::ONE - schlick_rgb(self.f0, wo.z));
        let diff = through * self.c_diff * FRAC_1_PI;
        let pdf = self.p_spec * reflected_pdf(wo, wi, self.alpha)
            + (1.0 - self.p_spec) * wi.z * FRAC_1_PI;
        (spec + diff, pdf)
    }
}

/// Cosine-weighted about +z (Malley's method), density cosθ/π.
fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = crate::sampling::warp::concentric_disk(u);
    Vec3::new(d.x, d.y, (1.0 - d.length_squared()).max(0.0).sqrt())
}

fn to_local(frame: &Frame, v: Vec3) -> Vec3 {
    Vec3::new(frame.x.dot(v), frame.y.dot(v), frame.z.dot(v))
}
