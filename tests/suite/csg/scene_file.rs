//! CSG as the scene file writes it: each surface keeps its operand's
//! material unless the CSG object names one, operands that bound no solid
//! are refused with one line naming their key, and the example scene
//! compiles to CSG primitives.

use super::scenes_dir;
use crate::common::process::assert_rejected;
use crate::common::{scene, scene_at};
use glam::Vec3;
use strata::math::Ray;
use strata::scene::Scene;

#[test]
fn surfaces_keep_their_operands_materials_unless_the_csg_names_one() {
    let mats = "[materials.red]\ndiffuse = [1.0, 0.0, 0.0]\n[materials.blue]\ndiffuse = [0.0, 0.0, 1.0]\n\
        [materials.green]\ndiffuse = [0.0, 1.0, 0.0]\n[materials.grey]\ndiffuse = [0.5, 0.5, 0.5]\n";
    let a = "{ sphere = { radius = 1.0 }, material = \"red\" }";
    let b = "{ sphere = { center = [0.0, 0.0, 1.0], radius = 0.5 }, material = \"blue\" }";
    let colour = |s: &Scene, ray: Ray| {
        let h = s.geometry.intersect(&ray).expect("hit");
        s.materials[s.geometry.surface(&ray, &h).material as usize].diffuse
    };
    let down_the_pit = Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
    let from_the_side = Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::X);
    // Each surface keeps its operand's material: the pit is blue, the rest red.
    let s = scene(&format!(
        "{mats}[[objects]]\ncsg = {{ op = \"difference\", a = {a}, b = {b} }}\n"
    ));
    assert_eq!(colour(&s, down_the_pit), Vec3::Z);
    assert_eq!(colour(&s, from_the_side), Vec3::X);
    // The CSG object's material overrides both, also through a nested node
    // that names its own, and the enclosing group's is only a default.
    let s = scene(&format!(
        "{mats}[[objects]]\nmaterial = \"green\"\ncsg = {{ op = \"union\", a = {{ sphere = {{ radius = 0.1 }} }}, b = {{ material = \"grey\", csg = {{ op = \"difference\", a = {a}, b = {b} }} }} }}\n"
    ));
    assert_eq!(colour(&s, down_the_pit), Vec3::Y);
    assert_eq!(colour(&s, from_the_side), Vec3::Y);
    let s = scene(&format!(
        "{mats}[[objects]]\nmaterial = \"green\"\ngroup = [ {{ csg = {{ op = \"difference\", a = {a}, b = {{ sphere = {{ center = [0.0, 0.0, 1.0], radius = 0.5 }} }} }} }} ]\n"
    ));
    assert_eq!(
        colour(&s, down_the_pit),
        Vec3::Y,
        "an operand without a material inherits the group's"
    );
    assert_eq!(colour(&s, from_the_side), Vec3::X);
}

#[test]
fn operands_that_bound_no_solid_are_errors_naming_their_key() {
    let sphere = "{ sphere = { radius = 1.0 } }";
    let csg = |a: &str, b: &str| {
        format!("[[objects]]\nsphere = {{ radius = 0.1 }}\n[[objects]]\ncsg = {{ op = \"difference\", a = {a}, b = {b} }}\n")
    };
    let open_box = std::fs::read_to_string(scenes_dir().join("meshes/cube.obj")).unwrap();
    let open_box = open_box.trim_end().rsplit_once('\n').unwrap().0.to_string() + "\n";
    assert_rejected(
        "open-mesh",
        Some(&csg(sphere, "{ mesh = \"open.obj\" }")),
        &[("open.obj", open_box.as_bytes())],
        &[
            "objects[1].csg.b.mesh",
            "open.obj",
            "not a closed mesh",
            "1 triangle(s)",
        ],
    );
    assert_rejected(
        "uncapped",
        Some(&csg(
            "{ cylinder = { radius = 1.0, height = 1.0, caps = false } }",
            sphere,
        )),
        &[],
        &["objects[1].csg.a.cylinder.caps", "uncapped"],
    );
    assert_rejected(
        "plane",
        Some(&csg(sphere, "{ plane = { normal = [0.0, 1.0, 0.0] } }")),
        &[],
        &["objects[1].csg.b.plane"],
    );
    assert_rejected(
        "triangle",
        Some(&csg(
            sphere,
            "{ triangle = { v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] } }",
        )),
        &[],
        &["objects[1].csg.b.triangle"],
    );
    assert_rejected(
        "empty-group",
        Some(&csg(sphere, "{ group = [] }")),
        &[],
        &["objects[1].csg.b.group"],
    );
    // Deep inside nesting, the plain objects' validation reports the full path.
    let nested = format!(
        "{{ csg = {{ op = \"union\", a = {sphere}, b = {{ sphere = {{ radius = -1.0 }} }} }} }}"
    );
    assert_rejected(
        "nested-radius",
        Some(&csg(sphere, &nested)),
        &[],
        &["objects[1].csg.b.csg.b.sphere.radius"],
    );
    let nested = format!("{{ group = [{sphere}, {{ sphere = {{ radius = nan }} }}] }}");
    assert_rejected(
        "group-nan",
        Some(&csg(&nested, sphere)),
        &[],
        &["objects[1].csg.a.group[1].sphere.radius"],
    );
    assert_rejected(
        "material",
        Some(&csg(
            "{ sphere = { radius = 1.0 }, material = \"nope\" }",
            sphere,
        )),
        &[],
        &["objects[1].csg.a.material", "nope"],
    );
    assert_rejected(
        "no-shape",
        Some(&csg(sphere, "{ material = \"x\" }")),
        &[],
        &["objects[1].csg.b"],
    );
}

#[test]
fn the_example_scene_compiles_to_csg_primitives() {
    let path = scenes_dir().join("csg.toml");
    let s = scene_at(&std::fs::read_to_string(&path).unwrap(), &path);
    let csg = s
        .geometry
        .shapes()
        .iter()
        .filter(|p| matches!(p.shape, strata::geometry::Shape::Csg(_)))
        .count();
    assert_eq!(csg, 3, "lens, die and drilled cylinder");
}
