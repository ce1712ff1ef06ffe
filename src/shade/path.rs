//! The path integrator (`integrator = "path"`): unidirectional path
//! tracing (Kajiya 1986, "The Rendering Equation") with next-event
//! estimation at every vertex and multiple importance sampling (Veach and
//! Guibas 1995) between light samples and the BSDF's own direction.
//!
//! At each vertex of a camera path:
//! 1. emitted radiance, weighed against the light sampling that could
//!    have found it (the power heuristic); the camera's and a mirror's or
//!    glass's rays (delta lobes) count it whole;
//! 2. next-event estimation: every light of the scene, and the glowing
//!    surfaces as one more ([`crate::light::emitters`]), is sampled
//!    `shadow_samples` times (a delta light once) and each sample is
//!    weighed by the power heuristic against the BSDF's density;
//! 3. a direction from the BSDF ([`super::scatter`]) continues the
//!    path; after [`ROULETTE_DEPTH`] bounces Russian roulette ends it with
//!    the chance that its throughput has fallen (Arvo and Kirk 1990).
//!
//! `max_depth` D bounds the bounces: vertices 0..=D take steps 1–3, and
//! vertex D + 1 adds only its emission (the BSDF's share of vertex D's
//! direct light), so light reflects at most D + 1 times; D = 0 is direct
//! light alone, as under the distribution integrator.
//!
//! Every number is drawn from the pixel's counter-based sampler, one
//! dimension per effect and depth ([`Dim::bounce`], [`Dim::lobe`],
//! [`Dim::roulette`], [`Dim::light`]), at the path's index in its sample
//! set: the image is the same for any thread count, slice, checkpoint or
//! noise target. Escaping rays see the environment (sampled as a light)
//! or the background (not sampled: it lights the scene as found).

use super::maps;
use super::sample::{CameraSample, FirstHit, SampleContext};
use super::scatter::Bsdf;
use super::Integrator;
use crate::accel::PrimHit;
use crate::light::environment::EnvSample;
use crate::light::{Light, LightSample, NO_PART};
use crate::math::offset::spawn_origin;
use crate::math::Ray;
use crate::sampling::mis::power_heuristic;
use crate::sampling::Dim;
use glam::{Vec2, Vec3};

/// Bounces after which Russian roulette may end a path: five, as
/// Mitsuba 3's `rr_depth`. Ending paths earlier saves time in closed
/// rooms whose walls reflect most of the light, but costs more noise than
/// the time buys back: on cornell-planes' walls, at equal render time,
/// three bounces gave 1.4 times the squared error of five
/// (docs/mitsuba.md, "When Russian roulette starts").
pub const ROULETTE_DEPTH: u32 = 5;

/// What the BSDF ray that reached a vertex was drawn with: what light
/// found along it is weighed by.
#[derive(Clone, Copy)]
pub(super) struct Came {
    /// The BSDF's density for the ray; `None` for the camera's ray and
    /// delta lobes, which no light sample can find.
    pdf: Option<f32>,
    /// The vertex it left, and its geometric normal faced towards the
    /// side it left from.
    from: Vec3,
    ng: Vec3,
}

impl Came {
    /// The camera's ray from `origin`.
    pub(super) fn camera(origin: Vec3) -> Self {
        Self {
            pdf: None,
            from: origin,
            ng: Vec3::ZERO,
        }
    }
}

/// A vertex to scatter from: its BSDF, its point with the point's
/// rounding bound, its geometric normal faced towards the viewer, and
/// the radiance it emits towards the viewer (MIS-weighed).
#[derive(Clone, Copy)]
pub(super) struct Vertex {
    pub(super) bsdf: Bsdf,
    pub(super) p: Vec3,
    pub(super) p_error: Vec3,
    pub(super) ng: Vec3,
    pub(super) emitted: Vec3,
}

/// What a path finds where its ray ends ([`Integrator::arrive`]).
pub(super) enum Arrival {
    /// The path ends there, bringing this radiance: an escaped ray (no
    /// point), or the vertex past the last bounce (its point).
    End(Vec3, Option<Vec3>),
    /// A vertex to light and scatter from.
    Scatter(Vertex),
}

/// One vertex's light sample, before its shadow ray.
pub(super) struct Contribution {
    wi: Vec3,
    /// To the point sampled (∞ for light from infinity).
    distance: f32,
    /// The primitive of the light's surface, which the shadow ray skips.
    pub(super) except: u32,
    pub(super) value: Vec3,
}

impl Integrator<'_> {
    /// Radiance of each camera sample of `batch` into `out` by path
    /// tracing; `first` as [`Integrator::camera_batch`] fills it.
    pub(super) fn path_batch(
        &mut self,
        batch: &[CameraSample],
        out: &mut [Vec3],
        mut first: Option<&mut [FirstHit]>,
    ) {
        if batch.len() == 1 || self.trace.is_some() {
            // One sample, or a replay, which records each path's
            // vertices in turn: each camera ray traced alone.
            for (i, sample) in batch.iter().enumerate() {
                let ray = self.camera_ray(&sample.ctx, sample.film);
                self.counts.camera += 1;
                let first_i = first.as_deref_mut().map(|f| &mut f[i]);
                out[i] = self.path(&sample.ctx, ray, None, first_i);
            }
            return;
        }
        // The camera rays together (coherent: one packet where it pays),
        // then the paths bounce by bounce together (`path_lanes`).
        let (rays, hits) = self.camera_hits(batch);
        self.path_lanes(batch, rays, hits, out, first);
    }

    /// The radiance a camera path starting with `ray` brings back;
    /// `camera_hit`, where given, is the ray's closest hit, already traced.
    fn path(
        &mut self,
        ctx: &SampleContext,
        mut ray: Ray,
        mut camera_hit: Option<Option<PrimHit>>,
        mut first: Option<&mut FirstHit>,
    ) -> Vec3 {
        let scene = self.scene;
        let (index, count) = (ctx.index(), ctx.count());
        let mut l = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        let mut came = Came::camera(ray.origin);
        let mut depth = 0;
        loop {
            let slot = self.begin_record(depth, if depth == 0 { "camera" } else { "bounce" }, &ray);
            let hit = match camera_hit.take() {
                Some(hit) => hit,
                None => scene.geometry.intersect(&ray),
            };
            let record = hit.map(|h| (h.t, h.prim));
            let v = match self.arrive(&ray, hit, &came, depth, first.take()) {
                Arrival::End(le, p) => {
                    l += beta * le;
                    self.finish_record(slot, record.zip(p).map(|((t, prim), p)| (t, prim, p)), le);
                    break;
                }
                Arrival::Scatter(v) => v,
            };
            let mut vertex = v.emitted;
            if v.bsdf.has_smooth_lobe() {
                vertex += self.next_event(ctx, depth, &v.bsdf, v.p, v.p_error, v.ng);
            }
            l += beta * vertex;
            self.finish_record(slot, record.map(|(t, prim)| (t, prim, v.p)), vertex);
            let choice = ctx.sampler.get_1d(Dim::lobe(depth), index, count);
            let u = ctx.sampler.get_2d(Dim::bounce(depth), index, count);
            let roulette = || ctx.sampler.get_1d(Dim::roulette(depth), index, count);
            let Some((next, next_came)) = self.bounce(depth, &v, (choice, u), roulette, &mut beta)
            else {
                break;
            };
            ray = next;
            came = next_came;
            depth += 1;
        }
        l
    }

    /// What a path finds where `ray` (which reached `hit`, drawn as
    /// `came` says) ends at path depth `depth`: the radiance it brings and
    /// the end of the path (an escaped ray; the vertex past the last
    /// bounce, which adds only its emission, the BSDF's half of the
    /// previous vertex's direct light), or the vertex to scatter from.
    /// With `first`, what the ray hit into it.
    #[inline(always)]
    pub(super) fn arrive(
        &self,
        ray: &Ray,
        hit: Option<PrimHit>,
        came: &Came,
        depth: u32,
        first: Option<&mut FirstHit>,
    ) -> Arrival {
        let scene = self.scene;
        let Some(hit) = hit else {
            if let Some(f) = first {
                *f = FirstHit::MISS;
            }
            return Arrival::End(self.escaped(ray, came), None);
        };
        let mut s = scene.geometry.surface(ray, &hit);
        let m = &scene.materials[s.material as usize];
        let wo = -ray.direction.normalize();
        maps::apply_normal_map(scene, m, &mut s, &hit, wo);
        let mapped;
        let m = match maps::textured_pbr(scene, m, s.uv) {
            Some(textured) => {
                mapped = textured;
                &mapped
            }
            None => m,
        };
        let (entering, ng, ns) = s.facing(wo);
        let texel = match (m.diffuse_texture, s.uv) {
            (Some(t), Some(uv)) => scene.textures.sample(t, uv),
            _ => Vec3::ONE,
        };
        if let Some(f) = first {
            let albedo = match m.pbr {
                Some(pbr) => pbr.base_color * texel,
                None => m.diffuse * texel,
            };
            *f = FirstHit {
                albedo,
                normal: s.shading_normal,
                depth: hit.t * ray.direction.length(),
            };
        }
        let mut emitted = Vec3::ZERO;
        if m.is_emissive() && (entering || !m.one_sided) {
            emitted += maps::emission(scene, m, s.uv)
                * self.emission_weight(&hit, came, s.p, s.geometric_normal);
        }
        if depth > scene.settings.max_depth {
            return Arrival::End(emitted, Some(s.p));
        }
        Arrival::Scatter(Vertex {
            bsdf: Bsdf::new(m, texel, wo, ng, ns, entering),
            p: s.p,
            p_error: s.p_error,
            ng,
            emitted,
        })
    }

    /// The path's next ray from vertex `v` at depth `depth`, drawn with
    /// `choice` and `u` (the draws of [`Dim::lobe`] and [`Dim::bounce`]),
    /// its throughput `beta` updated (Russian roulette, with the draw of
    /// [`Dim::roulette`] that `roulette` gives, included), and what the
    /// ray was drawn with; `None` where the path ends.
    #[inline(always)]
    pub(super) fn bounce(
        &mut self,
        depth: u32,
        v: &Vertex,
        (choice, u): (f32, Vec2),
        roulette: impl FnOnce() -> f32,
        beta: &mut Vec3,
    ) -> Option<(Ray, Came)> {
        let b = v.bsdf.sample(choice, u)?;
        *beta *= b.weight;
        if depth + 1 >= ROULETTE_DEPTH {
            let survive = beta.max_element().min(0.95);
            if !(roulette() < survive) {
                return None;
            }
            *beta /= survive;
        }
        if !(beta.max_element() > 0.0 && beta.is_finite()) {
            return None;
        }
        let through = v.ng.dot(b.wi) < 0.0;
        if through {
            self.counts.refraction += 1;
        } else {
            self.counts.reflection += 1;
        }
        let ray = Ray::new(spawn_origin(v.p, v.p_error, v.ng, b.wi), b.wi);
        let came = Came {
            pdf: (!b.delta).then_some(b.pdf),
            from: v.p,
            ng: v.ng,
        };
        Some((ray, came))
    }

    /// What a ray that hits nothing brings: the environment, weighed
    /// against its sampling, or the background.
    fn escaped(&self, ray: &Ray, came: &Came) -> Vec3 {
        let Some(env) = self.environment else {
            return self.scene.settings.background;
        };
        let le = env.radiance(ray.direction);
        let Some(pdf) = came.pdf else {
            return le;
        };
        let settings = &self.scene.settings;
        let light_pdf = env.pdf(
            Some(came.ng),
            ray.direction.normalize(),
            settings.light_sampling,
        );
        le * power_heuristic(pdf, settings.shadow_samples as f32 * light_pdf)
    }

    /// The MIS weight of emission found by a BSDF ray at `q` (normal `n`)
    /// on the hit's primitive: 1 where no light sampling could have found
    /// it.
    fn emission_weight(&self, hit: &PrimHit, came: &Came, q: Vec3, n: Vec3) -> f32 {
        let Some(pdf) = came.pdf else {
            return 1.0;
        };
        let scene = self.scene;
        let method = scene.settings.light_sampling;
        let light_pdf = match scene.lights.iter().find(|l| l.prim() == Some(hit.prim)) {
            Some(light) => light.pdf(came.from, q, n, method),
            None => {
                // An instance's triangle is named by the prototype's.
                let part = if hit.prim >= scene.geometry.first_instance() {
                    scene.geometry.instance(hit.prim).1.slot_prim(hit.part)
                } else {
                    NO_PART
                };
                scene.emitters.pdf((hit.prim, part), came.from, q, n)
            }
        };
        if light_pdf > 0.0 {
            power_heuristic(pdf, scene.settings.shadow_samples as f32 * light_pdf)
        } else {
            1.0
        }
    }

    /// Next-event estimation at a vertex (`p`, its rounding bound, `ng`
    /// faced towards the viewer): every light and the glowing surfaces,
    /// each sample weighed against the BSDF's density.
    fn next_event(
        &mut self,
        ctx: &SampleContext,
        depth: u32,
        bsdf: &Bsdf,
        p: Vec3,
        p_error: Vec3,
        ng: Vec3,
    ) -> Vec3 {
        let scene = self.scene;
        let method = scene.settings.light_sampling;
        let mut l = Vec3::ZERO;
        for source in 0..self.sources() {
            let light = scene.lights.get(source);
            let samples = self.samples_of(light);
            let dim = Dim::light(depth, source as u32);
            let mut sum = Vec3::ZERO;
            for j in 0..samples {
                // A delta light draws nothing.
                let u = if light.is_some_and(|l| !l.is_area()) {
                    Vec2::splat(0.5)
                } else {
                    let at = (ctx.index() * samples + j, ctx.count() * samples);
                    ctx.sampler.get_2d(dim, at.0, at.1)
                };
                let c = match light {
                    Some(light) => {
                        let drawn = match light.environment() {
                            Some(env) => env_drawn(env.sample(Some(ng), u, method)),
                            None => light_drawn(light, light.sample(p, u, method)),
                        };
                        drawn.and_then(|d| weigh(light, bsdf, d, samples))
                    }
                    None => self.emitter_sample(bsdf, p, u, samples),
                };
                let Some(c) = c else { continue };
                let ray = shadow_ray(p, p_error, ng, &c);
                self.counts.shadow += 1;
                if !scene.geometry.occluded_except(&ray, c.except) {
                    sum += c.value;
                }
            }
            l += sum / samples as f32;
        }
        l
    }

    /// The light sources of next-event estimation: the scene's lights,
    /// and the glowing surfaces as one more where there are any.
    pub(super) fn sources(&self) -> usize {
        self.scene.lights.len() + usize::from(!self.scene.emitters.is_empty())
    }

    /// Samples a vertex takes of `light` (`None`: the glowing surfaces):
    /// one of a delta light, `shadow_samples` of any other.
    pub(super) fn samples_of(&self, light: Option<&Light>) -> u32 {
        match light {
            Some(light) if !light.is_area() => 1,
            _ => self.scene.settings.shadow_samples,
        }
    }

    /// One sample of the glowing surfaces from `p`, as [`weigh`] weighs a
    /// light's.
    pub(super) fn emitter_sample(
        &self,
        bsdf: &Bsdf,
        p: Vec3,
        u: Vec2,
        samples: u32,
    ) -> Option<Contribution> {
        let e = self.scene.emitters.sample(p, u)?;
        let (f, bsdf_pdf) = bsdf.eval(e.wi);
        let cos = bsdf.cos(e.wi);
        if f.max_element() <= 0.0 || cos <= 0.0 {
            return None;
        }
        let w = power_heuristic(samples as f32 * e.pdf, bsdf_pdf);
        let radiance = match e.texture {
            Some((t, uv)) => e.radiance * self.scene.textures.sample(t, uv),
            None => e.radiance,
        };
        let value = f * radiance * (cos * w / e.pdf);
        value.is_finite().then_some(Contribution {
            wi: e.wi,
            distance: e.distance,
            except: e.prim,
            value,
        })
    }
}

/// A light's sample as [`weigh`] takes it: the direction, the distance
/// (∞ for light from infinity), radiance over density, and the density
/// per steradian where an area light or the environment has one.
pub(super) type Drawn = (Vec3, f32, Vec3, Option<f32>);

/// An environment's sample as [`weigh`] takes it.
#[inline(always)]
pub(super) fn env_drawn(e: Option<EnvSample>) -> Option<Drawn> {
    let e = e?;
    Some((e.wi, f32::INFINITY, e.radiance / e.pdf, Some(e.pdf)))
}

/// Any other light's sample as [`weigh`] takes it: an area light's
/// density is its radiance over the sample's weight.
#[inline(always)]
pub(super) fn light_drawn(light: &Light, s: Option<LightSample>) -> Option<Drawn> {
    let s = s?;
    let pdf = light
        .is_area()
        .then(|| light.surface_radiance().max_element() / s.weight.max_element());
    Some((s.wi, s.distance, s.weight, pdf))
}

/// One sample of `light`: f · L · cos / pdf times its MIS weight against
/// the BSDF (`samples` light samples a vertex), with the direction and
/// distance of its shadow ray (origin still the vertex).
#[inline(always)]
pub(super) fn weigh(
    light: &Light,
    bsdf: &Bsdf,
    (wi, distance, le_over_pdf, light_pdf): Drawn,
    samples: u32,
) -> Option<Contribution> {
    let (f, bsdf_pdf) = bsdf.eval(wi);
    let cos = bsdf.cos(wi);
    if f.max_element() <= 0.0 || cos <= 0.0 {
        return None;
    }
    let w = match light_pdf {
        Some(pdf) => power_heuristic(samples as f32 * pdf, bsdf_pdf),
        None => 1.0,
    };
    let value = f * le_over_pdf * (cos * w);
    value.is_finite().then_some(Contribution {
        wi,
        distance,
        except: light.prim().unwrap_or(u32::MAX),
        value,
    })
}

/// The shadow ray of contribution `c` from a vertex (`p`, its rounding
/// bound, `ng` faced towards the viewer), ending short of the point
/// sampled.
#[inline(always)]
pub(super) fn shadow_ray(p: Vec3, p_error: Vec3, ng: Vec3, c: &Contribution) -> Ray {
    let origin = spawn_origin(p, p_error, ng, c.wi);
    let tmax = if c.distance.is_finite() {
        (c.distance - (origin - p).length()).max(0.0)
    } else {
        f32::INFINITY
    };
    Ray::segment(origin, c.wi, tmax)
}
