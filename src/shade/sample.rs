//! What identifies one sample and what a render counts.

use crate::math::lanes::{mask_lanes, LANES};
use crate::math::Ray;
use crate::sampling::sampler::SetLanes;
use crate::sampling::{Dim, PixelSampler};
use glam::{Vec2, Vec3};

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
}

/// Counts summed field by field: each work item counts its own rays, and
/// the render adds them up.
impl std::ops::AddAssign for RayCounts {
    fn add_assign(&mut self, o: RayCounts) {
        self.camera += o.camera;
        self.shadow += o.shadow;
        self.reflection += o.reflection;
        self.refraction += o.refraction;
        self.glossy_rejected += o.glossy_rejected;
    }
}

impl std::ops::Add for RayCounts {
    type Output = RayCounts;
    fn add(mut self, o: RayCounts) -> RayCounts {
        self += o;
        self
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

/// The 2D draws of dimension `dim` for the lanes `i` in mask `wanted`:
/// point `at(i)` = (index, count) of lane `i`'s context `ctx_of(i)`,
/// exactly what its own sampler gives (zero in the other lanes). Lanes
/// that share their numbers and set size (a batch's samples of one pixel,
/// or one sample's several draws) are drawn together in SIMD lanes
/// ([`crate::sampling::sampler::DimSampler::get_2d_lanes`]), each such set
/// of lanes in turn where a batch holds several pixels' samples, rather
/// than the first set in lanes and the rest one by one (timed in
/// docs/mitsuba.md, "What was tried for the render"); several pixels'
/// stratified sets of one size are drawn at once, each lane under its own
/// pixel's patterns ([`SetLanes::each_pixel`]).
#[inline]
pub(super) fn draw_2d_lanes<'c>(
    wanted: u32,
    ctx_of: impl Fn(usize) -> &'c SampleContext,
    dim: Dim,
    at: impl Fn(usize) -> (u32, u32),
) -> [Vec2; LANES] {
    if let Some((sets, index)) = pixels_alike(wanted, &ctx_of, &at) {
        return only_wanted(sets.get_2d(dim, &index, wanted), wanted);
    }
    draw_lanes(wanted, ctx_of, at, |sampler, index, count, sharing| {
        sampler.dim_2d(dim, count).get_2d_lanes(index, sharing)
    })
}

/// The 1D draws of dimension `dim` for the lanes `i` in mask `wanted`, as
/// [`draw_2d_lanes`] draws 2D points
/// ([`crate::sampling::PixelSampler::get_1d_lanes`]).
#[inline]
pub(super) fn draw_1d_lanes<'c>(
    wanted: u32,
    ctx_of: impl Fn(usize) -> &'c SampleContext,
    dim: Dim,
    at: impl Fn(usize) -> (u32, u32),
) -> [f32; LANES] {
    if let Some((sets, index)) = pixels_alike(wanted, &ctx_of, &at) {
        return only_wanted(sets.get_1d(dim, &index, wanted), wanted);
    }
    draw_lanes(wanted, ctx_of, at, |sampler, index, count, sharing| {
        sampler.get_1d_lanes(dim, index, count, sharing)
    })
}

/// Where the lanes of `wanted` (two or more) hold the samples of two or
/// more pixels whose stratified sets have one size: those sets, drawn for
/// each lane's own pixel, and each lane's index (the first wanted lane's
/// in the others, so that every index is within the sets).
#[inline]
fn pixels_alike<'c>(
    wanted: u32,
    ctx_of: &impl Fn(usize) -> &'c SampleContext,
    at: &impl Fn(usize) -> (u32, u32),
) -> Option<(SetLanes, [u32; LANES])> {
    if wanted.count_ones() < 2 {
        return None;
    }
    let first_lane = wanted.trailing_zeros() as usize;
    let first = &ctx_of(first_lane).sampler;
    let (first_index, count) = at(first_lane);
    let mut index = [first_index; LANES];
    let mut samplers = [first; LANES];
    let mut one_pixel = true;
    for i in mask_lanes(wanted) {
        let (i_index, i_count) = at(i);
        if i_count != count {
            return None;
        }
        index[i] = i_index;
        samplers[i] = &ctx_of(i).sampler;
        one_pixel &= samplers[i].same_numbers(first);
    }
    // One pixel's lanes are one group of `draw_lanes`, drawn alike.
    if one_pixel {
        return None;
    }
    let sets = first.set_lanes(count).each_pixel(samplers)?;
    Some((sets, index))
}

/// `drawn` in the lanes of `wanted`, zero in the others.
#[inline(always)]
fn only_wanted<T: Copy + Default>(drawn: [T; LANES], wanted: u32) -> [T; LANES] {
    std::array::from_fn(|i| match wanted >> i & 1 {
        1 => drawn[i],
        _ => T::default(),
    })
}

/// The lanes of `wanted` grouped by the numbers they share (sampler and
/// set size), each group drawn by `draw(sampler, index, count, lanes)`
/// with every lane's index valid (the group's first index where a lane
/// is not in it).
#[inline(always)]
fn draw_lanes<'c, T: Copy + Default>(
    wanted: u32,
    ctx_of: impl Fn(usize) -> &'c SampleContext,
    at: impl Fn(usize) -> (u32, u32),
    draw: impl Fn(&PixelSampler, [u32; LANES], u32, u32) -> [T; LANES],
) -> [T; LANES] {
    let mut points = [T::default(); LANES];
    let mut left = wanted;
    while left != 0 {
        let first_lane = left.trailing_zeros() as usize;
        let first = ctx_of(first_lane);
        let (first_index, count) = at(first_lane);
        let mut index = [first_index; LANES];
        let mut sharing = 1u32 << first_lane;
        for i in mask_lanes(left & !sharing) {
            let (i_index, i_count) = at(i);
            if i_count == count && ctx_of(i).sampler.same_numbers(&first.sampler) {
                sharing |= 1 << i;
                index[i] = i_index;
            }
        }
        let drawn = draw(&first.sampler, index, count, sharing);
        for i in mask_lanes(sharing) {
            points[i] = drawn[i];
        }
        left &= !sharing;
    }
    points
}

/// The draws of one batch of camera samples (one lane a sample), for the
/// path integrator's every bounce: exactly what [`draw_1d_lanes`] and
/// [`draw_2d_lanes`] give at the point (index, count) of each lane's
/// context (a light's `samples` draws a vertex at index · samples + j of
/// count · samples). Where every sample of the batch has one set size
/// (a batch of one pixel's samples, or of several pixels' under the
/// stratified sampler), the lanes' indices and the sets' grids are worked
/// out once here, not again at every draw: a draw then only hashes its
/// dimension's pattern (each lane its own pixel's) and permutes, eight
/// lanes at once. Grouping a batch of several pixels' samples by pixel
/// drew each group apart, 13% more instructions a path on cornell-planes
/// at 4 spp (two pixels a batch) and 30% at 1 spp.
pub(super) struct BatchDraws<'c> {
    batch: &'c [CameraSample],
    shared: Option<SharedDraws>,
}

/// What a batch's draws share where its samples share their set size.
struct SharedDraws {
    /// Each lane's index (lane 0's past the batch's end).
    index: [u32; LANES],
    /// The sets of the samples' count, and of count · `samples`.
    sets: SetLanes,
    samples: u32,
    light_sets: SetLanes,
}

impl<'c> BatchDraws<'c> {
    /// The draws of `batch` (one to [`LANES`] samples), whose light
    /// draws take `samples` points a vertex.
    pub(super) fn new(batch: &'c [CameraSample], samples: u32) -> Self {
        debug_assert!((1..=LANES).contains(&batch.len()));
        let first = &batch[0].ctx;
        let count = first.count();
        let same_count = batch[1..].iter().all(|s| s.ctx.count() == count);
        let shared = same_count.then(|| {
            let sets = first.sampler.set_lanes(count);
            // Wrapping as the scalar count · samples does in a release build.
            let light_sets = first.sampler.set_lanes(count.wrapping_mul(samples));
            if batch[1..]
                .iter()
                .all(|s| s.ctx.sampler.same_numbers(&first.sampler))
            {
                return Some((sets, light_sets));
            }
            // Several pixels' samples (a pass of fewer samples a pixel
            // than lanes): the same sets, each lane under its own pixel's
            // patterns; lanes past the batch draw as its first sample.
            let samplers = std::array::from_fn(|i| &batch.get(i).unwrap_or(&batch[0]).ctx.sampler);
            sets.each_pixel(samplers)
                .zip(light_sets.each_pixel(samplers))
        });
        let shared = shared.flatten().map(|(sets, light_sets)| {
            let mut index = [first.index(); LANES];
            for (i, s) in batch.iter().enumerate() {
                index[i] = s.ctx.index();
            }
            SharedDraws {
                index,
                sets,
                samples,
                light_sets,
            }
        });
        Self { batch, shared }
    }

    /// The 1D draws of dimension `dim` for the lanes of `wanted` (each
    /// lane's own; the others hold no promised value).
    #[inline]
    pub(super) fn get_1d(&self, dim: Dim, wanted: u32) -> [f32; LANES] {
        match &self.shared {
            Some(s) => s.sets.get_1d(dim, &s.index, wanted),
            None => draw_1d_lanes(wanted, |i| &self.batch[i].ctx, dim, |i| self.at(i)),
        }
    }

    /// The 2D draws of dimension `dim` for the lanes of `wanted`.
    #[inline]
    pub(super) fn get_2d(&self, dim: Dim, wanted: u32) -> [Vec2; LANES] {
        match &self.shared {
            Some(s) => s.sets.get_2d(dim, &s.index, wanted),
            None => draw_2d_lanes(wanted, |i| &self.batch[i].ctx, dim, |i| self.at(i)),
        }
    }

    /// Draw `j` of a light's `samples` a vertex, of dimension `dim`, for
    /// the lanes of `wanted`.
    #[inline]
    pub(super) fn light_2d(&self, dim: Dim, samples: u32, j: u32, wanted: u32) -> [Vec2; LANES] {
        match &self.shared {
            Some(s) if s.samples == samples => {
                let index = s.index.map(|index| index * samples + j);
                s.light_sets.get_2d(dim, &index, wanted)
            }
            _ => {
                let at = |i: usize| {
                    let ctx = &self.batch[i].ctx;
                    (ctx.index() * samples + j, ctx.count() * samples)
                };
                draw_2d_lanes(wanted, |i| &self.batch[i].ctx, dim, at)
            }
        }
    }

    /// Lane `i`'s (index, count).
    fn at(&self, i: usize) -> (u32, u32) {
        let ctx = &self.batch[i].ctx;
        (ctx.index(), ctx.count())
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

/// What a camera ray's first hit shows, for the AOV channels of denoisers
/// and compositing: the diffuse albedo, the world-space shading normal (as
/// the surface has it, pointing out of solids), and the distance along the
/// ray. A ray that hits nothing has albedo and normal 0 and depth ∞.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstHit {
    pub albedo: Vec3,
    pub normal: Vec3,
    pub depth: f32,
}

impl FirstHit {
    pub const MISS: FirstHit = FirstHit {
        albedo: Vec3::ZERO,
        normal: Vec3::ZERO,
        depth: f32::INFINITY,
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::SamplerKind;
    use rand::RngExt;

    /// A batch's draws are each lane's own sampler's, bit for bit, for
    /// batches of one pixel's samples (drawn from the sets prepared once),
    /// of several pixels' samples of one set size (the same sets, each
    /// lane under its own pixel's patterns) and batches that mix set sizes
    /// too (drawn as [`draw_2d_lanes`] draws them), every dimension and
    /// light sample.
    #[test]
    fn a_batch_draws_what_each_sample_draws_alone() {
        let mut rng = crate::sampling::stream::seeded(777);
        let mut next = |n: u32| rng.random_range(0..n);
        let kinds = SamplerKind::ALL;
        for round in 0..3000 {
            let kind = kinds[round % kinds.len()];
            let len = 1 + next(LANES as u32) as usize;
            // Several pixels (one set size), and set sizes mixed too.
            let (pixels, mixed) = (round % 4 >= 2, round % 4 == 3);
            let spp = [1u32, 4, 16, 35][next(4) as usize];
            let samples = 1 + next(3);
            let batch: Vec<CameraSample> = (0..len)
                .map(|_| {
                    let pixel = if pixels { next(3) } else { 5 };
                    let spp = if mixed && next(2) == 0 { spp + 1 } else { spp };
                    let sampler = PixelSampler::new(kind, 3, pixel)
                        .with_sets(PixelSampler::prepare_sets([spp, spp * samples]));
                    CameraSample {
                        ctx: SampleContext::new(sampler, next(spp), spp),
                        film: Vec2::ZERO,
                    }
                })
                .collect();
            let draws = BatchDraws::new(&batch, samples);
            let wanted = next(1 << len).max(1);
            let depth = next(8);
            let j = next(samples);
            let dims = [Dim::lobe(depth), Dim::bounce(depth), Dim::light(depth, 1)];
            for dim in dims {
                let (one, two) = (draws.get_1d(dim, wanted), draws.get_2d(dim, wanted));
                let light = draws.light_2d(dim, samples, j, wanted);
                for i in mask_lanes(wanted) {
                    let ctx = &batch[i].ctx;
                    let (index, count) = (ctx.index(), ctx.count());
                    let s = &ctx.sampler;
                    let want_light = s.get_2d(dim, index * samples + j, count * samples);
                    assert_eq!(one[i].to_bits(), s.get_1d(dim, index, count).to_bits());
                    let want = s.get_2d(dim, index, count);
                    assert_eq!(
                        two[i].to_array().map(f32::to_bits),
                        want.to_array().map(f32::to_bits)
                    );
                    assert_eq!(
                        light[i].to_array().map(f32::to_bits),
                        want_light.to_array().map(f32::to_bits),
                        "round {round} lane {i}"
                    );
                }
            }
        }
    }

    /// Every wanted lane gets exactly its own sampler's draw, whatever mix
    /// of pixels, sample indices and set sizes the lanes hold, and the
    /// other lanes zero: batches of one pixel, of several pixels' samples,
    /// and lanes with a set size of their own.
    #[test]
    fn each_lane_draws_what_its_own_sampler_gives() {
        let mut state = 12345u32;
        let mut next = |n: u32| {
            state = state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            (state >> 8) % n
        };
        for round in 0..2000 {
            let kind = [SamplerKind::Stratified, SamplerKind::Random][round % 2];
            let pixels = 1 + next(4);
            let counts = [16, 5, 35, 1];
            let contexts: Vec<SampleContext> = (0..LANES)
                .map(|_| {
                    let pixel = next(pixels);
                    let spp = counts[(next(8) as usize).min(3) * (round / 2 % 2)];
                    let sampler = PixelSampler::new(kind, 7, pixel);
                    SampleContext::new(sampler, next(spp), spp)
                })
                .collect();
            let wanted = next(256);
            let dim = [Dim::LENS, Dim::light(1, 2)][round / 4 % 2];
            let at = |i: usize| (contexts[i].sample, contexts[i].spp);
            let drawn = draw_2d_lanes(wanted, |i| &contexts[i], dim, at);
            let drawn_1d = draw_1d_lanes(wanted, |i| &contexts[i], dim, at);
            for (i, x) in drawn_1d.iter().enumerate() {
                let expected = if wanted >> i & 1 == 1 {
                    let (index, count) = at(i);
                    contexts[i].sampler.get_1d(dim, index, count)
                } else {
                    0.0
                };
                assert_eq!(
                    x.to_bits(),
                    expected.to_bits(),
                    "round {round}, 1D lane {i}"
                );
            }
            for (i, point) in drawn.iter().enumerate() {
                let expected = if wanted >> i & 1 == 1 {
                    let (index, count) = at(i);
                    contexts[i].sampler.get_2d(dim, index, count)
                } else {
                    Vec2::ZERO
                };
                assert_eq!(
                    (point.x.to_bits(), point.y.to_bits()),
                    (expected.x.to_bits(), expected.y.to_bits()),
                    "round {round}, lane {i}"
                );
            }
        }
    }
}
