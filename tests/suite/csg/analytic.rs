//! CSG solids whose answers are known: the thickness and normals of a
//! lens, the hole through a drilled cylinder, the depth of a die's pit,
//! the empty difference of identical spheres, touching spheres that render
//! as the two spheres, tight bounds, and a group operand as the union of
//! its members.

use super::reference::{op, sphere, Op, Trs};
use super::{csg_scene, die, drilled, scenes_dir};
use crate::common::{render_rgb, scene, scene_at, seeded, Draw};
use glam::Vec3;
use strata::math::Ray;

#[test]
fn the_lens_is_as_thick_along_its_axis_as_two_radii_minus_the_centre_distance() {
    // Spheres of radius r with centres d apart overlap in a lens 2r − d thick.
    for (r, d, tilt) in [
        (2.0f64, 3.2f64, 0.0f64),
        (1.0, 0.5, 35.0),
        (5.0, 9.9, -60.0),
    ] {
        let node = op(
            Op::Intersection,
            sphere([0.0, 0.0, -d / 2.0], r),
            sphere([0.0, 0.0, d / 2.0], r),
        )
        .with(Trs {
            rotate: Some([1.0, 0.0, 0.0, tilt]),
            ..Trs::default()
        });
        let s = csg_scene(&node, "");
        let axis = Vec3::new(
            0.0,
            -(tilt.to_radians().sin() as f32),
            tilt.to_radians().cos() as f32,
        );
        let ray = Ray::new(10.0 * axis, -axis);
        let entry = s.geometry.intersect(&ray).expect("the axis meets the lens");
        let exit = s
            .geometry
            .intersect(&Ray {
                tmin: entry.t,
                ..ray
            })
            .expect("and leaves it");
        let thickness = (exit.t - entry.t) as f64;
        assert!(
            (thickness - (2.0 * r - d)).abs() < 2e-5 * r,
            "r {r} d {d}: {thickness}"
        );
        assert!(((10.0 - entry.t as f64) - (r - d / 2.0)).abs() < 2e-5 * r);
        // Outward normals: towards the ray on entry, away from it on exit.
        assert!(s.geometry.surface(&ray, &entry).geometric_normal.dot(axis) > 0.9999);
        assert!(s.geometry.surface(&ray, &exit).geometric_normal.dot(axis) < -0.9999);
        // From the lens centre, either way, the face is half the thickness away.
        for dir in [axis, -axis] {
            let h = s
                .geometry
                .intersect(&Ray::new(Vec3::ZERO, dir))
                .expect("a ray from inside leaves");
            assert!((h.t as f64 - (r - d / 2.0)).abs() < 2e-5 * r);
        }
    }
}

#[test]
fn a_ray_down_the_drilled_hole_passes_and_its_wall_faces_the_hole() {
    let s = csg_scene(&drilled(), "");
    // Along the hole: nothing, also off-centre inside the hole's radius.
    for (y, z) in [(0.0, 0.0), (0.2, 0.1), (-0.1, -0.35)] {
        assert!(
            s.geometry
                .intersect(&Ray::new(Vec3::new(-5.0, y, z), Vec3::X))
                .is_none(),
            "({y}, {z})"
        );
        assert!(!s
            .geometry
            .occluded(&Ray::segment(Vec3::new(-5.0, y, z), Vec3::X, 10.0)));
    }
    // Beside the hole: the cylinder's side, where x² + z² = 1.
    let h = s
        .geometry
        .intersect(&Ray::new(Vec3::new(-5.0, 0.6, 0.0), Vec3::X))
        .unwrap();
    assert!((h.t - 4.0).abs() < 1e-5);
    // Down through the top cap into the hole's upper wall at y = 0.4, whose
    // normal is the drill's, flipped: it points down into the hole.
    let ray = Ray::new(Vec3::new(0.1, 5.0, 0.0), -Vec3::Y);
    let cap = s.geometry.intersect(&ray).unwrap();
    assert!((cap.t - 4.0).abs() < 1e-5);
    let wall = s.geometry.intersect(&Ray { tmin: cap.t, ..ray }).unwrap();
    assert!((wall.t - 4.6).abs() < 1e-5, "{}", wall.t);
    assert!((s.geometry.surface(&ray, &wall).geometric_normal + Vec3::Y).length() < 1e-5);
    let floor = s
        .geometry
        .intersect(&Ray {
            tmin: wall.t,
            ..ray
        })
        .unwrap();
    assert!(
        (floor.t - 5.4).abs() < 1e-5,
        "hole's lower wall at y = −0.4"
    );
    assert!((s.geometry.surface(&ray, &floor).geometric_normal - Vec3::Y).length() < 1e-5);
}

#[test]
fn a_ray_into_the_die_pit_hits_at_the_pit_depth() {
    // Pit: the sphere of radius 0.5 at z = 1.2 bites 0.3 into the face z = 1.
    let s = csg_scene(&die(), "");
    // Straight down the face centre, which lies on the face's diagonal edge.
    let ray = Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
    let h = s.geometry.intersect(&ray).unwrap();
    assert!(
        (h.t - 4.3).abs() < 1e-5,
        "pit bottom at z = 0.7, got t = {}",
        h.t
    );
    let n = s.geometry.surface(&ray, &h).geometric_normal;
    assert!(
        (n - Vec3::Z).length() < 1e-5,
        "the pit's floor faces out of the die: {n}"
    );
    // On the pit's wall: z = 1.2 − √(0.25 − x²).
    let x = 0.45f32;
    let h = s
        .geometry
        .intersect(&Ray::new(Vec3::new(x, 0.0, 5.0), -Vec3::Z))
        .unwrap();
    let z = 1.2 - (0.25 - x * x).sqrt();
    assert!((5.0 - h.t - z).abs() < 1e-5);
    // Beside the pit: the flat face of the cube mesh, then the far face.
    let ray = Ray::new(Vec3::new(0.6, -0.5, 5.0), -Vec3::Z);
    let face = s.geometry.intersect(&ray).unwrap();
    assert!((face.t - 4.0).abs() < 1e-5);
    assert!((s.geometry.surface(&ray, &face).geometric_normal - Vec3::Z).length() < 1e-6);
    let back = s
        .geometry
        .intersect(&Ray {
            tmin: face.t,
            ..ray
        })
        .unwrap();
    assert!((back.t - 6.0).abs() < 1e-5);
    assert!((s.geometry.surface(&ray, &back).geometric_normal + Vec3::Z).length() < 1e-6);
}

#[test]
fn the_difference_of_identical_spheres_is_empty_with_no_nan() {
    let node = op(
        Op::Difference,
        sphere([0.3, 0.2, 0.1], 1.0),
        sphere([0.3, 0.2, 0.1], 1.0),
    );
    let text =
        node.object("") + "[render]\nwidth = 48\nheight = 36\nbackground = [0.25, 0.5, 0.75]\n";
    let s = scene(&text);
    let mut rng = seeded(5);
    for _ in 0..20_000 {
        let o = Vec3::new(
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
        );
        let d = rng.unit_vector();
        assert!(s.geometry.intersect(&Ray::new(o, d)).is_none());
        assert!(!s.geometry.occluded(&Ray::segment(o, d, 10.0)));
    }
    // The same with the copy under an identity transform given as a matrix.
    let text = "[[objects]]\ncsg = { op = \"difference\", a = { sphere = { radius = 1.0 } }, b = { sphere = { radius = 1.0 }, transform = { matrix = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]] } } }\n";
    let s2 = scene(text);
    for _ in 0..2000 {
        let o = rng.unit_vector() * rng.range(0.0, 3.0);
        assert!(s2
            .geometry
            .intersect(&Ray::new(o, rng.unit_vector()))
            .is_none());
    }
    let img = render_rgb(&s, 0);
    assert!(
        img.iter().all(|p| *p == Vec3::new(0.25, 0.5, 0.75)),
        "only background, no NaN"
    );
}

#[test]
fn a_union_of_touching_spheres_renders_exactly_like_the_two_spheres() {
    // Spheres touching at the origin, seen across the contact point, matte and glass.
    let base = "[render]\nwidth = 120\nheight = 90\nspp = 4\nmax_depth = 6\nbackground = [0.2, 0.3, 0.4]\n\
        [camera]\nposition = [0.4, 0.7, 4.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 30.0\n\
        [materials.m]\ndiffuse = [0.3, 0.3, 0.3]\nspecular = [0.2, 0.2, 0.2]\nshininess = 40.0\nreflectivity = 0.2\ntransparency = 0.3\nior = 1.4\n\
        [[lights]]\ntype = \"point\"\nposition = [0.5, 4.0, 3.0]\nintensity = [20.0, 20.0, 20.0]\n\
        [[objects]]\nplane = { point = [0.0, -1.0, 0.0], normal = [0.0, 1.0, 0.0] }\n";
    let a = "{ sphere = { center = [-1.0, 0.0, 0.0], radius = 1.0 } }";
    let b = "{ sphere = { center = [1.0, 0.0, 0.0], radius = 1.0 } }";
    let union = scene(&format!(
        "{base}[[objects]]\nmaterial = \"m\"\ncsg = {{ op = \"union\", a = {a}, b = {b} }}\n"
    ));
    let apart = scene(&format!(
        "{base}[[objects]]\nmaterial = \"m\"\ngroup = [{a}, {b}]\n"
    ));
    let (u, g) = (render_rgb(&union, 0), render_rgb(&apart, 0));
    assert!(u.iter().all(|p| p.is_finite()));
    let differing: Vec<usize> = (0..u.len())
        .filter(|&i| (u[i] - g[i]).abs().max_element() > 1e-6)
        .collect();
    assert!(differing.is_empty(), "pixels that differ: {differing:?}");
}

#[test]
fn a_csg_object_is_one_primitive_with_a_tight_bound() {
    let a = "{ sphere = { center = [-0.5, 0.0, 0.0], radius = 1.0 } }";
    let b = "{ sphere = { center = [0.5, 0.0, 0.0], radius = 1.0 } }";
    let bounds = |o: &str| {
        let s = scene(&format!(
            "[[objects]]\ncsg = {{ op = \"{o}\", a = {a}, b = {b} }}\n"
        ));
        assert_eq!(s.geometry.primitive_count(), 1);
        (s.geometry.bvh().bounds.min, s.geometry.bvh().bounds.max)
    };
    let close = |(lo, hi): (Vec3, Vec3), elo: Vec3, ehi: Vec3| {
        assert!(
            (lo - elo).abs().max_element() < 1e-3 && (hi - ehi).abs().max_element() < 1e-3,
            "{lo} {hi}"
        );
    };
    close(
        bounds("intersection"),
        Vec3::new(-0.5, -1.0, -1.0),
        Vec3::new(0.5, 1.0, 1.0),
    );
    close(
        bounds("difference"),
        Vec3::new(-1.5, -1.0, -1.0),
        Vec3::new(0.5, 1.0, 1.0),
    );
    close(
        bounds("union"),
        Vec3::new(-1.5, -1.0, -1.0),
        Vec3::new(1.5, 1.0, 1.0),
    );
    // Disjoint operands: the intersection is provably empty and not traced at all.
    let s = scene("[[objects]]\ncsg = { op = \"intersection\", a = { sphere = { center = [-2.0, 0.0, 0.0], radius = 1.0 } }, b = { sphere = { center = [2.0, 0.0, 0.0], radius = 1.0 } } }\n");
    assert_eq!(s.geometry.primitive_count(), 0);
}

#[test]
fn a_group_operand_is_the_union_of_its_members() {
    // A slab minus a row of five spheres: five separate pits.
    let pits: Vec<String> = (0..5)
        .map(|i| {
            format!(
                "{{ sphere = {{ center = [{}.0, 0.0, 1.0], radius = 0.3 }} }}",
                i * 2 - 4
            )
        })
        .collect();
    let text = format!(
        "[[objects]]\ncsg = {{ op = \"difference\", a = {{ mesh = \"meshes/cube.obj\", transform = {{ scale = [6.0, 1.0, 1.0] }} }}, b = {{ group = [{}] }} }}\n",
        pits.join(", ")
    );
    let s = scene_at(&text, &scenes_dir().join("csg-test.toml"));
    for x in [-4.0f32, -2.0, 0.0, 2.0, 4.0] {
        let h = s
            .geometry
            .intersect(&Ray::new(Vec3::new(x, 0.0, 5.0), -Vec3::Z))
            .unwrap();
        assert!((h.t - 4.3).abs() < 1e-5, "pit at x = {x}");
    }
    let h = s
        .geometry
        .intersect(&Ray::new(Vec3::new(-3.0, 0.0, 5.0), -Vec3::Z))
        .unwrap();
    assert!((h.t - 4.0).abs() < 1e-5, "flat between pits");
}
