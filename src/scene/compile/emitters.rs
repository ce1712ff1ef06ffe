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

/// The most triangles the placements of instanced glowing meshes may add
/// to the table (about 120 bytes each): a prototype placed many times is
/// stored once, and its emitters are one copy a placement. Past this the
/// placements are left to the BSDF's rays (unbiased, noisier) and a
/// warning says so.
pub(super) const INSTANCED_EMITTERS_MAX: usize = 1 << 20;

/// The table, and a warning where instanced glowing meshes were left out
/// of it ([`INSTANCED_EMITTERS_MAX`]).
pub(super) fn emitters(
    geometry: &Geometry,
    materials: &[Material],
    textures: &Textures,
    lights: &[Light],
) -> (Emitters, Option<String>) {
    emitters_within(
        geometry,
        materials,
        textures,
        lights,
        INSTANCED_EMITTERS_MAX,
    )
}

/// [`emitters`] with at most `most` triangles of placements.
fn emitters_within(
    geometry: &Geometry,
    materials: &[Material],
    textures: &Textures,
    lights: &[Light],
    most: usize,
) -> (Emitters, Option<String>) {
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
    // the inherited one (`Instance::material_of`, as its surface picks it).
    let first = geometry.first_instance();
    let placed: usize = geometry
        .instances()
        .iter()
        .map(|instance| {
            let prototype = &geometry.prototypes()[instance.prototype as usize];
            prototype
                .meshes()
                .iter()
                .filter(|mesh| glows(instance.material_of(mesh.material)))
                .map(|mesh| mesh.count as usize)
                .sum::<usize>()
        })
        .sum();
    if placed > most {
        let note = format!(
            "instanced glowing meshes have {placed} triangles in all their placements, over the \
             {most} sampled as lights: they light the scene through the path's own bounces \
             alone (the same image on average, noisier)"
        );
        return (Emitters::new(list), Some(note));
    }
    let mut object_triangles: Vec<Option<Vec<[Vec3; 3]>>> = vec![None; geometry.prototypes().len()];
    for (k, instance) in geometry.instances().iter().enumerate() {
        let prototype = &geometry.prototypes()[instance.prototype as usize];
        if !prototype
            .meshes()
            .iter()
            .any(|m| glows(instance.material_of(m.material)))
        {
            continue;
        }
        let triangles = object_triangles[instance.prototype as usize]
            .get_or_insert_with(|| prototype.file_order_triangles());
        let to_world: Affine3A = instance.affine();
        let prim = first + k as u32;
        for mesh in prototype.meshes() {
            let material = instance.material_of(mesh.material);
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
    (Emitters::new(list), None)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placements_past_the_limit_are_left_to_the_bsdf_with_a_warning() {
        let dir = std::env::temp_dir().join(format!("strata-emitters-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let panel =
            "mtllib panel.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl glow\nf 1 2 3 4\n";
        std::fs::write(dir.join("panel.obj"), panel).unwrap();
        std::fs::write(dir.join("panel.mtl"), "newmtl glow\nKd 0 0 0\nKe 1 1 1\n").unwrap();
        let text = "[render]\nintegrator = \"path\"\n\
                    [[objects]]\nmesh = \"panel.obj\"\ntransform = { translate = [0.0, 0.0, 1.0] }\n\
                    [[objects]]\nmesh = \"panel.obj\"\ntransform = { translate = [2.0, 0.0, 1.0] }\n";
        let scene =
            crate::scene::scene_from_str(text, &dir.join("scene.toml"), &Default::default())
                .unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(scene.geometry.instances().len(), 2);
        assert_eq!(scene.emitters.len(), 4, "two triangles a placement");
        let (s, m, t, l) = (
            &scene.geometry,
            &scene.materials,
            &scene.textures,
            &scene.lights,
        );
        let (within, note) = emitters_within(s, m, t, l, 4);
        assert_eq!((within.len(), note), (4, None));
        let (past, note) = emitters_within(s, m, t, l, 3);
        assert_eq!(past.len(), 0, "the placements left out");
        let note = note.expect("a warning");
        assert!(
            note.contains("4 triangles") && note.contains("over the 3"),
            "{note}"
        );
    }
}
