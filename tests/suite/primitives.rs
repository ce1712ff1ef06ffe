//! Every primitive against analytic answers, computed independently in f64:
//! t, normal, facing, rays from inside, tangent and grazing rays, and every
//! primitive under a non-uniform scale plus rotation.

use crate::common::{scene, seeded, Draw};
use glam::{DAffine3, DQuat, DVec3, Vec3};
use strata::math::Ray;

/// Smallest root > 0 of |o + t d|² = 1 (unit sphere), in f64.
fn unit_sphere_t(o: DVec3, d: DVec3) -> Option<f64> {
    let a = d.dot(d);
    let b = 2.0 * o.dot(d);
    let c = o.dot(o) - 1.0;
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    [(-b - s) / (2.0 * a), (-b + s) / (2.0 * a)]
        .into_iter()
        .find(|&t| t > 1e-9)
}

fn object(shape: &str, transform: &str) -> String {
    format!("[[objects]]\n{shape}\n{transform}\n")
}

#[test]
fn sphere_under_non_uniform_scale_and_rotation_matches_the_f64_ellipsoid() {
    let (scale, axis, deg, translate) = (
        [2.0, 0.5, 1.25],
        [1.0, 2.0, -0.5],
        37.0f64,
        [0.3, -0.2, 1.0],
    );
    let text = object(
        "sphere = { center = [0.0, 0.0, 0.0], radius = 1.0 }",
        &format!(
            "transform = {{ translate = {translate:?}, rotate = [{}, {}, {}, {deg}], scale = {scale:?} }}",
            axis[0], axis[1], axis[2]
        ),
    );
    let s = scene(&text);
    assert_eq!(
        s.geometry.shapes().len(),
        1,
        "the sphere stays one analytic primitive"
    );
    let m = DAffine3::from_scale_rotation_translation(
        DVec3::from_array(scale.map(|x: f32| x as f64)),
        DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), deg.to_radians()),
        DVec3::from_array(translate.map(|x: f32| x as f64)),
    );
    let inv = m.inverse();
    let mut rng = seeded(7);
    let mut hits = 0;
    for _ in 0..2000 {
        let o = rng.unit_vector() * 6.0;
        let target = Vec3::new(
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
            rng.range(-0.5, 2.5),
        );
        let d = (target - o).normalize();
        let ray = Ray::new(o, d);
        let (od, dd) = (o.as_dvec3(), d.as_dvec3());
        let expected = unit_sphere_t(inv.transform_point3(od), inv.transform_vector3(dd));
        let got = s.geometry.intersect(&ray);
        match (expected, got) {
            (Some(te), Some(h)) => {
                hits += 1;
                assert!(
                    ((h.t as f64) - te).abs() <= 1e-5 * te.max(1.0),
                    "t {} vs {te}",
                    h.t
                );
                // The normal is the gradient of |M⁻¹x|² at the hit.
                let p = od + te * dd;
                let grad = (inv.matrix3.transpose() * inv.transform_point3(p)).normalize();
                let n = s.geometry.surface(&ray, &h).geometric_normal.as_dvec3();
                assert!(n.dot(grad) > 1.0 - 1e-5, "normal {n} vs {grad}");
            }
            (None, None) => {}
            // Tangent rays may round either way; they must be within a hair of grazing.
            (e, g) => {
                let oo = inv.transform_point3(od);
                let dd2 = inv.transform_vector3(dd);
                let closest = (oo - dd2 * (oo.dot(dd2) / dd2.dot(dd2))).length();
                assert!(
                    (closest - 1.0).abs() < 1e-5,
                    "disagreement off the silhouette: {e:?} vs {g:?}"
                );
            }
        }
    }
    assert!(hits > 500, "the test exercised hits ({hits})");
}

#[test]
fn sphere_rays_from_inside_hit_the_far_side_facing_away() {
    let s = scene(&object(
        "sphere = { center = [1.0, 2.0, 3.0], radius = 2.0 }",
        "",
    ));
    let mut rng = seeded(3);
    for _ in 0..200 {
        let d = rng.unit_vector();
        let ray = Ray::new(Vec3::new(1.0, 2.0, 3.0) + 0.5 * rng.unit_vector(), d);
        let h = s
            .geometry
            .intersect(&ray)
            .expect("a ray from inside always hits");
        let surf = s.geometry.surface(&ray, &h);
        assert!(((surf.p - Vec3::new(1.0, 2.0, 3.0)).length() - 2.0).abs() < 1e-5);
        assert!(
            surf.geometric_normal.dot(d) > 0.0,
            "outward normal faces away from an inside ray"
        );
    }
}

#[test]
fn tangent_and_grazing_sphere_rays() {
    let s = scene(&object(
        "sphere = { center = [0.0, 0.0, 0.0], radius = 1.0 }",
        "",
    ));
    // Exactly tangent along x at y = 1: touches (or misses by rounding), never hits deep.
    let ray = Ray::new(Vec3::new(-5.0, 1.0, 0.0), Vec3::X);
    if let Some(h) = s.geometry.intersect(&ray) {
        assert!((h.t - 5.0).abs() < 1e-2);
    }
    // Just inside the silhouette: hits near x = 0.
    let ray = Ray::new(Vec3::new(-5.0, 0.9999, 0.0), Vec3::X);
    let h = s.geometry.intersect(&ray).expect("grazing hit");
    let p = ray.at(h.t);
    assert!(p.x.abs() < 0.02 && (p.length() - 1.0).abs() < 1e-5);
    // Just outside: misses.
    assert!(s
        .geometry
        .intersect(&Ray::new(Vec3::new(-5.0, 1.0001, 0.0), Vec3::X))
        .is_none());
}

#[test]
fn cylinder_with_caps_under_transform_matches_analytic_answers() {
    // Axis along x from base (1, 0, 0), radius 0.5, height 2, then scaled by 2 in y.
    let text = object(
        "cylinder = { base = [1.0, 0.0, 0.0], axis = [1.0, 0.0, 0.0], radius = 0.5, height = 2.0, caps = true }",
        "transform = { scale = [1.0, 2.0, 1.0] }",
    );
    let s = scene(&text);
    // Down the y axis onto the side at x = 2: the side is at y = 2·0.5 = 1 after scaling.
    let ray = Ray::new(Vec3::new(2.0, 5.0, 0.0), -Vec3::Y);
    let h = s.geometry.intersect(&ray).unwrap();
    assert!((h.t - 4.0).abs() < 1e-5, "t {}", h.t);
    let n = s.geometry.surface(&ray, &h).geometric_normal;
    assert!((n - Vec3::Y).length() < 1e-5, "{n}");
    // Along the axis onto the bottom cap at x = 1.
    let ray = Ray::new(Vec3::new(-3.0, 0.1, 0.1), Vec3::X);
    let h = s.geometry.intersect(&ray).unwrap();
    assert!((h.t - 4.0).abs() < 1e-5);
    assert!((s.geometry.surface(&ray, &h).geometric_normal + Vec3::X).length() < 1e-5);
    // From inside out through the top cap at x = 3.
    let ray = Ray::new(Vec3::new(2.0, 0.0, 0.0), Vec3::X);
    let h = s.geometry.intersect(&ray).unwrap();
    assert!((h.t - 1.0).abs() < 1e-5);
    assert!(s.geometry.surface(&ray, &h).geometric_normal.dot(Vec3::X) > 0.999);
    // Just past the rim misses.
    assert!(s
        .geometry
        .intersect(&Ray::new(
            Vec3::new(2.0, 1.001 * 2.0 * 0.5 + 0.001, 5.0),
            -Vec3::Z
        ))
        .is_none());
}

#[test]
fn open_cylinder_is_seen_from_inside() {
    let s = scene(&object(
        "cylinder = { radius = 1.0, height = 1.0, caps = false }",
        "",
    ));
    // Looking down the axis from above: passes through the open top, no hit.
    assert!(s
        .geometry
        .intersect(&Ray::new(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y))
        .is_none());
    // Slanted from above into the opening: hits the inside wall, normal facing away.
    let ray = Ray::new(Vec3::new(0.0, 2.0, 0.0), Vec3::new(1.0, -1.5, 0.0));
    let h = s.geometry.intersect(&ray).unwrap();
    assert!(
        s.geometry
            .surface(&ray, &h)
            .geometric_normal
            .dot(ray.direction)
            > 0.0
    );
}

#[test]
fn plane_and_triangle_under_rotation_and_scale() {
    let text = format!(
        "{}{}",
        object(
            "plane = { point = [0.0, -1.0, 0.0], normal = [0.0, 1.0, 0.0] }",
            "transform = { rotate = [0.0, 0.0, 1.0, 90.0] }"
        ),
        object(
            "triangle = { v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] }",
            "transform = { translate = [0.0, 0.0, -2.0], scale = [3.0, 2.0, 1.0] }"
        ),
    );
    let s = scene(&text);
    // The plane y = -1 rotated 90° about z becomes x = +1 with normal -x.
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    let h = s.geometry.intersect(&ray).unwrap();
    assert!((h.t - 1.0).abs() < 1e-6);
    assert!((s.geometry.surface(&ray, &h).geometric_normal + Vec3::X).length() < 1e-6);
    // The triangle now spans (0,0),(3,0),(0,2) at z = -2; barycentrics follow.
    let ray = Ray::new(Vec3::new(1.5, 0.5, 0.0), -Vec3::Z);
    let h = s.geometry.intersect(&ray).unwrap();
    assert!((h.t - 2.0).abs() < 1e-6);
    assert!(
        (h.u - 0.5).abs() < 1e-6 && (h.v - 0.25).abs() < 1e-6,
        "{} {}",
        h.u,
        h.v
    );
    assert!(s
        .geometry
        .intersect(&Ray::new(Vec3::new(2.0, 1.5, 0.0), -Vec3::Z))
        .is_none());
}

#[test]
fn matrix_transforms_equal_their_trs_form() {
    let trs = scene(&object(
        "sphere = { radius = 1.0 }",
        "transform = { translate = [1.0, 2.0, 3.0], scale = [2.0, 1.0, 1.0] }",
    ));
    let mat = scene(&object(
        "sphere = { radius = 1.0 }",
        "transform = { matrix = [[2.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 2.0], [0.0, 0.0, 1.0, 3.0], [0.0, 0.0, 0.0, 1.0]] }",
    ));
    let mut rng = seeded(11);
    for _ in 0..200 {
        let ray = Ray::new(
            rng.unit_vector() * 8.0 + Vec3::new(1.0, 2.0, 3.0),
            rng.unit_vector(),
        );
        assert_eq!(
            trs.geometry.intersect(&ray).map(|h| h.t),
            mat.geometry.intersect(&ray).map(|h| h.t)
        );
    }
}

#[test]
fn groups_nest_transforms_and_pass_materials_down() {
    let text = r#"
[materials.red]
diffuse = [1.0, 0.0, 0.0]
[[objects]]
material = "red"
transform = { translate = [10.0, 0.0, 0.0] }
group = [
  { sphere = { radius = 1.0 }, transform = { translate = [0.0, 5.0, 0.0] } },
  { group = [ { sphere = { radius = 0.5 } } ], transform = { scale = 2.0 } },
]
"#;
    let s = scene(text);
    assert_eq!(s.geometry.shapes().len(), 2);
    let ray = Ray::new(Vec3::new(10.0, 5.0, 10.0), -Vec3::Z);
    let h = s.geometry.intersect(&ray).unwrap();
    assert!((h.t - 9.0).abs() < 1e-5);
    assert_eq!(
        s.materials[s.geometry.surface(&ray, &h).material as usize].diffuse,
        Vec3::X
    );
    let h = s
        .geometry
        .intersect(&Ray::new(Vec3::new(10.0, 0.0, 10.0), -Vec3::Z))
        .unwrap();
    assert!(
        (h.t - 9.0).abs() < 1e-5,
        "uniformly scaled sphere of radius 0.5·2 = 1"
    );
}
