//! The glowing surfaces the path integrator samples as a light
//! ([`crate::light::emitters`]): the triangles of the scene's own meshes,
//! those of every placement of an instanced mesh (in world space), and
//! the untransformed spheres whose material emits, besides the surfaces of
//! `[[lights]]`, which are sampled as those lights.

use crate::geometry::{Geometry, MeshRange, Shape, NO_MATERIAL, NO_TRANSFORM};
use crate::light::{EmissionTexture, Emitter, EmitterId, Emitters, Light, NO_PART};
use crate::material::Material;
use crate::texture::Textures;
use glam::{Affine3A, Vec3};

pub(super) fn emitters(
    geometry: &Geometry,
    materials: &[Material],
    textures: &Textures,
    lights: &[Light],
) -> Emitters {
    let glows = |m: u32| m != NO_MATERIAL && materials[m as usize].is_emissive();
    let light_prims: Vec<u32> = lights.iter().filter_map(Light::prim).collect();
    let mut list = Vec::new();
    if geometry.meshes().iter().any(|m| glows(m.material)) {
        let triangles = geometry.file_order_triangles();
        for mesh in geometry.meshes().iter().filter(|m| glows(m.material)) {
            push_mesh(
                &mut list,
                mesh,
                &materials[mesh.material as usize],
                textures,
                |prim| ((prim, NO_PART), triangles[prim as usize]),
            );
        }
    }
    for (i, shape) in geometry.shapes().iter().enumerate() {
        let prim = geometry.triangle_count() + i as u32;
        if !glows(shape.material) || light_prims.contains(&prim) {
            continue;
        }
        if let (Shape::Sphere(s), NO_TRANSFORM) = (shape.shape, shape.transform) {
            list.push((
                (prim, NO_PART),
                Emitter::Sphere {
                    center: s.center,
                    radius: s.radius,
                    radiance: materials[shape.material as usize].emission,
                },
            ));
        }
    }
    // Each placement of a glowing prototype mesh, its triangles moved to
    // world space; the material is the instance's, else the mesh's, else
    // the inherited one, as the instance's surface picks it.
    let first = geometry.first_instance();
    let mut object_triangles: Vec<Option<Vec<[Vec3; 3]>>> = vec![None; geometry.prototypes().len()];
    for (k, instance) in geometry.instances().iter().enumerate() {
        let prototype = &geometry.prototypes()[instance.prototype as usize];
        let material_of = |mesh: &MeshRange| {
            if instance.material != NO_MATERIAL {
                instance.material
            } else if mesh.material != NO_MATERIAL {
                mesh.material
            } else {
                instance.inherited
            }
        };
        if !prototype.meshes().iter().any(|m| glows(material_of(m))) {
            continue;
        }
        let triangles = object_triangles[instance.prototype as usize]
            .get_or_insert_with(|| prototype.file_order_triangles());
        let to_world: Affine3A = instance.affine();
        let prim = first + k as u32;
        for mesh in prototype.meshes() {
            let material = material_of(mesh);
            if !glows(material) {
                continue;
            }
            push_mesh(
                &mut list,
                mesh,
                &materials[material as usize],
                textures,
                |tri| {
                    let v = triangles[tri as usize].map(|p| to_world.transform_point3(p));
                    ((prim, tri), v)
                },
            );
        }
    }
    Emitters::new(list)
}

/// Every triangle of `mesh` (glowing with `m`), its id and corners from
/// `triangle` given its primitive in the mesh's geometry.
fn push_mesh(
    list: &mut Vec<(EmitterId, Emitter)>,
    mesh: &MeshRange,
    m: &Material,
    textures: &Textures,
    triangle: impl Fn(u32) -> (EmitterId, [Vec3; 3]),
) {
    let radiance = m.emission;
    // An emissive map's texture, where the mesh has coordinates.
    let mapped = m.maps.emission.zip(mesh.uvs.as_ref());
    let mean = mapped.map(|(t, _)| textures.mean(t));
    for prim in mesh.first..mesh.first + mesh.count {
        let (id, v) = triangle(prim);
        let texture = mapped.zip(mean).map(|((texture, uvs), mean)| {
            let tri = uvs.indices[(prim - mesh.first) as usize];
            EmissionTexture {
                texture,
                uv: tri.map(|i| uvs.values[i as usize]),
                mean,
            }
        });
        list.push((
            id,
            Emitter::Triangle {
                v,
                radiance,
                texture,
            },
        ));
    }
}
