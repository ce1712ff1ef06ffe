//! The path integrator's batches as a wavefront: the paths of a wave of
//! up to [`WAVE_BATCHES`] batches of camera samples (each up to
//! [`PACKET_SIZE`], one pixel's) advance bounce by bounce together, as
//! the distribution integrator lights its camera hits (`direct.rs`). At
//! each depth the wave's continuation rays are traced together, then
//! every vertex is lit: each light's spherical rectangles built and its
//! samples drawn in SIMD lanes (one lane a path of a batch), the shadow
//! rays towards one sample of every path of the wave traced together;
//! then every path draws its next direction, the draws again in lanes.
//! How the wave's rays walk is [`Geometry::intersect_wave`]'s choice.
//!
//! Each path's arithmetic is the one of [`Integrator::arrive`],
//! [`Integrator::bounce`] and the weighing of its light samples, which
//! the single path ([`Integrator::path`]) runs too, and each path adds its
//! contributions in the same order: the radiance of every path is bit for
//! bit what tracing it alone gives, so the image does not depend on how
//! samples are batched or waved (threads, slices, crops, noise targets).
//!
//! [`Geometry::intersect_wave`]: crate::geometry::Geometry::intersect_wave

use super::path::{
    env_drawn, light_drawn, shadow_ray, weigh, Arrival, Came, Contribution, Vertex, ROULETTE_DEPTH,
};
use super::sample::{draw_1d_lanes, draw_2d_lanes};
use super::{CameraSample, FirstHit, Integrator};
use crate::accel::{PrimHit, PACKET_SIZE};
use crate::light::{Light, LightLanes};
use crate::math::lanes::{mask_lanes, LANES};
use crate::math::Ray;
use crate::sampling::Dim;
use glam::{Vec2, Vec3};

// A batch of camera samples is one lane per path.
const _: () = assert!(PACKET_SIZE == LANES);

/// Batches a wave advances together: up to this many times
/// [`PACKET_SIZE`] paths, whose rays of one bounce, and shadow rays
/// towards one light sample, are traced together.
pub const WAVE_BATCHES: usize = 8;

/// Rays a wave traces together at most.
const WAVE_RAYS: usize = WAVE_BATCHES * LANES;

/// A wave's arrays of rays and light samples, kept by the integrator
/// from one wave to the next: filled as far as a wave needs, never
/// cleared whole (arrays sized for the largest wave, zeroed per bounce,
/// were a tenth of cornell-planes' instructions).
#[derive(Default)]
pub(super) struct WaveScratch {
    rays: Vec<Ray>,
    /// Each ray's batch and lane.
    at: Vec<(u8, u8)>,
    hits: Vec<Option<PrimHit>>,
    /// Sample `j` of batch `w` at `j * WAVE_BATCHES + w`.
    contributions: Vec<[Option<Contribution>; LANES]>,
}

/// The paths of one batch of a wave, one lane a path.
struct Paths<'b> {
    batch: &'b [CameraSample],
    ray: [Ray; LANES],
    hit: [Option<PrimHit>; LANES],
    l: [Vec3; LANES],
    beta: [Vec3; LANES],
    came: [Came; LANES],
    /// Each scattering lane's vertex, read in place: a vertex (its BSDF)
    /// is large, and copies of the batch's vertices were a tenth of the
    /// dragon's render.
    v: [Option<Vertex>; LANES],
    /// The lanes whose paths go on, that scatter at this depth, and that
    /// take light samples there.
    alive: u32,
    scatter: u32,
    lit: u32,
}

impl<'b> Paths<'b> {
    fn new(batch: &'b [CameraSample], ray: [Ray; LANES], hit: [Option<PrimHit>; LANES]) -> Self {
        Self {
            batch,
            ray,
            hit,
            l: [Vec3::ZERO; LANES],
            beta: [Vec3::ONE; LANES],
            came: std::array::from_fn(|i| Came::camera(ray[i].origin)),
            v: [None; LANES],
            alive: u32::MAX >> (32 - batch.len()),
            scatter: 0,
            lit: 0,
        }
    }

    /// Lane `i`'s vertex (a lane that scatters has one).
    #[inline(always)]
    fn vertex(&self, i: usize) -> &Vertex {
        self.v[i].as_ref().expect("a scattering lane's vertex")
    }
}

impl Integrator<'_> {
    /// Radiance of each path of the wave `batches` (each of one or more
    /// samples, up to [`WAVE_BATCHES`] of them) into `out[w][i]` for
    /// sample `i` of batch `w`; `first[w]` as [`Integrator::camera_batch`]
    /// fills it for batch `w`. Exactly what [`Integrator::path`] returns
    /// for each sample alone.
    pub(super) fn path_wave(
        &mut self,
        batches: &[&[CameraSample]],
        out: &mut [[Vec3; LANES]],
        mut first: Option<&mut [[FirstHit; LANES]]>,
    ) {
        let k = batches.len();
        debug_assert!((1..=WAVE_BATCHES).contains(&k));
        debug_assert!(batches.iter().all(|b| (1..=PACKET_SIZE).contains(&b.len())));
        // The camera rays batch by batch (coherent: one packet where it
        // pays); lanes past a batch's samples stay dead.
        let mut paths: [Option<Paths>; WAVE_BATCHES] = std::array::from_fn(|_| None);
        for (p, batch) in paths.iter_mut().zip(batches) {
            let (rays, hits) = self.camera_hits(batch);
            *p = Some(Paths::new(batch, rays, hits));
        }
        let mut scratch = std::mem::take(&mut self.wave);
        let mut depth = 0;
        loop {
            if depth > 0 {
                self.bounce_hits(&mut paths[..k], &mut scratch);
            }
            // Where each path's ray ends: escaped, past the last bounce,
            // or a vertex to light and scatter from.
            let mut scatters = false;
            for (w, p) in paths[..k].iter_mut().flatten().enumerate() {
                p.scatter = 0;
                p.lit = 0;
                for i in mask_lanes(p.alive) {
                    let first_i = match (&mut first, depth) {
                        (Some(f), 0) => Some(&mut f[w][i]),
                        _ => None,
                    };
                    match self.arrive(&p.ray[i], p.hit[i], &p.came[i], depth, first_i) {
                        Arrival::End(le, _) => p.l[i] += p.beta[i] * le,
                        Arrival::Scatter(v) => {
                            if v.bsdf.has_smooth_lobe() {
                                p.lit |= 1 << i;
                            }
                            p.v[i] = Some(v);
                            p.scatter |= 1 << i;
                        }
                    }
                }
                scatters |= p.scatter != 0;
            }
            if !scatters {
                break;
            }
            let direct = self.next_event_wave(depth, &paths[..k], &mut scratch);
            for (p, direct) in paths[..k].iter_mut().flatten().zip(&direct) {
                p.alive = 0;
                if p.scatter == 0 {
                    continue;
                }
                for i in mask_lanes(p.scatter) {
                    let mut radiance = p.vertex(i).emitted;
                    if p.lit >> i & 1 != 0 {
                        radiance += direct[i];
                    }
                    p.l[i] += p.beta[i] * radiance;
                }
                self.bounce_lanes(depth, p);
            }
            depth += 1;
        }
        self.wave = scratch;
        for (o, p) in out.iter_mut().zip(paths[..k].iter().flatten()) {
            let n = p.batch.len();
            o[..n].copy_from_slice(&p.l[..n]);
        }
    }

    /// The next directions of the lanes of `p` that scatter at `depth`,
    /// drawn in lanes; Russian roulette's draws too where it may end a
    /// path (drawn for every path that scatters: the draws are
    /// counter-based, so a draw not used changes no other). Sets the
    /// lanes that go on.
    fn bounce_lanes(&mut self, depth: u32, p: &mut Paths) {
        let batch = p.batch;
        let ctx_of = |i: usize| &batch[i].ctx;
        let at = |i: usize| (batch[i].ctx.index(), batch[i].ctx.count());
        let choice = draw_1d_lanes(p.scatter, ctx_of, Dim::lobe(depth), at);
        let u = draw_2d_lanes(p.scatter, ctx_of, Dim::bounce(depth), at);
        let roulette = if depth + 1 >= ROULETTE_DEPTH {
            draw_1d_lanes(p.scatter, ctx_of, Dim::roulette(depth), at)
        } else {
            [0.0; LANES]
        };
        for i in mask_lanes(p.scatter) {
            let draws = (choice[i], u[i]);
            let v = p.v[i].as_ref().expect("a scattering lane's vertex");
            if let Some((r, c)) = self.bounce(depth, v, draws, || roulette[i], &mut p.beta[i]) {
                p.ray[i] = r;
                p.came[i] = c;
                p.alive |= 1 << i;
            }
        }
    }

    /// The closest hits of the rays of the wave's live lanes, into their
    /// `hit`s: traced together, each hit bit for bit
    /// [`crate::geometry::Geometry::intersect`]'s.
    fn bounce_hits(&mut self, paths: &mut [Option<Paths>], scratch: &mut WaveScratch) {
        let (rays, at) = (&mut scratch.rays, &mut scratch.at);
        rays.clear();
        at.clear();
        for (w, p) in paths.iter().flatten().enumerate() {
            for i in mask_lanes(p.alive) {
                rays.push(p.ray[i]);
                at.push((w as u8, i as u8));
            }
        }
        scratch.hits.clear();
        scratch.hits.resize(rays.len(), None);
        self.scene.geometry.intersect_wave(rays, &mut scratch.hits);
        for (&(w, i), hit) in at.iter().zip(&scratch.hits) {
            let p = paths[w as usize].as_mut().expect("a wave's batch");
            p.hit[i as usize] = *hit;
        }
    }

    /// Next-event estimation at the wave's vertices at path depth
    /// `depth` (the lanes of each batch's `lit`): for each lane exactly
    /// what [`Integrator::next_event`] gives its vertex alone.
    fn next_event_wave(
        &mut self,
        depth: u32,
        paths: &[Option<Paths>],
        scratch: &mut WaveScratch,
    ) -> [[Vec3; LANES]; WAVE_BATCHES] {
        let scene = self.scene;
        let method = scene.settings.light_sampling;
        let mut l = [[Vec3::ZERO; LANES]; WAVE_BATCHES];
        for source in 0..self.sources() {
            let light = scene.lights.get(source);
            let samples = self.samples_of(light);
            let dim = Dim::light(depth, source as u32);
            // A lane no sample of the light can reach draws nothing (the
            // draws are counter-based: no other number changes) and every
            // sample would be rejected by its BSDF (both normals below).
            let mut active = [0u32; WAVE_BATCHES];
            for (a, p) in active.iter_mut().zip(paths.iter().flatten()) {
                *a = p.lit;
                if let Some(light) = light {
                    for i in mask_lanes(p.lit) {
                        let v = p.vertex(i);
                        if light.hidden_from(v.p, v.ng) {
                            *a &= !(1 << i);
                        }
                    }
                }
            }
            let mut sum = [[Vec3::ZERO; LANES]; WAVE_BATCHES];
            if active.iter().any(|&a| a != 0) {
                // Every sample of every batch first (each batch's
                // spherical rectangles built once), then the shadow rays
                // of each sample of the wave together. Only the active
                // lanes' entries are written and read.
                let c = &mut scratch.contributions;
                let need = samples as usize * WAVE_BATCHES;
                if c.len() < need {
                    c.resize(need, [const { None }; LANES]);
                }
                for (w, p) in paths.iter().flatten().enumerate() {
                    if active[w] == 0 {
                        continue;
                    }
                    let points =
                        std::array::from_fn(|i| p.v[i].as_ref().map_or(Vec3::ZERO, |v| v.p));
                    let seen = light
                        .filter(|l| l.environment().is_none())
                        .map(|l| l.seen_from_lanes(&points, active[w], method));
                    for j in 0..samples {
                        let c = &mut c[j as usize * WAVE_BATCHES + w];
                        self.light_samples(p, light, &seen, active[w], (dim, j), c);
                    }
                }
                for j in 0..samples as usize {
                    let c = &scratch.contributions[j * WAVE_BATCHES..(j + 1) * WAVE_BATCHES];
                    self.shadow_wave(
                        paths,
                        c,
                        &active,
                        &mut scratch.rays,
                        &mut scratch.at,
                        &mut sum,
                    );
                }
            }
            for (w, p) in paths.iter().flatten().enumerate() {
                for i in mask_lanes(p.lit) {
                    l[w][i] += sum[w][i] / samples as f32;
                }
            }
        }
        l
    }

    /// Sample `j` of `light` (`None`: the glowing surfaces; `seen` its
    /// spherical rectangles, where it has them) from the vertices of the
    /// lanes `active` of `p`, weighed, into `c[i]` for each lane `i` of
    /// `active`: each lane's as [`Integrator::next_event`] takes it.
    fn light_samples(
        &self,
        p: &Paths,
        light: Option<&Light>,
        seen: &Option<LightLanes>,
        active: u32,
        (dim, j): (Dim, u32),
        c: &mut [Option<Contribution>; LANES],
    ) {
        let method = self.scene.settings.light_sampling;
        let samples = self.samples_of(light);
        let batch = p.batch;
        let u = if light.is_some_and(|l| !l.is_area()) {
            [Vec2::splat(0.5); LANES]
        } else {
            let at = |i: usize| {
                let ctx = &batch[i].ctx;
                (ctx.index() * samples + j, ctx.count() * samples)
            };
            draw_2d_lanes(active, |i| &batch[i].ctx, dim, at)
        };
        match (light, seen) {
            (Some(light), Some(seen)) => {
                let s = seen.sample(active, &u);
                for i in mask_lanes(active) {
                    c[i] = light_drawn(light, s[i])
                        .and_then(|d| weigh(light, &p.vertex(i).bsdf, d, samples));
                }
            }
            (Some(light), None) => {
                let env = light.environment().expect("a light seen alone");
                for i in mask_lanes(active) {
                    let v = p.vertex(i);
                    c[i] = env_drawn(env.sample(Some(v.ng), u[i], method))
                        .and_then(|d| weigh(light, &v.bsdf, d, samples));
                }
            }
            (None, _) => {
                for i in mask_lanes(active) {
                    let v = p.vertex(i);
                    c[i] = self.emitter_sample(&v.bsdf, v.p, u[i], samples);
                }
            }
        }
    }

    /// Traces the shadow rays of the wave's contributions `c[w][i]` (from
    /// vertex `i` of batch `w`, for the lanes `i` of `active[w]`)
    /// together, adding each unblocked one's value to `sum[w][i]`.
    fn shadow_wave(
        &mut self,
        paths: &[Option<Paths>],
        c: &[[Option<Contribution>; LANES]],
        active: &[u32; WAVE_BATCHES],
        rays: &mut Vec<Ray>,
        at: &mut Vec<(u8, u8)>,
        sum: &mut [[Vec3; LANES]; WAVE_BATCHES],
    ) {
        let geometry = &self.scene.geometry;
        rays.clear();
        at.clear();
        // One primitive skipped by every ray (a light's surface), or
        // `None` where they differ (the glowing surfaces').
        let mut except = None;
        let mut one_except = true;
        for (w, p) in paths.iter().flatten().enumerate() {
            for i in mask_lanes(active[w]) {
                let Some(c) = &c[w][i] else { continue };
                let v = p.vertex(i);
                rays.push(shadow_ray(v.p, v.p_error, v.ng, c));
                at.push((w as u8, i as u8));
                match except {
                    None => except = Some(c.except),
                    Some(e) => one_except &= e == c.except,
                }
            }
        }
        let len = rays.len();
        self.counts.shadow += len as u64;
        let contribution = |(w, i): (u8, u8)| {
            c[w as usize][i as usize]
                .as_ref()
                .expect("a traced contribution")
        };
        let mut blocked = [false; WAVE_RAYS];
        match except {
            None => return,
            Some(except) if one_except && len > 1 => {
                geometry.occluded_wave(rays, except, &mut blocked[..len]);
            }
            _ => {
                for k in 0..len {
                    let except = contribution(at[k]).except;
                    blocked[k] = geometry.occluded_except(&rays[k], except);
                }
            }
        }
        for (&at, &blocked) in at.iter().zip(&blocked) {
            if !blocked {
                sum[at.0 as usize][at.1 as usize] += contribution(at).value;
            }
        }
    }
}
