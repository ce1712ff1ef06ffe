//! The glowing surfaces the path integrator samples as a light
//! ([`crate::light::emitters`]): the triangles of the scene's own meshes
//! and the untransformed spheres whose material emits, besides the
//! surfaces of `[[lights]]`, which are sampled as those lights.

use crate::geometry::{Geometry, Shape, NO_TRANSFORM};
use crate::light::{Emitter, Emitters, Light};
use crate::material::Material;

pub(super) fn emitters(geometry: &Geometry, materials: &[Material], lights: &[Light]) -> Emitters {
    let glows = |m: u32| materials[m as usize].is_emissive();
    let light_prims: Vec<u32> = lights.iter().filter_map(Light::prim).collect();
    let mut list = Vec::new();
    if geometry.meshes().iter().any(|m| glows(m.material)) {
        let triangles = geometry.file_order_triangles();
        for mesh in geometry.meshes().iter().filter(|m| glows(m.material)) {
            let radiance = materials[mesh.material as usize].emission;
            for prim in mesh.first..mesh.first + mesh.count {
                let v = triangles[prim as usize];
                list.push((prim, Emitter::Triangle { v, radiance }));
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
