//! glTF nodes that share a mesh (issue 45): the mesh is stored once and
//! each node places an instance of it. A file whose nodes share meshes
//! (nested nodes, non-uniform scale, a mirroring node, a mesh of two
//! primitives with their own materials) renders as the same file with
//! every node given its own copy of the mesh, alone, placed many times
//! by `instances`, and as `strata render MODEL` frames it; `strata trace`
//! numbers its triangles as the file's copies; and a thousand nodes
//! sharing a mesh cost the mesh once plus a fixed record each.

use crate::common::{
    bumpy_sphere_obj, render_rgb, scene_at, seeded, stderr, strata, temp_dir, Draw,
    StreamRng as Rng,
};
use glam::Vec3;
use std::path::{Path, PathBuf};
use strata::accel::BuildQuality;
use strata::math::Ray;
use strata::rays::file::encode_rays;
use strata::scene::compile::{compile_model, LoadProgress};
use strata::scene::loaders::load_mesh_file;
use strata::scene::model::model_scene;
use strata::scene::{load_mesh_scene, RenderOverrides, Scene};

/// The meshes of the test files: a bumpy sphere, a pair of tetrahedra (two
/// primitives, two materials) and a single tetrahedron, all closed and
/// wound outwards.
const SPHERE: usize = 0;
const PAIR: usize = 1;
const SINGLE: usize = 2;

/// Positions and triangles, outward.
type Triangles = (Vec<[f32; 3]>, Vec<[u32; 3]>);

fn sphere(dir: &Path, nu: u32, nv: u32) -> Triangles {
    std::fs::write(dir.join("sphere.obj"), bumpy_sphere_obj(nu, nv, 1.0, 0.25)).unwrap();
    let asset = load_mesh_file(&dir.join("sphere.obj")).unwrap();
    let m = &asset.meshes[0];
    (
        m.positions.iter().map(|p| p.to_array()).collect(),
        m.indices.clone(),
    )
}

/// A tetrahedron of corners `v`, each face wound away from the opposite corner.
fn tetrahedron(v: [[f32; 3]; 4]) -> Triangles {
    let p = v.map(Vec3::from);
    let faces = [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]].map(|[a, b, c]: [u32; 3]| {
        let d = 6 - a - b - c;
        let n = (p[b as usize] - p[a as usize]).cross(p[c as usize] - p[a as usize]);
        if n.dot(p[d as usize] - p[a as usize]) > 0.0 {
            [a, c, b]
        } else {
            [a, b, c]
        }
    });
    (v.to_vec(), faces.to_vec())
}

/// The nodes of the test file: `(mesh, the rest of the node's JSON)`;
/// the scene's roots are nodes 0, 1, 5, 6 and 7.
fn nodes() -> Vec<(Option<usize>, String)> {
    [
        (Some(SPHERE), r#""translation":[-4,0,0]"#),
        (
            None,
            r#""translation":[0,0,-2],"rotation":[0,0.38268343,0,0.9238795],"children":[2,3]"#,
        ),
        (Some(SPHERE), r#""scale":[1.5,0.6,1],"translation":[0,1,0]"#),
        (Some(PAIR), r#""translation":[2,0,0],"children":[4]"#),
        // Mirrored, under two parents.
        (Some(SPHERE), r#""scale":[-1,1.2,1],"translation":[0,2,0]"#),
        (Some(SINGLE), r#""translation":[0,-2.5,0]"#),
        (
            Some(PAIR),
            r#""rotation":[0.27059805,0.27059805,0,0.9238795],"translation":[3,-2,1]"#,
        ),
        (
            Some(SPHERE),
            r#""scale":[0.5,0.5,0.5],"translation":[4,0,0]"#,
        ),
    ]
    .map(|(m, s)| (m, s.to_string()))
    .to_vec()
}
const ROOTS: &str = "[0,1,5,6,7]";

/// Write `name`.gltf and `name`.bin: the meshes of `geometry`, placed by
/// `nodes`. With `shared`, a node names its mesh; without, every node
/// that has a mesh gets its own copy of the mesh (the same accessors), so
/// nothing is shared.
fn write_gltf(
    dir: &Path,
    name: &str,
    geometry: &[Triangles],
    nodes: &[(Option<usize>, String)],
    roots: &str,
    shared: bool,
) -> PathBuf {
    let mut bin = Vec::new();
    let (mut views, mut accessors) = (Vec::new(), Vec::new());
    for (positions, triangles) in geometry {
        for bytes in [
            positions
                .iter()
                .flatten()
                .flat_map(|v| v.to_le_bytes())
                .collect::<Vec<u8>>(),
            triangles
                .iter()
                .flatten()
                .flat_map(|i| i.to_le_bytes())
                .collect(),
        ] {
            views.push(format!(
                r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#,
                bin.len(),
                bytes.len()
            ));
            bin.extend(bytes);
        }
        let lo = (0..3).map(|k| positions.iter().map(|p| p[k]).fold(f32::MAX, f32::min));
        let hi = (0..3).map(|k| positions.iter().map(|p| p[k]).fold(f32::MIN, f32::max));
        let list = |it: &mut dyn Iterator<Item = f32>| {
            it.map(|v| format!("{v:?}")).collect::<Vec<_>>().join(",")
        };
        accessors.push(format!(
            r#"{{"bufferView":{},"componentType":5126,"count":{},"type":"VEC3","min":[{}],"max":[{}]}}"#,
            views.len() - 2,
            positions.len(),
            list(&mut { lo }),
            list(&mut { hi })
        ));
        accessors.push(format!(
            r#"{{"bufferView":{},"componentType":5125,"count":{},"type":"SCALAR"}}"#,
            views.len() - 1,
            triangles.len() * 3
        ));
    }
    let meshes = [
        r#"{"name":"sphere","primitives":[{"attributes":{"POSITION":0},"indices":1}]}"#,
        r#"{"name":"pair","primitives":[{"attributes":{"POSITION":2},"indices":3,"material":0},{"attributes":{"POSITION":4},"indices":5,"material":1}]}"#,
        r#"{"name":"single","primitives":[{"attributes":{"POSITION":4},"indices":5}]}"#,
    ];
    let mut mesh_list: Vec<&str> = Vec::new();
    let mut node_list = Vec::new();
    for (mesh, rest) in nodes {
        let index = match (mesh, shared) {
            (None, _) => None,
            (Some(m), true) => Some(*m),
            (Some(m), false) => {
                mesh_list.push(meshes[*m]);
                Some(mesh_list.len() - 1)
            }
        };
        let mesh = index.map_or(String::new(), |i| format!(r#""mesh":{i},"#));
        node_list.push(format!("{{{mesh}{rest}}}"));
    }
    if shared {
        // The pair and the single tetrahedron only where their accessors are.
        mesh_list = meshes[..if geometry.len() < 3 { 1 } else { 3 }].to_vec();
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":{roots}}}],
        "buffers":[{{"byteLength":{},"uri":"{name}.bin"}}],
        "bufferViews":[{}],"accessors":[{}],"meshes":[{}],"nodes":[{}],
        "materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.8,0.2,0.2,1],"metallicFactor":0}}}},
                     {{"pbrMetallicRoughness":{{"baseColorFactor":[0.2,0.3,0.8,1],"metallicFactor":0}}}}]}}"#,
        bin.len(),
        views.join(","),
        accessors.join(","),
        mesh_list.join(","),
        node_list.join(",")
    );
    std::fs::write(dir.join(format!("{name}.bin")), &bin).unwrap();
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, json).unwrap();
    path
}

/// The test file with its meshes shared (`shared.gltf`) and unshared
/// (`copies.gltf`), and the triangles of each mesh.
fn files(dir: &Path) -> [usize; 3] {
    let geometry = [
        sphere(dir, 18, 12),
        tetrahedron([[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]]),
        tetrahedron([
            [0., 0., 0.5],
            [0.8, 0.1, 0.7],
            [0.2, 0.9, 0.5],
            [0.3, 0.3, -0.4],
        ]),
    ];
    write_gltf(dir, "shared", &geometry, &nodes(), ROOTS, true);
    write_gltf(dir, "copies", &geometry, &nodes(), ROOTS, false);
    [
        geometry[0].1.len(),
        geometry[1].1.len() + geometry[2].1.len(),
        geometry[2].1.len(),
    ]
}

const LIGHTS: &str = "[[lights]]\ntype = \"point\"\nposition = [0.0, 30.0, 20.0]\nintensity = [3000.0, 3000.0, 3000.0]\n\
[camera]\nposition = [0.0, 4.0, 22.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\n\
[render]\nwidth = 48\nheight = 40\nspp = 4\n";

/// Two images equal within float rounding (as tests/suite/instancing.rs
/// holds instances to copies).
fn assert_same_image(a: &[Vec3], b: &[Vec3], what: &str) {
    let total: f32 = b.iter().map(|c| c.element_sum()).sum();
    assert!(total > 0.0, "{what}: the scene is lit");
    let diff: f32 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).abs().element_sum())
        .sum();
    assert!(
        diff <= 1e-4 * total,
        "{what}: images differ by {diff} of {total}"
    );
    let off = a
        .iter()
        .zip(b)
        .filter(|(x, y)| (**x - **y).abs().max_element() > 1e-3 * y.max_element().max(1e-3))
        .count();
    assert!(
        off * 200 <= a.len(),
        "{what}: {off} of {} pixels differ",
        a.len()
    );
}

/// Rays from 30 away towards points inside random triangles of `copies`.
fn rays(copies: &Scene, rng: &mut Rng, n: usize) -> Vec<Ray> {
    let tris = copies.geometry.file_order_triangles();
    (0..n)
        .map(|_| {
            let t = tris[(rng.range(0.0, 1.0) * tris.len() as f32) as usize % tris.len()];
            let (u, v) = (rng.range(0.05, 0.45), rng.range(0.05, 0.45));
            let target = (1.0 - u - v) * t[0] + u * t[1] + v * t[2];
            let origin = target + rng.unit_vector() * 30.0;
            Ray::new(origin, (target - origin).normalize())
        })
        .collect()
}

#[test]
fn shared_meshes_are_stored_once_and_render_as_copies() {
    let dir = temp_dir("gltf-instances");
    let [sphere, pair, single] = files(&dir);
    let load = |file: &str, object: &str| {
        let text = format!("{LIGHTS}[[objects]]\nmesh = \"{file}\"\n{object}");
        scene_at(&text, &dir.join("s.toml"))
    };
    let (shared, copies) = (load("shared.gltf", ""), load("copies.gltf", ""));
    // The sphere (4 nodes) and the pair (2) once each; the single
    // tetrahedron, one node's, baked.
    let g = &shared.geometry;
    assert_eq!((g.prototypes().len(), g.instances().len()), (2, 6));
    assert_eq!(g.triangle_count() as usize, single);
    assert_eq!(g.unique_triangles() as usize, sphere + pair + single);
    assert_eq!(
        g.instanced_triangles() as usize + single,
        4 * sphere + 2 * pair + single
    );
    let c = &copies.geometry;
    assert!(c.instances().is_empty());
    assert_eq!(c.triangle_count() as usize, 4 * sphere + 2 * pair + single);
    assert_same_image(
        &render_rgb(&shared, 2),
        &render_rgb(&copies, 2),
        "placed once",
    );

    // Every first hit from outside meets a closed mesh from outside, the
    // mirrored sphere's too: its normal faces the ray, in both files; and
    // each pair keeps its primitives' materials.
    let mut rng = seeded(45);
    let mut hits = 0;
    let mut colours = std::collections::BTreeSet::new();
    for ray in rays(&copies, &mut rng, 3000) {
        for s in [&shared, &copies] {
            if let Some(hit) = s.geometry.intersect(&ray) {
                hits += 1;
                let surface = s.geometry.surface(&ray, &hit);
                assert!(
                    surface.geometric_normal.dot(ray.direction) < 0.0,
                    "{ray:?}: a normal facing away, {:?}",
                    surface.geometric_normal
                );
                colours.insert(format!(
                    "{:?}",
                    s.materials[surface.material as usize].diffuse
                ));
            }
        }
    }
    assert!(hits > 5000, "{hits} hits");
    assert_eq!(
        colours.len(),
        3,
        "the default and the pair's two: {colours:?}"
    );

    // Placed twice more by an instances file, after a turn: each shared
    // mesh's placement flattened with each of the file's.
    std::fs::write(
        dir.join("two.csv"),
        "1,0,0,0, 0,1,0,0, 0,0,1,0\n0.8,0,0,0, 0,0,-0.8,1, 0,0.8,0,-1\n",
    )
    .unwrap();
    let object = "instances = \"two.csv\"\ntransform = { rotate = [0.0, 1.0, 0.0, 30.0] }\n";
    let (shared, copies) = (load("shared.gltf", object), load("copies.gltf", object));
    let g = &shared.geometry;
    assert_eq!((g.prototypes().len(), g.instances().len()), (3, 2 * 6 + 2));
    assert_eq!(g.unique_triangles() as usize, sphere + pair + single);
    assert_same_image(
        &render_rgb(&shared, 2),
        &render_rgb(&copies, 2),
        "placed twice",
    );
}

/// `strata render MODEL` places the instances and frames the whole model,
/// as it frames the copies.
#[test]
fn a_model_with_shared_meshes_is_framed_and_rendered_as_its_copies() {
    let dir = temp_dir("gltf-instances-model");
    files(&dir);
    let cli = RenderOverrides {
        width: Some(40),
        height: Some(32),
        spp: Some(4),
        ..Default::default()
    };
    let model = |name: &str| {
        let made = model_scene(&dir.join(name), &cli, &[], None).unwrap();
        let camera = format!("{:?}", made.description.camera);
        let start = std::time::Instant::now();
        let progress = LoadProgress::default();
        let scene = compile_model(made, &cli, BuildQuality::Auto, start, &progress).unwrap();
        (scene.0, camera)
    };
    let (shared, shared_camera) = model("shared.gltf");
    let (copies, copies_camera) = model("copies.gltf");
    assert_eq!(shared.geometry.instances().len(), 6);
    assert_eq!(shared_camera, copies_camera, "framed alike");
    assert_same_image(&render_rgb(&shared, 2), &render_rgb(&copies, 2), "model");
}

/// `strata trace` of the file numbers its triangles as the file's copies:
/// the same hit records, byte for byte, as the unshared file's.
#[test]
fn trace_numbers_shared_meshes_as_the_files_copies() {
    let dir = temp_dir("gltf-instances-trace");
    let [sphere, pair, single] = files(&dir);
    let (shared, _) = load_mesh_scene(&dir.join("shared.gltf"), BuildQuality::Auto).unwrap();
    let (copies, _) = load_mesh_scene(&dir.join("copies.gltf"), BuildQuality::Auto).unwrap();
    assert!(shared.geometry.instances().is_empty(), "traced as it is");
    assert_eq!(
        shared.geometry.triangle_count() as usize,
        4 * sphere + 2 * pair + single
    );
    assert_eq!(
        shared.geometry.file_order_triangles(),
        copies.geometry.file_order_triangles()
    );
    let mut rng = seeded(46);
    std::fs::write(
        dir.join("rays.bin"),
        encode_rays(&rays(&copies, &mut rng, 4000)),
    )
    .unwrap();
    let trace = |file: &str, hits: &str| {
        let out = strata(
            &dir,
            &[
                "trace", file, "--rays", "rays.bin", "--hits", hits, "--quiet",
            ],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        std::fs::read(dir.join(hits)).unwrap()
    };
    let (a, b) = (trace("shared.gltf", "a.bin"), trace("copies.gltf", "b.bin"));
    assert_eq!(a, b, "the same hits, numbered alike");
    // Ids reach past the first copy of the sphere: the numbering matters.
    let ids: Vec<u32> = a
        .chunks(16)
        .map(|r| u32::from_le_bytes(r[4..8].try_into().unwrap()))
        .filter(|&id| id != u32::MAX)
        .collect();
    assert!(ids.len() > 3000 && ids.iter().any(|&id| id as usize > 2 * sphere));
}

/// A thousand nodes sharing a mesh cost the mesh once and at most 200
/// bytes each (accounted bytes: records, trees and vertices).
#[test]
fn a_thousand_nodes_sharing_a_mesh_cost_it_once_and_200_bytes_each() {
    let dir = temp_dir("gltf-instances-memory");
    let geometry = [sphere(&dir, 64, 48)];
    let mut rng = seeded(3);
    let bytes = |name: &str, n: usize, rng: &mut Rng| {
        let nodes: Vec<(Option<usize>, String)> = (0..n)
            .map(|_| {
                let t = rng.unit_vector() * rng.range(0.0, 100.0);
                let s = rng.range(0.5, 2.0);
                (
                    Some(SPHERE),
                    format!(
                        r#""translation":[{},{},{}],"scale":[{s},{s},{s}]"#,
                        t.x, t.y, t.z
                    ),
                )
            })
            .collect();
        let roots = format!(
            "[{}]",
            (0..n).map(|i| i.to_string()).collect::<Vec<_>>().join(",")
        );
        write_gltf(&dir, name, &geometry, &nodes, &roots, true);
        let text = format!("[[objects]]\nmesh = \"{name}.gltf\"\n");
        let s: Scene = scene_at(&text, &dir.join("s.toml"));
        assert_eq!(s.geometry.instances().len(), n);
        s.geometry.accel_bytes()
    };
    let two = bytes("two", 2, &mut rng);
    let thousand = bytes("thousand", 1000, &mut rng);
    let per_node = (thousand - two) as f64 / 998.0;
    assert!(
        per_node <= 200.0,
        "{per_node:.0} bytes per node (two nodes: {two} bytes)"
    );
    assert!(thousand < 2 * two, "{thousand} against {two}: not copied");
}
