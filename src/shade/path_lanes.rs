//! The path integrator's batches as a wavefront: the paths of one batch
//! of camera samples (up to [`PACKET_SIZE`], one pixel's) advance bounce
//! by bounce together, as the distribution integrator lights its camera
//! hits (`direct.rs`). At each depth the batch's continuation rays are
//! traced back to back, then every vertex is lit: each light's spherical
//! rectangles built and its samples drawn in SIMD lanes (one lane a
//! path), the shadow rays towards one sample of every lane traced back
//! to back; then every path draws its next direction, the draws again in
//! lanes. The rays walk one after another
//! ([`crate::geometry::Geometry::intersect_few`]): a batch's rays leave
//! from one pixel's hits and share cached nodes, and neither walks in
//! flight nor a stream's bundles paid for eight of them.
//!
//! Each path's arithmetic is the one of [`Integrator::arrive`],
//! [`Integrator::bounce`] and the weighing of its light samples, which
//! the single path ([`Integrator::path`]) runs too, and each path adds its
//! contributions in the same order: the radiance of every path is bit for
//! bit what tracing it alone gives, so the image does not depend on how
//! samples are batched (threads, slices, crops, noise targets).

use super::path::{
    env_drawn, light_drawn, shadow_ray, weigh, Arrival, Came, Contribution, Vertex, ROULETTE_DEPTH,
};
use super::sample::BatchDraws;
use super::{CameraSample, FirstHit, Integrator};
use crate::accel::{PrimHit, PACKET_SIZE};
use crate::math::lanes::{mask_lanes, LANES};
use crate::math::Ray;
use crate::sampling::Dim;
use glam::{Vec2, Vec3};

// A batch of camera samples is one lane per path.
const _: () = assert!(PACKET_SIZE == LANES);

impl Integrator<'_> {
    /// Radiance of each path of `batch` (two or more samples) into `out`,
    /// from its camera ray `rays[i]` and that ray's closest hit `hits[i]`;
    /// `first` as [`Integrator::camera_batch`] fills it. Exactly what
    /// [`Integrator::path`] returns for each sample alone.
    pub(super) fn path_lanes(
        &mut self,
        batch: &[CameraSample],
        rays: [Ray; PACKET_SIZE],
        hits: [Option<PrimHit>; PACKET_SIZE],
        out: &mut [Vec3],
        mut first: Option<&mut [FirstHit]>,
    ) {
        let n = batch.len();
        debug_assert!((2..=PACKET_SIZE).contains(&n));
        let (mut ray, mut hit) = (rays, hits);
        let mut l = [Vec3::ZERO; LANES];
        let mut beta = [Vec3::ONE; LANES];
        let mut came: [Came; LANES] = std::array::from_fn(|i| Came::camera(rays[i].origin));
        let mut vertices: [Option<Vertex>; LANES] = [None; LANES];
        let mut alive = u32::MAX >> (32 - n);
        let draws = BatchDraws::new(batch, self.scene.settings.shadow_samples);
        let mut depth = 0;
        while alive != 0 {
            if depth > 0 {
                self.bounce_hits(&ray, alive, &mut hit);
            }
            // Where each path's ray ends: escaped, past the last bounce,
            // or a vertex to light and scatter from.
            let mut scatter = 0u32;
            for i in mask_lanes(alive) {
                let first_i = match (&mut first, depth) {
                    (Some(f), 0) => Some(&mut f[i]),
                    _ => None,
                };
                match self.arrive(&ray[i], hit[i], &came[i], depth, first_i) {
                    Arrival::End(le, _) => l[i] += beta[i] * le,
                    Arrival::Scatter(v) => {
                        vertices[i] = Some(v);
                        scatter |= 1 << i;
                    }
                }
            }
            if scatter == 0 {
                break;
            }
            // Read in place: a vertex (its BSDF) is large, and copies of
            // the batch's vertices were a tenth of the dragon's render.
            let v = &vertices;
            let mut lit = 0u32;
            for i in mask_lanes(scatter) {
                if vertex(v, i).bsdf.has_smooth_lobe() {
                    lit |= 1 << i;
                }
            }
            let direct = if lit != 0 {
                self.next_event_lanes(&draws, depth, v, lit)
            } else {
                [Vec3::ZERO; LANES]
            };
            for i in mask_lanes(scatter) {
                let mut radiance = vertex(v, i).emitted;
                if lit >> i & 1 != 0 {
                    radiance += direct[i];
                }
                l[i] += beta[i] * radiance;
            }
            // The next directions, drawn in lanes; Russian roulette's
            // draws too where it may end a path (drawn for every path
            // that scatters: the draws are counter-based, so a draw not
            // used changes no other).
            let choice = draws.get_1d(Dim::lobe(depth), scatter);
            let u = draws.get_2d(Dim::bounce(depth), scatter);
            let roulette = if depth + 1 >= ROULETTE_DEPTH {
                draws.get_1d(Dim::roulette(depth), scatter)
            } else {
                [0.0; LANES]
            };
            alive = 0;
            for i in mask_lanes(scatter) {
                let draws = (choice[i], u[i]);
                let bounced = self.bounce(depth, vertex(v, i), draws, || roulette[i], &mut beta[i]);
                if let Some((r, c)) = bounced {
                    ray[i] = r;
                    came[i] = c;
                    alive |= 1 << i;
                }
            }
            depth += 1;
        }
        out[..n].copy_from_slice(&l[..n]);
    }

    /// The closest hits of the rays `rays[i]` of the lanes `i` in `live`,
    /// into `hits[i]`: traced together, each hit bit for bit
    /// [`crate::geometry::Geometry::intersect`]'s.
    fn bounce_hits(&mut self, rays: &[Ray; LANES], live: u32, hits: &mut [Option<PrimHit>; LANES]) {
        let geometry = &self.scene.geometry;
        if live.count_ones() == 1 {
            let i = live.trailing_zeros() as usize;
            hits[i] = geometry.intersect(&rays[i]);
            return;
        }
        let mut gathered = [rays[0]; LANES];
        let mut lane = [0u8; LANES];
        let mut len = 0;
        for i in mask_lanes(live) {
            gathered[len] = rays[i];
            lane[len] = i as u8;
            len += 1;
        }
        let mut found = [None; LANES];
        geometry.intersect_few(&gathered[..len], &mut found[..len]);
        for k in 0..len {
            hits[lane[k] as usize] = found[k];
        }
    }

    /// Next-event estimation at the vertices `v[i]` of the lanes `i` in
    /// `lit` at path depth `depth`: for each lane exactly what
    /// [`Integrator::next_event`] gives its vertex alone.
    fn next_event_lanes(
        &mut self,
        draws: &BatchDraws,
        depth: u32,
        v: &[Option<Vertex>; LANES],
        lit: u32,
    ) -> [Vec3; LANES] {
        let scene = self.scene;
        let method = scene.settings.light_sampling;
        let points: [Vec3; LANES] =
            std::array::from_fn(|i| v[i].as_ref().map_or(Vec3::ZERO, |v| v.p));
        let mut l = [Vec3::ZERO; LANES];
        for source in 0..self.sources() {
            let light = scene.lights.get(source);
            let samples = self.samples_of(light);
            let dim = Dim::light(depth, source as u32);
            // A lane no sample of the light can reach draws nothing (the
            // draws are counter-based: no other number changes) and every
            // sample would be rejected by its BSDF (both normals below).
            let mut active = lit;
            if let Some(light) = light {
                for i in mask_lanes(lit) {
                    if light.hidden_from(points[i], vertex(v, i).ng) {
                        active &= !(1 << i);
                    }
                }
            }
            let mut sum = [Vec3::ZERO; LANES];
            if active != 0 {
                let seen = light
                    .filter(|l| l.environment().is_none())
                    .map(|l| l.seen_from_lanes(&points, active, method));
                for j in 0..samples {
                    let u = if light.is_some_and(|l| !l.is_area()) {
                        [Vec2::splat(0.5); LANES]
                    } else {
                        draws.light_2d(dim, samples, j, active)
                    };
                    let mut c: [Option<Contribution>; LANES] = [const { None }; LANES];
                    match (light, &seen) {
                        (Some(light), Some(seen)) => {
                            let s = seen.sample(active, &u);
                            for i in mask_lanes(active) {
                                c[i] = light_drawn(light, s[i])
                                    .and_then(|d| weigh(light, &vertex(v, i).bsdf, d, samples));
                            }
                        }
                        (Some(light), None) => {
                            let env = light.environment().expect("a light seen alone");
                            for i in mask_lanes(active) {
                                c[i] = env_drawn(env.sample(Some(vertex(v, i).ng), u[i], method))
                                    .and_then(|d| weigh(light, &vertex(v, i).bsdf, d, samples));
                            }
                        }
                        (None, _) => {
                            for i in mask_lanes(active) {
                                c[i] = self.emitter_sample(
                                    &vertex(v, i).bsdf,
                                    points[i],
                                    u[i],
                                    samples,
                                );
                            }
                        }
                    }
                    self.shadow_lanes(v, &c, active, &mut sum);
                }
            }
            for i in mask_lanes(lit) {
                l[i] += sum[i] / samples as f32;
            }
        }
        l
    }

    /// Traces the shadow rays of the contributions `c[i]` (lanes `i` of
    /// `active`, from vertex `v[i]`) together, adding each unblocked one's
    /// value to `sum[i]`.
    fn shadow_lanes(
        &mut self,
        v: &[Option<Vertex>; LANES],
        c: &[Option<Contribution>; LANES],
        active: u32,
        sum: &mut [Vec3; LANES],
    ) {
        let geometry = &self.scene.geometry;
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); LANES];
        let mut lane = [0u8; LANES];
        let mut len = 0;
        // One primitive skipped by every ray (a light's surface), or
        // `None` where they differ (the glowing surfaces').
        let mut except = None;
        let mut one_except = true;
        for i in mask_lanes(active) {
            let Some(c) = &c[i] else { continue };
            let v = vertex(v, i);
            rays[len] = shadow_ray(v.p, v.p_error, v.ng, c);
            lane[len] = i as u8;
            len += 1;
            match except {
                None => except = Some(c.except),
                Some(e) => one_except &= e == c.except,
            }
        }
        self.counts.shadow += len as u64;
        let mut blocked = [false; LANES];
        match except {
            None => return,
            Some(except) if one_except && len > 1 => {
                geometry.occluded_few(&rays[..len], except, &mut blocked[..len]);
            }
            _ => {
                for k in 0..len {
                    let except = c[lane[k] as usize].as_ref().map_or(u32::MAX, |c| c.except);
                    blocked[k] = geometry.occluded_except(&rays[k], except);
                }
            }
        }
        for k in 0..len {
            if !blocked[k] {
                let i = lane[k] as usize;
                sum[i] += c[i].as_ref().expect("a traced contribution").value;
            }
        }
    }
}

/// Lane `i`'s vertex (a lane that scatters has one).
#[inline(always)]
fn vertex(v: &[Option<Vertex>; LANES], i: usize) -> &Vertex {
    v[i].as_ref().expect("a scattering lane's vertex")
}
