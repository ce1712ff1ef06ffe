//! Self-intersection, in the style of pbrt-v4's re-intersection test: for
//! every primitive type, under random transforms, at scales 1e-4, 1 and 1e5,
//! rays spawned from a hit (reflection, shadow, refraction entering and
//! leaving) never hit their own surface again at t ≈ 0.

use crate::common::{scene_at, seeded, Draw, StreamRng as Rng};
use std::path::Path;
use strata::math::offset::spawn_origin;
use strata::math::Ray;
use strata::scene::Scene;

/// One object of each primitive type, in unit size around the origin (area
/// light surfaces are placed by the caller, since lights take no transform).
/// `identity` is an instances file of one identity row: the instanced
/// mesh is walked in object space under the object's random transform.
fn objects(identity: &Path) -> Vec<(&'static str, String)> {
    let mesh = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/meshes/icosphere.obj");
    vec![
        ("sphere", "sphere = { radius = 1.0 }".to_string()),
        (
            "cylinder",
            "cylinder = { base = [0.0, -0.5, 0.0], radius = 0.7, height = 1.0 }".to_string(),
        ),
        (
            "triangle",
            "triangle = { v = [[-1.0, -1.0, 0.0], [1.0, -0.5, 0.2], [0.0, 1.0, -0.1]] }"
                .to_string(),
        ),
        ("mesh", format!("mesh = \"{mesh}\"")),
        (
            "instanced mesh",
            format!("mesh = \"{mesh}\"\ninstances = \"{}\"", identity.display()),
        ),
        (
            "plane",
            "plane = { point = [0.0, 0.1, 0.0], normal = [0.1, 1.0, 0.2] }".to_string(),
        ),
        (
            "rect light",
            "[[lights]]\ntype = \"rect\"\ncorner = CORNER\nedge_u = EDGE_U\nedge_v = EDGE_V\nradiance = [1.0, 1.0, 1.0]\n"
                .to_string(),
        ),
        (
            "disk light",
            "[[lights]]\ntype = \"disk\"\ncenter = CORNER\nnormal = NORMAL\nradius = RADIUS\nradiance = [1.0, 1.0, 1.0]\n"
                .to_string(),
        ),
    ]
}

fn random_transform(rng: &mut Rng, scale: f32) -> String {
    let axis = rng.unit_vector();
    let s = [
        rng.range(0.3, 3.0) * scale,
        rng.range(0.3, 3.0) * scale,
        rng.range(0.3, 3.0) * scale,
    ];
    let t = rng.unit_vector() * rng.range(0.0, 4.0) * scale;
    format!(
        "transform = {{ translate = [{}, {}, {}], rotate = [{}, {}, {}, {}], scale = [{}, {}, {}] }}",
        t.x,
        t.y,
        t.z,
        axis.x,
        axis.y,
        axis.z,
        rng.range(0.0, 360.0),
        s[0],
        s[1],
        s[2]
    )
}

/// The first hit of `ray`, if it is the same primitive at a distance that
/// can only be a self-intersection.
fn self_hit(scene: &Scene, ray: &Ray, prim: u32, scale: f32) -> Option<f32> {
    scene
        .geometry
        .intersect(ray)
        .filter(|h| h.prim == prim && h.t * ray.direction.length() < 1e-4 * scale)
        .map(|h| h.t)
}

#[test]
fn spawned_rays_never_hit_their_own_surface_at_any_scale() {
    let mut rng = seeded(2024);
    let mut checked = 0usize;
    let dir = crate::common::temp_dir("robust-instance");
    let identity = dir.join("identity.csv");
    std::fs::write(&identity, "1,0,0,0,0,1,0,0,0,0,1,0\n").unwrap();
    for (name, shape) in objects(&identity) {
        for scale in [1e-4f32, 1.0, 1e5] {
            for _ in 0..1000 {
                // 1000 random transforms per (shape, scale), each probed by 2 rays.
                let text = if shape.starts_with("[[lights]]") {
                    // Light surfaces take no transform: place them by random edges instead.
                    let (e1, e2) = (rng.unit_vector() * scale, rng.unit_vector() * scale);
                    let c = rng.unit_vector() * rng.range(0.0, 2.0) * scale - 0.5 * (e1 + e2);
                    shape
                        .replace("CORNER", &format!("{:?}", c.to_array()))
                        .replace("EDGE_U", &format!("{:?}", e1.to_array()))
                        .replace("EDGE_V", &format!("{:?}", e2.to_array()))
                        .replace("NORMAL", &format!("{:?}", e1.cross(e2).to_array()))
                        .replace("RADIUS", &format!("{}", 0.8 * scale))
                } else {
                    format!(
                        "[[objects]]\n{shape}\n{}\n",
                        random_transform(&mut rng, scale)
                    )
                };
                let scene = scene_at(&text, Path::new("robust.toml"));
                for _ in 0..2 {
                    let target = rng.unit_vector() * rng.range(0.0, 0.8) * scale;
                    let origin = target + rng.unit_vector() * 20.0 * scale;
                    let ray = Ray::new(origin, (target - origin).normalize());
                    let Some(hit) = scene.geometry.intersect(&ray) else {
                        continue;
                    };
                    let s = scene.geometry.surface(&ray, &hit);
                    let n = s.geometric_normal;
                    let wo = -ray.direction;
                    let front = if n.dot(wo) >= 0.0 { n } else { -n };
                    let mirror = 2.0 * front.dot(wo) * front - wo;
                    let mut spawned = vec![
                        ("reflection", mirror),
                        (
                            "refraction in",
                            (-front + 0.3 * rng.unit_vector()).normalize(),
                        ),
                    ];
                    // A shadow ray towards a random direction above the surface.
                    let mut up = rng.unit_vector();
                    if up.dot(front) < 0.0 {
                        up = -up;
                    }
                    spawned.push(("shadow", up));
                    for (kind, dir) in spawned {
                        let o = spawn_origin(s.p, s.p_error, n, dir);
                        let r = Ray::new(o, dir);
                        assert_eq!(
                            self_hit(&scene, &r, hit.prim, scale),
                            None,
                            "{name} at scale {scale}: {kind} ray re-hits itself"
                        );
                        checked += 1;
                        if kind == "refraction in" {
                            // Leaving again from the far side of a closed shape.
                            if let Some(inner) =
                                scene.geometry.intersect(&r).filter(|h| h.prim == hit.prim)
                            {
                                let s2 = scene.geometry.surface(&r, &inner);
                                let out_dir = r.direction;
                                let o2 =
                                    spawn_origin(s2.p, s2.p_error, s2.geometric_normal, out_dir);
                                let r2 = Ray::new(o2, out_dir);
                                assert_eq!(
                                    self_hit(&scene, &r2, inner.prim, scale),
                                    None,
                                    "{name} at scale {scale}: leaving ray re-hits itself"
                                );
                                checked += 1;
                            }
                        }
                    }
                }
            }
        }
    }
    assert!(
        checked > 40_000,
        "the test exercised many spawned rays ({checked})"
    );
}

#[test]
fn a_flat_floor_under_a_grazing_light_shows_no_acne() {
    // A directional light 89.5° from the normal over a floor at the origin,
    // 1e5 away from it, and at scale 1e-4; the floor is an infinite plane or
    // a two-triangle quad. Every pixel must see the same irradiance: acne
    // would darken some of them.
    let expected = 100.0 * 0.0087265 / std::f32::consts::PI;
    for (offset, size) in [(0.0f32, 1.0f32), (1e5, 1.0), (0.0, 1e-4), (1e5, 1e-2)] {
        let (o, w) = (offset, 10.0 * size);
        let floors = [
            format!("plane = {{ point = [{o}, 0.0, {o}], normal = [0.0, 1.0, 0.0] }}"),
            format!(
                "group = [ {{ triangle = {{ v = [[{a}, 0.0, {a}], [{a}, 0.0, {b}], [{b}, 0.0, {b}]] }} }}, \
                 {{ triangle = {{ v = [[{a}, 0.0, {a}], [{b}, 0.0, {b}], [{b}, 0.0, {a}]] }} }} ]",
                a = o - w,
                b = o + w
            ),
        ];
        for floor in floors {
            let text = format!(
                "[render]\nwidth = 64\nheight = 64\n[camera]\ntype = \"orthographic\"\nposition = [{o}, {h}, {o}]\n\
                 look_at = [{o}, 0.0, {o}]\nup = [0.0, 0.0, -1.0]\nheight = {v}\n[materials.white]\ndiffuse = [1.0, 1.0, 1.0]\n\
                 [[lights]]\ntype = \"directional\"\ndirection = [0.999962, -0.0087265, 0.0]\nirradiance = [100.0, 100.0, 100.0]\n\
                 [[objects]]\n{floor}\nmaterial = \"white\"\n",
                h = 5.0 * size,
                v = 4.0 * size,
            );
            let scene = scene_at(&text, Path::new("acne.toml"));
            let img = crate::common::render_rgb(&scene, 0);
            let speckles = img
                .iter()
                .filter(|p| (p.x - expected).abs() > 1e-3 * expected)
                .count();
            assert_eq!(
                speckles, 0,
                "offset {offset} size {size} floor {floor}: {speckles} of 4096 pixels differ"
            );
        }
    }
}
