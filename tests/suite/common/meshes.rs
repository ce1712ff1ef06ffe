//! Meshes and placements the tests generate: a cube, a bumpy sphere as OBJ
//! text, random invertible affine maps and their lines in a placements
//! file, and base64 for a glTF buffer's `data:` URI.

use super::{Draw, StreamRng};
use glam::{Affine3A, Mat3, Vec3};

/// The cube of side `side` centred on the origin, two triangles a face,
/// wound outwards.
pub fn cube(side: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let v = (0..8)
        .map(|i| (Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2 & 1) as f32) - 0.5) * side)
        .collect();
    let f = vec![
        [0, 2, 3],
        [0, 3, 1],
        [4, 5, 7],
        [4, 7, 6],
        [0, 1, 5],
        [0, 5, 4],
        [2, 6, 7],
        [2, 7, 3],
        [0, 4, 6],
        [0, 6, 2],
        [1, 3, 7],
        [1, 7, 5],
    ];
    (v, f)
}

/// OBJ text of a bumpy UV sphere of 2 × `nu` × `nv` triangles with shared
/// edges everywhere: radius `radius`, bumps of amplitude `bump`.
pub fn bumpy_sphere_obj(nu: u32, nv: u32, radius: f32, bump: f32) -> String {
    let mut obj = String::new();
    for j in 0..=nv {
        for i in 0..nu {
            let th = std::f32::consts::PI * j as f32 / nv as f32;
            let ph = std::f32::consts::TAU * i as f32 / nu as f32;
            let r = radius + bump * ((5.0 * ph).sin() * (3.0 * th).cos());
            obj += &format!(
                "v {} {} {}\n",
                r * th.sin() * ph.cos(),
                r * th.cos(),
                r * th.sin() * ph.sin()
            );
        }
    }
    for j in 0..nv {
        for i in 0..nu {
            let a = j * nu + i + 1;
            let b = j * nu + (i + 1) % nu + 1;
            let (c, d) = (a + nu, b + nu);
            obj += &format!("f {a} {b} {d}\nf {a} {d} {c}\n");
        }
    }
    obj
}

/// A random invertible affine map: rotation, non-uniform scale (mirrored
/// in y half the time), another rotation (so a shear), and a translation
/// of up to `reach`.
pub fn random_affine(rng: &mut StreamRng, reach: f32) -> Affine3A {
    let rot = |rng: &mut StreamRng| {
        Mat3::from_axis_angle(rng.unit_vector(), rng.range(0.0, std::f32::consts::TAU))
    };
    let mut s = Vec3::new(
        rng.range(0.3, 2.0),
        rng.range(0.3, 2.0),
        rng.range(0.3, 2.0),
    );
    if rng.range(0.0, 1.0) < 0.5 {
        s.y = -s.y;
    }
    let linear = rot(rng) * Mat3::from_diagonal(s) * rot(rng);
    Affine3A::from_mat3_translation(linear, rng.unit_vector() * rng.range(0.0, reach))
}

/// The map as a line of a placements file (`instances = "FILE.csv"`): its
/// 3 × 4 matrix, row-major.
pub fn placement_row(a: &Affine3A) -> String {
    let m = Mat3::from(a.matrix3).transpose();
    let t = a.translation;
    let r = [m.x_axis, m.y_axis, m.z_axis];
    (0..3)
        .map(|i| format!("{},{},{},{}", r[i].x, r[i].y, r[i].z, t[i]))
        .collect::<Vec<_>>()
        .join(",")
}

/// Standard base64 with padding, for a glTF buffer's `data:` URI.
pub fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let n = chunk.iter().fold(0u32, |n, &b| n << 8 | u32::from(b)) << (8 * (3 - chunk.len()));
        for k in 0..=chunk.len() {
            out.push(ABC[(n >> (18 - 6 * k) & 63) as usize] as char);
        }
        out.push_str(&"=".repeat(3 - chunk.len()));
    }
    out
}
