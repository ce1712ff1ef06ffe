//! Integer hashing: the source of all randomness in strata.

/// A 32-bit integer hash with low bias: Chris Wellons' "lowbias32" from his
/// hash-prospector search (2018).
#[inline]
pub fn hash_u32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// Hash a sequence of words into one (a chained, order-sensitive combine).
#[inline]
pub fn hash_words(words: &[u32]) -> u32 {
    let mut h = 0x9e37_79b9u32;
    for &w in words {
        h = hash_u32(h ^ hash_u32(w.wrapping_add(0x632b_e5ab)));
    }
    h
}

/// Map 32 random bits to a float in [0, 1).
#[inline]
pub fn unit_float(bits: u32) -> f32 {
    // The top 24 bits fill the mantissa exactly; the result is < 1.
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// A seeded stream of uniform floats, for tests and benches: reproducible
/// inputs from one seed, drawn from the same hash as everything else.
pub struct HashRng(pub u32);

impl HashRng {
    /// A float in [0, 1).
    pub fn unit(&mut self) -> f32 {
        self.0 = hash_u32(self.0.wrapping_add(0x9e37_79b9));
        unit_float(self.0)
    }

    /// A float in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// A point of the cube of side `scale` centred on the origin.
    pub fn cube(&mut self, scale: f32) -> glam::Vec3 {
        glam::Vec3::new(self.unit() - 0.5, self.unit() - 0.5, self.unit() - 0.5) * scale
    }

    /// A unit vector, uniform on the sphere (rejection from the cube).
    pub fn unit_vector(&mut self) -> glam::Vec3 {
        loop {
            let v = glam::Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}
