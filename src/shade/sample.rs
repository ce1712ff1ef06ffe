//! What identifies one sample and what a render counts.

use crate::math::Ray;
use crate::sampling::spherical_rect8::{mask_lanes, LANES};
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

    pub fn add(&mut self, o: &RayCounts) {
        self.camera += o.camera;
        self.shadow += o.shadow;
        self.reflection += o.reflection;
        self.refraction += o.refraction;
        self.glossy_rejected += o.glossy_rejected;
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
/// exactly what its own sampler gives (zero in the other lanes). The lanes
/// that share the first wanted lane's numbers and set size (a batch's
/// samples of one pixel, or one sample's several draws) are drawn together
/// in SIMD lanes ([`crate::sampling::sampler::DimSampler::get_2d_lanes`]).
#[inline]
pub(super) fn draw_2d_lanes<'c>(
    wanted: u32,
    ctx_of: impl Fn(usize) -> &'c SampleContext,
    dim: Dim,
    at: impl Fn(usize) -> (u32, u32),
) -> [Vec2; LANES] {
    let mut points = [Vec2::ZERO; LANES];
    if wanted == 0 {
        return points;
    }
    let first_lane = wanted.trailing_zeros() as usize;
    let first = ctx_of(first_lane);
    let (first_index, count) = at(first_lane);
    let mut index = [first_index; LANES];
    let mut sharing = 0u32;
    for i in mask_lanes(wanted) {
        let ctx = ctx_of(i);
        let (i_index, i_count) = at(i);
        if i_count == count && ctx.sampler.same_numbers(&first.sampler) {
            sharing |= 1 << i;
            index[i] = i_index;
        } else {
            points[i] = ctx.sampler.get_2d(dim, i_index, i_count);
        }
    }
    let drawn = first
        .sampler
        .dim_2d(dim, count)
        .get_2d_lanes(index, sharing);
    for i in mask_lanes(sharing) {
        points[i] = drawn[i];
    }
    points
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
