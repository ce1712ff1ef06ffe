//! One BVH over every bounded primitive.
//!
//! Our own PLOC (Meister and Bittner 2018; `ploc`: every pass in
//! parallel, the same tree on any thread count) builds a binary tree in
//! obvhs's layout, which obvhs's parallel reinsertion improves; the
//! fastest preset starts it from clusters of neighbouring primitives
//! (`cluster`), and `choice` says which preset a render gets. We collapse
//! the binary tree into an 8-wide layout of our own whose child boxes are plain f32 in structure-of-arrays form, so one
//! `wide::f32x8` slab test checks all eight children of a node. We traverse
//! it ourselves: obvhs's own traversal clamps tmin to 1e-4, uses a
//! non-watertight triangle test and drops nodes when its 32-entry stack
//! overflows. Ours honours `[tmin, tmax]`, uses the watertight test and
//! spills to the heap instead of dropping work.
//!
//! The walks are generic over what they ask at a node (`node_test`: a
//! ray's slab test, a whole line's, the distance to a point, or a
//! caller's own, which reads a node's child boxes and nothing else of
//! it) and at a leaf (`query`: closest hit, occlusion, every leaf), and
//! each traversal order is written once: one ray depth first, nearest
//! child first or in any order (`walk`, going down a node as `descend`
//! says, deferring children on a `stack`); several single-ray walks
//! `in_flight` on one thread, so that their cache misses overlap; best
//! first by distance (`nearest`); a `packet` of eight rays in lanes, for
//! the eight consecutive rays of a stream `narrow` enough to share a
//! walk; a `bundle` of up to 64 alike rays, node by node.

mod assemble;
mod binary;
pub mod build;
pub mod bundle;
pub mod choice;
mod cluster;
mod collapse;
mod descend;
pub mod hit;
pub mod in_flight;
mod lbvh;
pub mod narrow;
mod nearest;
mod node;
pub mod node_test;
pub mod packet;
mod ploc;
pub mod query;
mod reinsert;
mod simd;
mod stack;
mod validate;
mod walk;

pub use build::{BuildQuality, Bvh8, TreeStats};
pub use choice::BuildChoice;
pub use collapse::NO_PRIM;
pub use hit::PrimHit;
pub use nearest::NearestQueue;
pub use node_test::{ChildBoxes, NodeTest};
pub use packet::{Packet, PACKET_SIZE};
pub use query::{
    ClosestHit, ClosestHitPacket, EveryLeaf, Occlusion, OcclusionPacket, PacketQuery, Query,
};
pub use simd::kernel::Kernel;
pub use simd::{allocator, kernel, pages, prefetch};
pub use walk::{AnyOrder, NearestFirst, WalkOrder};
