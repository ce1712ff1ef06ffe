//! Points made vertices by their exact position: one id per distinct
//! position, numbered in order of first use, +0 and −0 one place. What a
//! file that lists every triangle's own corners (STL) and a set of loose
//! triangles (`rays::topology`, CSG's closed-mesh check) are welded by.
//!
//! The map from a position to its id hashes by [`PositionHasher`], not by
//! the standard library's SipHash: SipHash is keyed against collisions an
//! attacker crafts (a denial of service on a web server's tables), which
//! a mesh read here cannot cost anyone but its reader, and its rounds
//! were a third of the weld of a 14-million-triangle STL
//! (docs/performance.md, "One weld").

use glam::{DVec3, Vec3};
use std::collections::hash_map::{Entry, HashMap};
use std::hash::{BuildHasherDefault, Hash, Hasher};

/// A float32 position's key: its coordinates' bits, −0 made +0.
#[inline]
pub fn key(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// A float64 position's key: its coordinates' bits, −0 made +0.
#[inline]
pub fn exact_key(p: DVec3) -> [u64; 3] {
    (p + DVec3::ZERO).to_array().map(f64::to_bits)
}

/// One id per distinct key ([`key`] or [`exact_key`]), in order of first
/// use.
#[derive(Debug, Clone)]
pub struct Welder<K> {
    ids: HashMap<K, u32, BuildHasherDefault<PositionHasher>>,
}

impl<K> Default for Welder<K> {
    fn default() -> Self {
        Self {
            ids: HashMap::default(),
        }
    }
}

impl<K: Hash + Eq> Welder<K> {
    /// A welder with room for `n` distinct positions before it grows.
    pub fn with_capacity(n: usize) -> Self {
        Self {
            ids: HashMap::with_capacity_and_hasher(n, Default::default()),
        }
    }

    /// The id of the position `key`, and whether this is its first use (its
    /// id then the next: as many as were welded before).
    #[inline]
    pub fn id(&mut self, key: K) -> (u32, bool) {
        let next = self.ids.len() as u32;
        match self.ids.entry(key) {
            Entry::Occupied(e) => (*e.get(), false),
            Entry::Vacant(e) => (*e.insert(next), true),
        }
    }

    /// How many distinct positions were welded.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// Whether no position was welded.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Forgets every position (keeping the room), for the next mesh.
    pub fn clear(&mut self) {
        self.ids.clear();
    }
}

/// The hash of a position's key: its words folded in by a rotation and a
/// multiplication by the golden ratio's 64-bit fraction, then mixed by
/// MurmurHash3's 64-bit finaliser (Appleby), so that every bit of every
/// coordinate reaches the high bits the table probes by. Unkeyed: the same
/// hashes in every process (not that any answer depends on them).
#[derive(Debug, Clone, Copy, Default)]
pub struct PositionHasher(u64);

impl PositionHasher {
    #[inline]
    fn fold(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(26) ^ word).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

impl Hasher for PositionHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.fold(u64::from_le_bytes(w.try_into().expect("eight bytes")));
        }
        let rest = words.remainder();
        if !rest.is_empty() {
            let mut w = [0u8; 8];
            w[..rest.len()].copy_from_slice(rest);
            self.fold(u64::from_le_bytes(w));
        }
    }

    #[inline]
    fn write_u32(&mut self, n: u32) {
        self.fold(n.into());
    }

    #[inline]
    fn write_u64(&mut self, n: u64) {
        self.fold(n);
    }

    #[inline]
    fn write_usize(&mut self, n: usize) {
        self.fold(n as u64);
    }

    #[inline]
    fn finish(&self) -> u64 {
        let mut h = self.0;
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ h >> 33
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;
    use std::hash::BuildHasher;

    /// Ids in order of first use, one per position bit for bit: −0 and +0
    /// one vertex, a coordinate one float step away another, float64
    /// positions told apart where their float32 roundings are not.
    #[test]
    fn positions_get_one_id_each_in_order_of_first_use() {
        let a = Vec3::new(0.0, 1.0, 2.0);
        let points = [
            a,
            Vec3::new(-0.0, 1.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0f32.next_up()),
            Vec3::X,
            a,
        ];
        let mut welder = Welder::default();
        let ids: Vec<(u32, bool)> = points.iter().map(|&p| welder.id(key(p))).collect();
        assert_eq!(
            ids,
            [(0, true), (0, false), (1, true), (2, true), (0, false)]
        );
        assert_eq!(welder.len(), 3);
        let close = DVec3::new(0.1, 0.2, 0.3);
        let beside = DVec3::new(0.1 + 1e-12, 0.2, 0.3);
        assert_eq!(close.as_vec3(), beside.as_vec3());
        let mut exact = Welder::with_capacity(2);
        assert_eq!(exact.id(exact_key(close)), (0, true));
        assert_eq!(exact.id(exact_key(-DVec3::ZERO)), (1, true));
        assert_eq!(exact.id(exact_key(DVec3::ZERO)), (1, false));
        assert_eq!(exact.id(exact_key(beside)), (2, true));
        exact.clear();
        assert!(exact.is_empty());
        assert_eq!(exact.id(exact_key(beside)), (0, true));
    }

    /// Positions on a regular lattice (a scan's grid, a CAD part's round
    /// numbers), whose bits differ in few places, spread over the table's
    /// high bits: 200,000 of them fall into as many of 2^20 buckets (by
    /// their top 20 bits) as random hashes would, within 1%.
    #[test]
    fn lattice_positions_spread_over_the_hash_s_high_bits() {
        let hasher = BuildHasherDefault::<PositionHasher>::default();
        let mut seen = HashSet::new();
        let mut n = 0;
        for i in 0..100 {
            for j in 0..100 {
                for k in 0..20 {
                    let p = Vec3::new(i as f32 * 0.5, j as f32, k as f32 * 0.125);
                    seen.insert(hasher.hash_one(key(p)) >> 44);
                    n += 1;
                }
            }
        }
        // n keys into m buckets: m·(1 − e^(−n/m)) distinct by chance.
        let m = (1u64 << 20) as f64;
        let chance = m * (1.0 - (-(n as f64) / m).exp());
        assert!(
            seen.len() as f64 > 0.99 * chance,
            "{} buckets of {n} keys, {chance:.0} by chance",
            seen.len()
        );
    }
}
