//! Texture maps that change a hit's shading: a normal or bump map bends
//! the shading normal, a metallic-roughness map scales the material's
//! factors, an emissive map its emission. Both integrators call these
//! only for materials that have such a map, so every other surface pays
//! one branch.
//!
//! **Normal maps** (glTF `normalTexture`, MTL `norm`) hold a tangent-space
//! normal as rgb = (n + 1)/2, +x along ∂p/∂u and +y along −∂p/∂v (up in
//! the image, as glTF and OpenGL write them); glTF's `scale` multiplies
//! x and y. The frame is the shading normal with a tangent made
//! orthogonal to it (Gram–Schmidt): the file's (glTF `TANGENT`, its w the
//! bitangent's sign, `b = w (n × t)`) where it has them, else ∂p/∂u worked
//! out per triangle at the hit from positions and texture coordinates
//! (`Geometry::uv_derivatives`), the bitangent's sign from −∂p/∂v.
//! **Bump maps** (MTL `bump`/`map_Bump`, `-bm` the scale) hold a height
//! h in their red channel, in world units times the scale; the normal is
//! Blinn's (1978) `(∂p/∂u + h_u n) × (∂p/∂v + h_v n)`, the slopes h_u, h_v
//! central differences one texel wide, and ∂p/∂u, ∂p/∂v first projected
//! into the shading normal's plane so that a flat map gives that normal
//! back (pbrt-v4's `BumpMap`, §10.5.1).
//!
//! A mapped normal is for shading only: offsets and which side a ray is
//! on keep the geometric normal. Where the mapped normal leaves the
//! geometric side, or the UV frame is degenerate (a UV triangle of no
//! area, non-finite values), the unmapped shading normal stays. Where it
//! faces away from the viewer, it is bent towards the viewer until the
//! viewer sees it at a grazing cosine of [`MIN_COS_VIEW`], so light does
//! not leak through the surface: the bend-back of Cycles'
//! `ensure_valid_reflection` in its simplest form (bend towards the
//! incoming direction, not solved for the reflection).

use crate::accel::PrimHit;
use crate::geometry::Surface;
use crate::material::{Material, NormalMapKind};
use crate::scene::Scene;
use glam::{Vec2, Vec3};

/// The least cosine between a bent shading normal and the viewer.
pub const MIN_COS_VIEW: f32 = 0.01;

/// `s`'s shading normal with `m`'s normal or bump map applied, seen along
/// `wo` (unit, away from the surface). Unchanged where `m` has no such map
/// or `s` no texture coordinates.
#[inline]
pub fn apply_normal_map(scene: &Scene, m: &Material, s: &mut Surface, hit: &PrimHit, wo: Vec3) {
    if let (Some(map), Some(uv)) = (m.maps.normal, s.uv) {
        if let Some(n) = mapped_normal(scene, map, s, uv, hit, wo) {
            s.shading_normal = n;
        }
    }
}

#[cold]
fn mapped_normal(
    scene: &Scene,
    map: crate::material::NormalMap,
    s: &Surface,
    uv: Vec2,
    hit: &PrimHit,
    wo: Vec3,
) -> Option<Vec3> {
    let n = s.shading_normal;
    let textures = &scene.textures;
    let mapped = match map.kind {
        NormalMapKind::Normal => {
            let (t, b) = match scene.geometry.vertex_tangent(hit).and_then(|t| {
                // The file's tangent, made orthogonal to the normal; the
                // bitangent w (n × t), as glTF defines it.
                let xyz = t.truncate();
                let tangent = (xyz - n * n.dot(xyz)).try_normalize()?;
                let w = if t.w < 0.0 { -1.0 } else { 1.0 };
                Some((tangent, n.cross(tangent) * w))
            }) {
                Some(frame) => frame,
                None => {
                    let (dpdu, dpdv) = scene.geometry.uv_derivatives(hit)?;
                    let t = (dpdu - n * n.dot(dpdu)).try_normalize()?;
                    let b = n.cross(t);
                    // +y of the map is −∂p/∂v (v runs down the image).
                    (t, if b.dot(dpdv) > 0.0 { -b } else { b })
                }
            };
            let c = textures.sample(map.texture, uv) * 2.0 - Vec3::ONE;
            t * (c.x * map.scale) + b * (c.y * map.scale) + n * c.z
        }
        NormalMapKind::Height => {
            let (dpdu, dpdv) = scene.geometry.uv_derivatives(hit)?;
            let (w, h) = textures.size(map.texture);
            let (du, dv) = (1.0 / w as f32, 1.0 / h as f32);
            let height = |d: Vec2| textures.sample(map.texture, uv + d).x * map.scale;
            let hu = (height(Vec2::new(du, 0.0)) - height(Vec2::new(-du, 0.0))) / (2.0 * du);
            let hv = (height(Vec2::new(0.0, dv)) - height(Vec2::new(0.0, -dv))) / (2.0 * dv);
            let tu = dpdu - n * n.dot(dpdu);
            let tv = dpdv - n * n.dot(dpdv);
            let cross = (tu + hu * n).cross(tv + hv * n);
            if cross.dot(n) < 0.0 {
                -cross
            } else {
                cross
            }
        }
    };
    let mapped = mapped.try_normalize()?;
    if !(mapped.dot(s.geometric_normal) > 0.0) {
        return None;
    }
    // Faced towards the viewer, as the integrators face their normals.
    let side = if s.geometric_normal.dot(wo) >= 0.0 {
        1.0
    } else {
        -1.0
    };
    let faced = mapped * side;
    let cos = faced.dot(wo);
    let faced = if cos < MIN_COS_VIEW {
        (faced + (MIN_COS_VIEW - cos) * wo).try_normalize()?
    } else {
        faced
    };
    Some(faced * side)
}

/// `m` with its metallic-roughness map read at `uv`: blue scales
/// `metallic`, green `roughness` (glTF 2.0, `metallicRoughnessTexture`).
/// `None` where there is nothing to change.
#[inline]
pub fn textured_pbr(scene: &Scene, m: &Material, uv: Option<Vec2>) -> Option<Material> {
    let (Some(t), Some(uv), Some(pbr)) = (m.maps.metallic_roughness, uv, m.pbr) else {
        return None;
    };
    let texel = scene.textures.sample(t, uv);
    let mut out = *m;
    out.pbr = Some(crate::material::MetallicRoughness {
        metallic: pbr.metallic * texel.z,
        roughness: pbr.roughness * texel.y,
        ..pbr
    });
    Some(out)
}

/// The emitted radiance of `m` at `uv`: its emission, times its emissive
/// map where it has one (glTF 2.0, `emissiveTexture`).
#[inline]
pub fn emission(scene: &Scene, m: &Material, uv: Option<Vec2>) -> Vec3 {
    match (m.maps.emission, uv) {
        (Some(t), Some(uv)) => m.emission * scene.textures.sample(t, uv),
        _ => m.emission,
    }
}
