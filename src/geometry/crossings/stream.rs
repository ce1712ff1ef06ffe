//! The crossings of many rays at once: counts and lists for the mesh
//! queries of a binding (`count_hits`, `contains`, `all_hits`), each ray's
//! walk that of [`Geometry::crossings`], several in flight on a tree that
//! outgrows the caches.
//!
//! A crossing walk never ends early, so it reads every node its ray
//! passes, and on a tree the caches do not hold (the dragon) most of
//! those reads wait for memory. Sixteen walks in flight
//! ([`CROSSINGS_IN_FLIGHT`]) overlap those waits
//! ([`crate::accel::in_flight`]; Kocberber, Falsafi and Grot 2015,
//! "Asynchronous Memory Access Chaining"), as a stream's closest hits'
//! eight do.
//! Each walk takes the steps of its ray's own walk (the same node test,
//! the same order: any, unsorted), so each ray meets the same leaves and
//! the same crossings, bit for bit; a list is sorted as
//! [`Geometry::crossings`] sorts it. On a tree that fits the caches there is no wait to overlap,
//! and rays walk one at a time, as a stream's do there
//! ([`crate::geometry::travel`]).

use super::{Crossing, CONTAINS_DIRECTION};
use crate::accel::{AnyOrder, Query};
use crate::geometry::Geometry;
use crate::math::Ray;
use crate::shape::triangle::ShearedRay;

/// Crossing walks in flight at once: twice a closest hit's
/// [`crate::accel::IN_FLIGHT`]. A crossing walk never ends early, so no
/// walk's slot idles on a ray that finished after a few nodes, and more
/// waits overlap: `count_hits` on the dragon (200,000 random rays, one
/// thread) took 5% less time than with 8 (medians of six interleaved runs
/// of 15; 12 gained less, 20 no more). On an Intel Xeon with 2 MB of L2
/// a core (two threads, four alternating rounds of 21 calls), 12 took 5%
/// more time than 16 and 24 the same (count_hits 0.7% less, all_hits 2%
/// more).
const CROSSINGS_IN_FLIGHT: usize = 16;

/// The walk's question for a count: the crossings of each leaf, counted
/// in the walk's own state.
struct CountCrossings<'g> {
    geometry: &'g Geometry,
}

impl Query for CountCrossings<'_> {
    type State = (ShearedRay, u32);
    type Answer = u32;
    const SHORTENS: bool = false;

    #[inline(always)]
    fn start(&mut self, ray: &Ray) -> (ShearedRay, u32) {
        (ShearedRay::new(ray), 0)
    }

    #[inline(always)]
    fn leaf(&mut self, s: &mut (ShearedRay, u32), start: u32, count: u32, ray: &mut Ray) -> bool {
        let (sheared, n) = (&s.0, &mut s.1);
        self.geometry
            .crossings_in_leaf(start, count, ray, sheared, &mut |_| *n += 1);
        false
    }

    #[inline(always)]
    fn answer(&mut self, s: &(ShearedRay, u32), _: bool) -> u32 {
        s.1
    }
}

/// The walk's question for a list: each walk gathers its ray's crossings
/// in a list of its own (a slot, reused by the next ray that walk takes),
/// and its answer moves them, sorted, to the end of `out` and says where
/// they lie there.
struct ListCrossings<'g, 'o> {
    geometry: &'g Geometry,
    /// One list per walk under way (a few more: walks that were set up
    /// and replaced before their first step keep theirs).
    slots: Vec<Vec<Crossing>>,
    /// The slots no walk holds.
    free: Vec<u32>,
    out: &'o mut Vec<Crossing>,
}

impl Query for ListCrossings<'_, '_> {
    type State = (ShearedRay, u32);
    /// Where in `out` the ray's crossings lie: first index and count.
    type Answer = (usize, u32);
    const SHORTENS: bool = false;

    #[inline(always)]
    fn start(&mut self, ray: &Ray) -> (ShearedRay, u32) {
        let slot = self.free.pop().unwrap_or_else(|| {
            self.slots.push(Vec::new());
            self.slots.len() as u32 - 1
        });
        self.slots[slot as usize].clear();
        (ShearedRay::new(ray), slot)
    }

    #[inline(always)]
    fn leaf(&mut self, s: &mut (ShearedRay, u32), start: u32, count: u32, ray: &mut Ray) -> bool {
        let list = &mut self.slots[s.1 as usize];
        self.geometry
            .crossings_in_leaf(start, count, ray, &s.0, &mut |c| list.push(c));
        false
    }

    fn answer(&mut self, s: &(ShearedRay, u32), _: bool) -> (usize, u32) {
        let list = &mut self.slots[s.1 as usize];
        let g = self.geometry;
        list.sort_unstable_by(|a, b| g.crossing_order(a, b));
        let first = self.out.len();
        self.out.extend_from_slice(list);
        self.free.push(s.1);
        (first, list.len() as u32)
    }
}

impl Geometry {
    /// `out[i] = self.count_crossings(&rays[i])`, the rays several in
    /// flight where the tree prefetches (module docs).
    ///
    /// Never inlined: compiled here, once, as the library's own callers
    /// run it. Small at its source, it was otherwise compiled again inside
    /// each crate that calls it, and the Python package's copy, inlined
    /// into its thread pool's closure, walked the dragon's rays 1.8 times
    /// slower than this one (docs/python.md, "Against embreex and Open3D").
    #[inline(never)]
    pub fn count_crossings_stream(&self, rays: &[Ray], out: &mut [u32]) {
        assert_eq!(rays.len(), out.len(), "one count per ray");
        if !self.bvh.prefetch {
            for (o, ray) in out.iter_mut().zip(rays) {
                *o = self.count_crossings(ray);
            }
            return;
        }
        let mut query = CountCrossings { geometry: self };
        self.bvh.walk_in_flight_by::<_, _, _, CROSSINGS_IN_FLIGHT>(
            rays,
            AnyOrder,
            &self.leaf_blocks,
            &mut query,
            out,
            |_| false,
        );
    }

    /// `out[i] = self.contains(points[i])`, the rays from the points
    /// walked as [`Geometry::count_crossings_stream`] walks them.
    pub fn contains_stream(&self, points: &[glam::Vec3], out: &mut [bool]) {
        assert_eq!(points.len(), out.len(), "one answer per point");
        const PART: usize = 256;
        let mut counts = [0u32; PART];
        for (points, out) in points.chunks(PART).zip(out.chunks_mut(PART)) {
            let rays: [Ray; PART] = std::array::from_fn(|i| {
                Ray::new(
                    points.get(i).copied().unwrap_or_default(),
                    CONTAINS_DIRECTION,
                )
            });
            let counts = &mut counts[..points.len()];
            self.count_crossings_stream(&rays[..points.len()], counts);
            for (o, n) in out.iter_mut().zip(counts.iter()) {
                *o = n % 2 == 1;
            }
        }
    }

    /// Every crossing of each ray of `rays`, as [`Geometry::crossings`]
    /// lists it, appended to `out`: ray `i`'s are `out[first..first + n]`
    /// for `(first, n) = spans[i]`, sorted as that function sorts them (the
    /// rays' lists themselves lie in `out` in the order their walks end).
    /// Several in flight where the tree prefetches (module docs). Never
    /// inlined, as [`Geometry::count_crossings_stream`].
    #[inline(never)]
    pub fn crossings_stream(
        &self,
        rays: &[Ray],
        out: &mut Vec<Crossing>,
        spans: &mut [(usize, u32)],
    ) {
        assert_eq!(rays.len(), spans.len(), "one span per ray");
        if !self.bvh.prefetch {
            for (span, ray) in spans.iter_mut().zip(rays) {
                let first = out.len();
                self.crossings(ray, out);
                *span = (first, (out.len() - first) as u32);
            }
            return;
        }
        let mut query = ListCrossings {
            geometry: self,
            slots: Vec::new(),
            free: Vec::new(),
            out,
        };
        self.bvh.walk_in_flight_by::<_, _, _, CROSSINGS_IN_FLIGHT>(
            rays,
            AnyOrder,
            &self.leaf_blocks,
            &mut query,
            spans,
            |_| false,
        );
    }
}
