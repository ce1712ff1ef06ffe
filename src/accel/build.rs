//! Building: obvhs PLOC into a binary tree, then a greedy collapse into
//! 8-wide nodes (largest-area child opened first, the rule of Wald, Benthin
//! and Boulos 2008, "Getting Rid of Packets").

use super::node::{encode_leaf, Node8, EMPTY, MAX_LEAF_PRIMS, MAX_PRIMS};
use crate::math::Aabb;
use crate::shape::triangle8::NO_PRIM;
use glam::Vec3A;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::Bvh2;
use obvhs::ploc::PlocBuilder;
use obvhs::BvhBuildParams;

/// Build effort. `auto` picks by primitive count: the better presets pay
/// off on big meshes only if rays outnumber triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BuildQuality {
    Fastest,
    Fast,
    #[default]
    Auto,
    Medium,
    High,
}

impl std::str::FromStr for BuildQuality {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "fastest" => Ok(Self::Fastest),
            "fast" => Ok(Self::Fast),
            "auto" => Ok(Self::Auto),
            "medium" => Ok(Self::Medium),
            "high" => Ok(Self::High),
            _ => Err(format!(
                "unknown BVH quality '{s}' (expected fastest, fast, auto, medium or high)"
            )),
        }
    }
}

impl BuildQuality {
    fn params(self, prim_count: usize) -> BvhBuildParams {
        match self {
            Self::Fastest => BvhBuildParams::fastest_build(),
            Self::Fast => BvhBuildParams::fast_build(),
            Self::Medium => BvhBuildParams::medium_build(),
            Self::High => BvhBuildParams::slow_build(),
            Self::Auto if prim_count > 2_000_000 => BvhBuildParams::fast_build(),
            Self::Auto => BvhBuildParams::medium_build(),
        }
    }
}

/// The 8-wide BVH. `prim_ids` lists primitive ids in leaf order, in
/// blocks of [`LEAF_BLOCK`] slots that no leaf straddles; unused slots
/// hold [`NO_PRIM`].
#[derive(Debug, Clone)]
pub struct Bvh8 {
    pub nodes: Vec<Node8>,
    pub prim_ids: Vec<u32>,
    pub bounds: Aabb,
    /// Deepest node level, for sizing traversal stacks.
    pub depth: u32,
}

impl Bvh8 {
    pub fn empty() -> Self {
        Self {
            nodes: Vec::new(),
            prim_ids: Vec::new(),
            bounds: Aabb::EMPTY,
            depth: 0,
        }
    }

    /// Build over primitive boxes; primitive `i` is reported as id `i`.
    /// Boxes must be finite (the scene compiler rejects the rest).
    pub fn build(boxes: &[Aabb], quality: BuildQuality) -> Self {
        if boxes.is_empty() {
            return Self::empty();
        }
        assert!(
            boxes.len() <= MAX_PRIMS,
            "too many primitives for one BVH: {}",
            boxes.len()
        );
        let params = quality.params(boxes.len());
        // obvhs reads our boxes through `Boundable`: no converted copy
        // (32 bytes a primitive) at the build's memory peak.
        let mut bvh2 = PlocBuilder::with_capacity(boxes.len()).build(
            params.ploc_search_distance,
            boxes,
            (0..boxes.len() as u32).collect(),
            params.sort_precision,
            params.search_depth_threshold,
        );
        if params.reinsertion_batch_ratio > 0.0 {
            ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
        }
        let mut out = Self {
            nodes: Vec::with_capacity(bvh2.nodes.len() / 4 + 1),
            prim_ids: Vec::with_capacity(boxes.len()),
            bounds: boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b)),
            depth: 0,
        };
        let counts = subtree_counts(&bvh2);
        let mut collapse = Collapse {
            bvh2: &bvh2,
            counts: &counts,
            out: &mut out,
            packer: LanePacker::default(),
        };
        collapse.root();
        out
    }

    /// Bytes held by the final structure.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node8>() + self.prim_ids.len() * 4
    }
}

impl obvhs::Boundable for Aabb {
    #[inline]
    fn aabb(&self) -> obvhs::aabb::Aabb {
        obvhs::aabb::Aabb {
            min: Vec3A::from(self.min),
            max: Vec3A::from(self.max),
        }
    }
}

/// Primitive count under every BVH2 node (iterative: trees can be deep).
fn subtree_counts(bvh2: &Bvh2) -> Vec<u32> {
    let n = bvh2.nodes.len();
    let mut counts = vec![0u32; n];
    // Post-order by an explicit stack.
    let mut order = Vec::with_capacity(n);
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        order.push(i);
        let node = &bvh2.nodes[i];
        if node.prim_count == 0 {
            stack.push(node.first_index as usize);
            stack.push(node.first_index as usize + 1);
        }
    }
    for &i in order.iter().rev() {
        let node = &bvh2.nodes[i];
        counts[i] = if node.prim_count > 0 {
            node.prim_count
        } else {
            counts[node.first_index as usize] + counts[node.first_index as usize + 1]
        };
    }
    counts
}

struct Collapse<'a> {
    bvh2: &'a Bvh2,
    counts: &'a [u32],
    out: &'a mut Bvh8,
    packer: LanePacker,
}

impl Collapse<'_> {
    fn is_leaf_candidate(&self, i: usize) -> bool {
        let node = &self.bvh2.nodes[i];
        node.prim_count > 0 || self.counts[i] <= LEAF_PRIMS
    }

    fn root(&mut self) {
        self.out.nodes.push(Node8::EMPTY);
        // Work list of (BVH2 node, Node8 slot to fill, depth): iterative, so
        // degenerate deep trees cannot overflow the call stack.
        let mut work = vec![(0usize, 0usize, 1u32)];
        while let Some((src, dst, depth)) = work.pop() {
            self.out.depth = self.out.depth.max(depth);
            let children = self.open(src);
            for (slot, &c) in children.iter().enumerate() {
                let b = self.bvh2.nodes[c].aabb;
                let node = &mut self.out.nodes[dst];
                for axis in 0..3 {
                    node.bounds[2 * axis][slot] = b.min[axis];
                    node.bounds[2 * axis + 1][slot] = b.max[axis];
                }
                if self.is_leaf_candidate(c) {
                    let prims = self.gather_prims(c);
                    let start = self.packer.place(&prims, &mut self.out.prim_ids);
                    self.out.nodes[dst].child[slot] = encode_leaf(start, prims.len() as u32);
                } else {
                    let new = self.out.nodes.len();
                    self.out.nodes.push(Node8::EMPTY);
                    self.out.nodes[dst].child[slot] = new as u32;
                    work.push((c, new, depth + 1));
                }
            }
            debug_assert!(self.out.nodes[dst].child.iter().any(|&c| c != EMPTY));
        }
    }

    /// The up-to-8 BVH2 nodes that become children of one Node8: start from
    /// `src`'s children and keep opening the one with the largest area.
    fn open(&self, src: usize) -> Vec<usize> {
        let node = &self.bvh2.nodes[src];
        if node.prim_count > 0 || self.is_leaf_candidate(src) && src == 0 {
            return vec![src];
        }
        let mut children = vec![node.first_index as usize, node.first_index as usize + 1];
        while children.len() < 8 {
            let best = children
                .iter()
                .enumerate()
                .filter(|(_, &c)| self.bvh2.nodes[c].prim_count == 0)
                .max_by(|a, b| {
                    self.bvh2.nodes[*a.1]
                        .aabb
                        .half_area()
                        .total_cmp(&self.bvh2.nodes[*b.1].aabb.half_area())
                })
                .map(|(i, _)| i);
            let Some(i) = best else { break };
            let c = children.swap_remove(i);
            let first = self.bvh2.nodes[c].first_index as usize;
            children.push(first);
            children.push(first + 1);
        }
        children
    }

    fn gather_prims(&self, i: usize) -> Vec<u32> {
        let mut prims = Vec::with_capacity(LEAF_PRIMS as usize);
        let mut stack = vec![i];
        while let Some(i) = stack.pop() {
            let node = &self.bvh2.nodes[i];
            if node.prim_count > 0 {
                let s = node.first_index as usize;
                prims.extend_from_slice(
                    &self.bvh2.primitive_indices[s..s + node.prim_count as usize],
                );
            } else {
                stack.push(node.first_index as usize + 1);
                stack.push(node.first_index as usize);
            }
        }
        prims
    }
}

/// Places leaves into blocks of [`LEAF_BLOCK`] slots so that no leaf
/// straddles two blocks: a leaf is then one 8-wide triangle test over one
/// contiguous block (see `shape::triangle8`). First fit among the last few
/// blocks that still have room keeps the padding small (a fraction of a
/// percent on scanned meshes) and keeps leaves that are near in the tree
/// near in memory.
#[derive(Default)]
struct LanePacker {
    /// Blocks with free slots: (first free slot, end of block).
    open: Vec<(u32, u32)>,
}

impl LanePacker {
    /// Blocks kept open for first fit.
    const OPEN_BLOCKS: usize = 8;

    /// Writes `prims` into free slots of `prim_ids` (growing it by whole
    /// blocks padded with [`NO_PRIM`]) and returns the first slot.
    fn place(&mut self, prims: &[u32], prim_ids: &mut Vec<u32>) -> u32 {
        let n = prims.len() as u32;
        let i = match self.open.iter().position(|&(free, end)| end - free >= n) {
            Some(i) => i,
            None => {
                let start = prim_ids.len() as u32;
                prim_ids.resize(prim_ids.len() + LEAF_BLOCK, NO_PRIM);
                if self.open.len() == Self::OPEN_BLOCKS {
                    self.open.remove(0);
                }
                self.open.push((start, start + LEAF_BLOCK as u32));
                self.open.len() - 1
            }
        };
        let start = self.open[i].0;
        prim_ids[start as usize..(start + n) as usize].copy_from_slice(prims);
        self.open[i].0 += n;
        if self.open[i].0 == self.open[i].1 {
            self.open.remove(i);
        }
        start
    }
}

/// Slots per leaf block: one `f32x8` lane each.
pub const LEAF_BLOCK: usize = crate::shape::triangle8::LANES;

/// Subtrees with at most this many primitives become one leaf.
const LEAF_PRIMS: u32 = 8;
const _: () = assert!(LEAF_PRIMS <= MAX_LEAF_PRIMS && LEAF_PRIMS as usize <= LEAF_BLOCK);
