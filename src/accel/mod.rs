//! One BVH over every bounded primitive.
//!
//! obvhs builds the tree (PLOC, Meister and Bittner 2018, with parallel
//! reinsertion; the fastest preset starts it from clusters of neighbouring
//! primitives, `cluster`); we collapse its binary tree into an 8-wide layout of our
//! own whose child boxes are plain f32 in structure-of-arrays form, so one
//! `wide::f32x8` slab test checks all eight children of a node. We traverse
//! it ourselves: obvhs's own traversal clamps tmin to 1e-4, uses a
//! non-watertight triangle test and drops nodes when its 32-entry stack
//! overflows. Ours honours `[tmin, tmax]`, uses the watertight test and
//! spills to the heap instead of dropping work. Given many rays at once,
//! `stream` keeps several single-ray walks in flight on one thread so
//! that their cache misses overlap, `beam` sends the groups of rays
//! narrow enough to share a walk through `packet` instead, and `bundle`
//! walks up to 64 alike rays together, node by node.

pub mod beam;
pub mod build;
pub mod bundle;
mod cluster;
mod collapse;
pub mod hit;
pub mod node;
pub mod packet;
pub mod prefetch;
pub mod stream;
pub mod traverse;
mod validate;
mod walk;

pub use build::{BuildQuality, Bvh8, TreeStats};
pub use collapse::{LEAF_BLOCK, NO_PRIM};
pub use hit::PrimHit;
pub use packet::{Packet, PACKET_SIZE};
