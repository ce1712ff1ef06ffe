//! The glowing surfaces the path integrator samples as a light
//! ([`crate::light::emitters`]): the triangles of the scene's own meshes
//! and the untransformed spheres whose material emits, besides the
//! surfaces of `[[lights]]`, which are sampled as those lights.

use crate::geometry::{Geometry, Shape, NO_TRANSFORM};
use crate::light::{EmissionTexture, Emitter, Emitters, Light};
use crate::material::Material;
use crate::texture::Textures;

pub(super) fn emitters(
    geometry: &Geometry,
    materials: &[Material],
    textures: &Textures,
    lights: &[Light],
) -> Emitters {
    let glows = |m: u32| materials[m as usize].is_emissive();
    let light_prims: Vec<u32> = lights.iter().filter_map(Light::prim).collect();
    let mut list = Vec::new();
    if geometry.meshes().iter().any(|m| glows(m.material)) {
        let triangles = geometry.file_order_triangles();
        for mesh in geometry.meshes().iter().filter(|m| glows(m.material)) {
            let m = &materials[mesh.material as usize];
            let radiance = m.emission;
            // An emissive map's texture, where the mesh has coordinates.
            let mapped = m.maps.emission.zip(mesh.uvs.as_ref());
            let mean = mapped.map(|(t, _)| textures.mean(t));
            for prim in mesh.first..mesh.first + mesh.count {
                let v = triangles[prim as usize];
                let texture = mapped.zip(mean).map(|((texture, uvs), mean)| {
                    let tri = uvs.indices[(prim - mesh.first) as usize];
                    EmissionTexture {
                        texture,
                        uv: tri.map(|i| uvs.values[i as usize]),
                        mean,
                    }
                });
                list.push((
                    prim,
                    Emitter::Triangle {
                        v,
                        radiance,
                        texture,
                    },
                ));
            }
        }
    }
    for (i, shape) in geometry.shapes().iter().enumerate() {
        let prim = geometry.triangle_count() + i as u32;
        if !glows(shape.material) || light_prims.contains(&prim) {
            continue;
        }
        if let (Shape::Sphere(s), NO_TRANSFORM) = (shape.shape, shape.transform) {
            list.push((
                prim,
                Emitter::Sphere {
                    center: s.center,
                    radius: s.radius,
                    radiance: materials[shape.material as usize].emission,
                },
            ));
        }
    }
    Emitters::new(list)
}
