//! A bundle's or a packet's rays at a leaf that holds instances: the rays
//! that may meet one instance enter its prototype together, as a bundle
//! of their own ([`crate::accel::bundle`]), where one at a time each would
//! pay a lone walk's setup and read the prototype's top nodes again
//! (Embree walks an instance's prototype one ray at a time). Alike rays (a
//! camera's, a light's shadow rays) that reach one instance share the
//! prototype's upper nodes. On a field of 1,000 dragons
//! (`tools/bench_instances.py`) this traced camera rays 12% faster on two
//! threads and 5% on one (docs/performance.md, "Instancing").
//!
//! Each ray's answer is the one its lone walk gives: a leaf's own
//! triangles and shapes are tested ray by ray as [`Geometry::hit_leaf`]
//! tests them, and each instance's prototype is walked with the ray its
//! own test would use, by a bundle, whose answers are the single walks'
//! bit for bit. The closest hit is the least of the same candidates in a
//! total order ([`crate::accel::hit::closer`]) whichever instance is
//! tested first; an occlusion is a yes or no.

use super::instance::Instance;
use super::query::{leaf_ray, OcclusionState};
use super::Geometry;
use crate::accel::bundle::BUNDLE_SIZE;
use crate::accel::query::{keep_closer, ClosestState};
use crate::accel::PrimHit;
use crate::math::Ray;
use crate::shape::triangle::ShearedRay;

/// A leaf's block, the slots of its own primitives (triangles, shapes)
/// and the slots of its instances.
#[derive(Clone, Copy)]
pub(super) struct LeafParts {
    block: usize,
    own: u32,
    instances: u32,
}

/// The rays of a bundle or a packet that may meet one instance, in its
/// prototype's object space, and which ray of the bundle or packet each
/// is.
struct Gathered {
    rays: [Ray; BUNDLE_SIZE],
    of: [u8; BUNDLE_SIZE],
    len: usize,
}

impl Gathered {
    /// The rays `ray_of(i)` of the lanes `i` of `mask` (`None`: a lane to
    /// skip) that may meet `instance` ([`Instance::may_hit`]), moved into
    /// its object space.
    #[inline(always)]
    fn meeting(instance: &Instance, mask: u64, ray_of: impl Fn(usize) -> Option<Ray>) -> Self {
        let mut gathered = Self {
            rays: [Ray::new(glam::Vec3::ZERO, glam::Vec3::Z); BUNDLE_SIZE],
            of: [0; BUNDLE_SIZE],
            len: 0,
        };
        for i in bits(mask) {
            if let Some(ray) = ray_of(i) {
                if instance.may_hit(&ray) {
                    gathered.rays[gathered.len] = instance.object_ray(&ray);
                    gathered.of[gathered.len] = i as u8;
                    gathered.len += 1;
                }
            }
        }
        gathered
    }
}

/// What [`Geometry::hit_instance_rays`] found: each gathered ray's hit
/// on the instance, if any, with the ray's lane.
pub(super) struct InstanceHits {
    id: u32,
    found: [Option<PrimHit>; BUNDLE_SIZE],
    of: [u8; BUNDLE_SIZE],
    len: usize,
}

impl InstanceHits {
    /// Each hit, as the instance's (`prim` its id), with its ray's lane.
    pub(super) fn hits(&self) -> impl Iterator<Item = (usize, PrimHit)> + '_ {
        (0..self.len).filter_map(|k| {
            let hit = self.found[k]?;
            Some((
                self.of[k] as usize,
                PrimHit {
                    prim: self.id,
                    ..hit
                },
            ))
        })
    }
}

/// The bits of `mask`, lowest first.
#[inline(always)]
fn bits(mut mask: u64) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            i
        })
    })
}

impl Geometry {
    /// The parts of leaf `start..start + count` where the bundle's rays
    /// `mask` enter its instances together: `None` where the leaf holds
    /// no instance or one ray reaches it (its own leaf test is the same
    /// work).
    #[inline(always)]
    pub(super) fn instance_parts(&self, start: u32, count: u32, mask: u64) -> Option<LeafParts> {
        if self.instances.is_empty() || mask & mask.wrapping_sub(1) == 0 {
            return None;
        }
        let (block, lanes) = Self::leaf_lanes(start, count);
        let ids = &self.leaf_blocks[block].id;
        let first = self.first_instance();
        let mut instances = 0u32;
        let mut m = lanes;
        while m != 0 {
            let lane = m.trailing_zeros() as usize;
            m &= m - 1;
            if ids[lane] >= first {
                instances |= 1 << lane;
            }
        }
        (instances != 0).then_some(LeafParts {
            block,
            own: lanes & !instances,
            instances,
        })
    }

    /// The closest-hit leaf test of the bundle's rays `mask` (ray `i`:
    /// `rays[i]` ending at `ends[i]`, its state `states[i]`) at a leaf of
    /// `parts`, each instance's prototype entered by its rays together.
    /// Lowers each ray's end to the hit it keeps, as the query's own leaf
    /// test does.
    pub(super) fn hit_leaf_together<const CLOSED: bool>(
        &self,
        states: &mut [Option<ClosestState<Option<ShearedRay>>>],
        rays: &[Ray],
        ends: &mut [f32],
        parts: LeafParts,
        mask: u64,
    ) {
        if parts.own != 0 {
            for i in bits(mask) {
                let Some(state) = &mut states[i] else {
                    continue;
                };
                let mut ray = Ray {
                    tmax: ends[i],
                    ..rays[i]
                };
                let test = leaf_ray::<CLOSED>(&ray, state.best.as_ref());
                let sheared = state.leaf.get_or_insert_with(|| ShearedRay::new(&test));
                let hit = self.hit_lanes(parts.block, parts.own, &test, sheared);
                keep_closer(&mut state.best, &mut ray, hit);
                ends[i] = ray.tmax;
            }
        }
        for lane in bits(parts.instances as u64) {
            let id = self.leaf_blocks[parts.block].id[lane];
            let test = |i: usize| {
                let state = states[i].as_ref()?;
                let ray = Ray {
                    tmax: ends[i],
                    ..rays[i]
                };
                Some(leaf_ray::<CLOSED>(&ray, state.best.as_ref()))
            };
            let found = self.hit_instance_rays(id, mask, test);
            for (i, hit) in found.hits() {
                let Some(state) = &mut states[i] else {
                    continue;
                };
                let mut ray = Ray {
                    tmax: ends[i],
                    ..rays[i]
                };
                keep_closer(&mut state.best, &mut ray, Some(hit));
                ends[i] = ray.tmax;
            }
        }
    }

    /// The occlusion leaf test of the bundle's rays `mask` at a leaf of
    /// `parts`, skipping primitive `except`: the rays blocked, each
    /// instance's prototype entered by the rays still open together.
    /// `CLOSED` as for [`super::query`]'s occlusion query: a ray is tested
    /// up to its state's end, else up to its own.
    pub(super) fn blocks_leaf_together<const CLOSED: bool>(
        &self,
        states: &[Option<OcclusionState>],
        rays: &[Ray],
        parts: LeafParts,
        mask: u64,
        except: u32,
    ) -> u64 {
        let test = |i: usize, state: &OcclusionState| Ray {
            tmax: if CLOSED { state.tmax } else { rays[i].tmax },
            ..rays[i]
        };
        let mut open = 0u64;
        for i in bits(mask) {
            let Some(state) = &states[i] else { continue };
            let blocked = parts.own != 0
                && self.blocks_lanes(
                    parts.block,
                    parts.own,
                    &test(i, state),
                    &state.sheared,
                    except,
                );
            if !blocked {
                open |= 1 << i;
            }
        }
        for lane in bits(parts.instances as u64) {
            let id = self.leaf_blocks[parts.block].id[lane];
            if id != except && open != 0 {
                open &= !self.instance_blocks_rays(id, open, |i| {
                    states[i].as_ref().map(|state| test(i, state))
                });
            }
        }
        mask & !open
    }

    /// The hits of instance `id` for the rays `ray_of(i)` of the lanes
    /// `i` of `mask` (`None`: a lane to skip), each
    /// [`Geometry::hit_instance`]'s for its ray; those that may meet the
    /// instance enter its prototype together where
    /// [`Geometry::enter_together`] says. Returns each ray's hit, if any,
    /// with the ray's lane.
    #[inline(always)]
    pub(super) fn hit_instance_rays(
        &self,
        id: u32,
        mask: u64,
        ray_of: impl Fn(usize) -> Option<Ray>,
    ) -> InstanceHits {
        let (instance, prototype) = self.instance(id);
        let gathered = Gathered::meeting(instance, mask, ray_of);
        let n = gathered.len;
        let mut found = [None; BUNDLE_SIZE];
        prototype.intersect_open_end_rays(&gathered.rays[..n], &mut found[..n]);
        InstanceHits {
            id,
            found,
            of: gathered.of,
            len: n,
        }
    }

    /// The lanes `i` of `mask` whose rays `ray_of(i)` instance `id` blocks,
    /// each [`Geometry::instance_blocks`]'s answer, the rays that may meet
    /// it entering its prototype together as for
    /// [`Geometry::hit_instance_rays`].
    #[inline(always)]
    pub(super) fn instance_blocks_rays(
        &self,
        id: u32,
        mask: u64,
        ray_of: impl Fn(usize) -> Option<Ray>,
    ) -> u64 {
        let (instance, prototype) = self.instance(id);
        let gathered = Gathered::meeting(instance, mask, ray_of);
        let n = gathered.len;
        let mut blocked = [false; BUNDLE_SIZE];
        prototype.occluded_open_end_rays(&gathered.rays[..n], &mut blocked[..n]);
        let mut lanes = 0u64;
        for (&i, &b) in gathered.of[..n].iter().zip(&blocked[..n]) {
            lanes |= (b as u64) << i;
        }
        lanes
    }
}
