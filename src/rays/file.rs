//! The binary ray and hit files of `strata rays` and `strata trace`
//! (an interface: `tools/validate_embree.py` and other tools read them).
//!
//! Both are flat arrays of little-endian 32-bit records with no header:
//!
//! | file       | record (32 / 16 bytes)                                   |
//! |------------|----------------------------------------------------------|
//! | `RAYS.bin` | `ox oy oz dx dy dz tmin tmax`, 8 × f32                   |
//! | `HITS.bin` | `t: f32`, `prim: u32`, `u: f32`, `v: f32`, one per ray   |
//!
//! A closest-hit record holds the hit distance `t` (in units of the ray's
//! direction, which need not be unit length), the triangle's index in file
//! order, and the barycentric weights `u`, `v` of its vertices v1 and v2;
//! a miss is `t = +inf`, `prim = u32::MAX`, `u = v = 0`. An occlusion record
//! (`strata trace --occlusion`) is [`HitRecord::OCCLUDED`] (`t = 0`,
//! `prim = 0`) or the miss record.

use crate::accel::PrimHit;
use crate::error::io_message;
use crate::error::{InputError, InputResult};
use crate::math::Ray;
use glam::Vec3;
use std::io::Write;
use std::path::Path;

/// Bytes per ray record.
pub const RAY_BYTES: usize = 32;
/// Bytes per hit record.
pub const HIT_BYTES: usize = 16;

/// One record of a hit file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HitRecord {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

impl HitRecord {
    /// No hit in `(tmin, tmax]`.
    pub const MISS: HitRecord = HitRecord {
        t: f32::INFINITY,
        prim: u32::MAX,
        u: 0.0,
        v: 0.0,
    };

    /// An occlusion query that found something in `(tmin, tmax]`.
    pub const OCCLUDED: HitRecord = HitRecord {
        t: 0.0,
        prim: 0,
        u: 0.0,
        v: 0.0,
    };

    /// The record of an occlusion query's answer.
    pub fn occluded(blocked: bool) -> Self {
        if blocked {
            Self::OCCLUDED
        } else {
            Self::MISS
        }
    }

    pub fn from_hit(hit: Option<PrimHit>) -> Self {
        hit.map_or(Self::MISS, |h| HitRecord {
            t: h.t,
            prim: h.prim,
            u: h.u,
            v: h.v,
        })
    }

    pub fn is_hit(&self) -> bool {
        self.prim != u32::MAX
    }
}

/// Decode a ray file held in memory. Errors name `path` and say what is
/// wrong: a length that is not a whole number of records, or a ray that
/// no tracer can use (non-finite values, a zero direction, `tmin < 0`,
/// `tmax < tmin`).
pub fn parse_rays(path: &Path, bytes: &[u8]) -> InputResult<Vec<Ray>> {
    if !bytes.len().is_multiple_of(RAY_BYTES) {
        return Err(InputError::file(
            path,
            format!(
                "truncated ray file: {} bytes is not a whole number of {RAY_BYTES}-byte \
                 records (ox oy oz dx dy dz tmin tmax as little-endian f32)",
                bytes.len()
            ),
        ));
    }
    let mut rays = Vec::with_capacity(bytes.len() / RAY_BYTES);
    for (i, record) in bytes.chunks_exact(RAY_BYTES).enumerate() {
        let f = |k: usize| f32::from_le_bytes(record[4 * k..4 * k + 4].try_into().unwrap());
        let ray = Ray {
            origin: Vec3::new(f(0), f(1), f(2)),
            direction: Vec3::new(f(3), f(4), f(5)),
            tmin: f(6),
            tmax: f(7),
        };
        let problem = if !ray.origin.is_finite() || !ray.direction.is_finite() {
            Some("origin and direction must be finite")
        } else if ray.direction == Vec3::ZERO {
            Some("direction is zero")
        } else if !(ray.tmin >= 0.0 && ray.tmin.is_finite()) {
            Some("tmin must be finite and ≥ 0")
        } else if ray.tmax.is_nan() || ray.tmax < ray.tmin {
            Some("tmax must be ≥ tmin (it may be +inf)")
        } else {
            None
        };
        if let Some(problem) = problem {
            return Err(InputError::new(path, format!("ray {i}"), problem));
        }
        rays.push(ray);
    }
    Ok(rays)
}

/// Read and decode a ray file; see [`parse_rays`].
pub fn read_rays(path: &Path) -> InputResult<Vec<Ray>> {
    let bytes = std::fs::read(path).map_err(|e| InputError::file(path, read_error(&e)))?;
    parse_rays(path, &bytes)
}

/// Encode rays as a ray file's bytes.
pub fn encode_rays(rays: &[Ray]) -> Vec<u8> {
    let mut out = Vec::with_capacity(rays.len() * RAY_BYTES);
    for r in rays {
        for x in r.components() {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    out
}

/// Encode triangles as the native Embree harness's `MESH.tris`
/// (`tools/embree/embree_trace.c`): u32 vertex and triangle counts, the
/// vertices as f32 xyz, then u32 indices; unindexed, so triangle `i` is
/// vertices `3i..3i + 3` and keeps its index as its primitive id.
pub fn encode_triangles(tris: &[[Vec3; 3]]) -> Vec<u8> {
    let mut out = Vec::with_capacity(8 + tris.len() * 48);
    out.extend_from_slice(&(3 * tris.len() as u32).to_le_bytes());
    out.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for x in tris.iter().flatten().flat_map(|v| v.to_array()) {
        out.extend_from_slice(&x.to_le_bytes());
    }
    for i in 0..3 * tris.len() as u32 {
        out.extend_from_slice(&i.to_le_bytes());
    }
    out
}

/// Encode hit records as a hit file's bytes.
pub fn encode_hits(hits: &[HitRecord]) -> Vec<u8> {
    let mut out = Vec::with_capacity(hits.len() * HIT_BYTES);
    for h in hits {
        out.extend_from_slice(&h.t.to_le_bytes());
        out.extend_from_slice(&h.prim.to_le_bytes());
        out.extend_from_slice(&h.u.to_le_bytes());
        out.extend_from_slice(&h.v.to_le_bytes());
    }
    out
}

/// Decode a hit file held in memory.
pub fn parse_hits(path: &Path, bytes: &[u8]) -> InputResult<Vec<HitRecord>> {
    if !bytes.len().is_multiple_of(HIT_BYTES) {
        return Err(InputError::file(
            path,
            format!(
                "truncated hit file: {} bytes is not a whole number of {HIT_BYTES}-byte records",
                bytes.len()
            ),
        ));
    }
    Ok(bytes
        .chunks_exact(HIT_BYTES)
        .map(|r| {
            let w = |k: usize| <[u8; 4]>::try_from(&r[4 * k..4 * k + 4]).unwrap();
            HitRecord {
                t: f32::from_le_bytes(w(0)),
                prim: u32::from_le_bytes(w(1)),
                u: f32::from_le_bytes(w(2)),
                v: f32::from_le_bytes(w(3)),
            }
        })
        .collect())
}

/// Write bytes to `path` atomically (temporary file, then rename).
pub fn write_file(path: &Path, bytes: &[u8]) -> InputResult<()> {
    crate::output::atomic::write_atomic(path, |w| w.write_all(bytes))
        .map_err(|e| InputError::file(path, format!("cannot write: {}", io_message(&e))))
}

fn read_error(e: &std::io::Error) -> String {
    format!("cannot read: {}", io_message(e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_and_hits_round_trip() {
        let rays = vec![
            Ray::new(Vec3::new(1.0, -2.0, 3.5), Vec3::new(0.0, 0.0, -1.0)),
            Ray::segment(Vec3::splat(1e5), Vec3::new(1e-6, 2.0, 0.0), 7.0),
        ];
        let path = Path::new("mem.bin");
        assert_eq!(parse_rays(path, &encode_rays(&rays)).unwrap(), rays);
        let hits = vec![
            HitRecord::MISS,
            HitRecord {
                t: 1.5,
                prim: 7,
                u: 0.25,
                v: 0.5,
            },
            HitRecord::OCCLUDED,
        ];
        assert_eq!(parse_hits(path, &encode_hits(&hits)).unwrap(), hits);
    }

    #[test]
    fn truncated_and_invalid_rays_are_named() {
        let path = Path::new("rays.bin");
        let mut bytes = encode_rays(&[Ray::new(Vec3::ZERO, Vec3::X)]);
        bytes.pop();
        let err = parse_rays(path, &bytes).unwrap_err().to_string();
        assert!(err.starts_with("rays.bin: truncated"), "{err}");
        let bad = [
            Ray::new(Vec3::ZERO, Vec3::ZERO),
            Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X),
            Ray {
                tmin: -1.0,
                ..Ray::new(Vec3::ZERO, Vec3::X)
            },
            Ray::segment(Vec3::ZERO, Vec3::X, f32::NAN),
        ];
        for ray in bad {
            let bytes = encode_rays(&[Ray::new(Vec3::ZERO, Vec3::X), ray]);
            let err = parse_rays(path, &bytes).unwrap_err().to_string();
            assert!(err.starts_with("rays.bin: ray 1: "), "{err}");
        }
    }
}
