//! The 8-wide tree made of the parts the collapse emits in parallel
//! ([`super::collapse`]): each part's nodes and leaf blocks copied once
//! into the whole tree, and the packing of a part's leaves into blocks of
//! [`LANES`] slots.

use super::build::Bvh8;
use super::collapse::NO_PRIM;
use super::node::{encode_leaf, is_leaf, leaf_range, Node8, EMPTY};
use super::simd::pages::Pages;
use crate::math::lanes::LANES;
use crate::math::Aabb;
use rayon::prelude::*;

/// A subtree of the 8-wide tree: its nodes, the first its root, with
/// child references local to it, and its leaves' slots; and the subtrees
/// made in parallel under its root's slots, each a part of its own.
#[derive(Default)]
pub(super) struct Part {
    pub(super) nodes: Vec<Node8>,
    pub(super) prim_ids: Vec<u32>,
    pub(super) depth: u32,
    pub(super) packer: LanePacker,
    pub(super) subs: Vec<(usize, Part)>,
}

/// Where a part's nodes and slots start in the whole tree, and the root
/// slots that refer to its subtrees' roots there.
struct Placed<'p> {
    part: &'p Part,
    node_base: u32,
    slot_base: u32,
    links: Vec<(usize, u32)>,
}

impl Part {
    /// The whole tree, whose root box is `bounds`: every part in the
    /// order of nested appends (a part's nodes, then each of its subtrees
    /// in slot order, likewise), its references moved by where its nodes
    /// and slots start, each copied once and all in parallel. Slots move
    /// by whole blocks: every part's `prim_ids` is a whole number of them.
    pub(super) fn into_bvh(self, bounds: Aabb) -> Bvh8 {
        let mut placed = Vec::new();
        let (mut nodes, mut slots) = (0, 0);
        let depth = self.place(&mut nodes, &mut slots, &mut placed);
        let mut all_nodes: Vec<Node8> = (0..nodes).into_par_iter().map(|_| Node8::EMPTY).collect();
        let mut prim_ids = vec![0u32; slots as usize];
        let mut pieces = Vec::with_capacity(placed.len());
        let (mut node_rest, mut slot_rest) = (&mut all_nodes[..], &mut prim_ids[..]);
        for p in &placed {
            let (n, tail) = std::mem::take(&mut node_rest).split_at_mut(p.part.nodes.len());
            node_rest = tail;
            let (s, tail) = std::mem::take(&mut slot_rest).split_at_mut(p.part.prim_ids.len());
            slot_rest = tail;
            pieces.push((n, s));
        }
        placed
            .par_iter()
            .zip(pieces)
            .for_each(|(p, (nodes, slots))| {
                for (out, node) in nodes.iter_mut().zip(&p.part.nodes) {
                    *out = *node;
                    for c in &mut out.child {
                        if *c == EMPTY {
                            continue;
                        }
                        *c = if is_leaf(*c) {
                            let (start, count) = leaf_range(*c);
                            encode_leaf(start + p.slot_base, count)
                        } else {
                            *c + p.node_base
                        };
                    }
                }
                for &(slot, root) in &p.links {
                    nodes[0].child[slot] = root;
                }
                slots.copy_from_slice(&p.part.prim_ids);
            });
        Bvh8 {
            nodes: all_nodes,
            prim_ids,
            bounds,
            depth,
            prefetch: true,
            pages: Pages::Small,
        }
    }

    /// Lays this part out from node `nodes` and slot `slots` (moved past
    /// it and its subtrees) into `placed`; returns its depth.
    fn place<'p>(&'p self, nodes: &mut u32, slots: &mut u32, placed: &mut Vec<Placed<'p>>) -> u32 {
        let at = placed.len();
        placed.push(Placed {
            part: self,
            node_base: *nodes,
            slot_base: *slots,
            links: Vec::new(),
        });
        *nodes += self.nodes.len() as u32;
        *slots += self.prim_ids.len() as u32;
        let mut depth = self.depth;
        for (slot, sub) in &self.subs {
            let root = *nodes;
            depth = depth.max(sub.place(nodes, slots, placed) + 1);
            placed[at].links.push((*slot, root));
        }
        depth
    }
}

/// Places leaves into blocks of [`LANES`] slots so that no leaf
/// straddles two blocks: a leaf is then one 8-wide triangle test over one
/// contiguous block (see `shape::triangle_lanes`). First fit among the last few
/// blocks that still have room keeps the padding small (a fraction of a
/// percent on scanned meshes) and keeps leaves that are near in the tree
/// near in memory.
#[derive(Default)]
pub(super) struct LanePacker {
    /// Blocks with free slots: (first free slot, end of block).
    open: Vec<(u32, u32)>,
}

impl LanePacker {
    /// Blocks kept open for first fit.
    const OPEN_BLOCKS: usize = 8;

    /// Writes `prims` into free slots of `prim_ids` (growing it by whole
    /// blocks padded with [`NO_PRIM`]) and returns the first slot.
    pub(super) fn place(&mut self, prims: &[u32], prim_ids: &mut Vec<u32>) -> u32 {
        let n = prims.len() as u32;
        let i = match self.open.iter().position(|&(free, end)| end - free >= n) {
            Some(i) => i,
            None => {
                let start = prim_ids.len() as u32;
                prim_ids.resize(prim_ids.len() + LANES, NO_PRIM);
                if self.open.len() == Self::OPEN_BLOCKS {
                    self.open.remove(0);
                }
                self.open.push((start, start + LANES as u32));
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
