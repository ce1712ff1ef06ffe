//! Every query answers for `(tmin, tmax]` ([`super::query`]'s module
//! docs): a hit exactly at `tmax` counts and one exactly at `tmin` does
//! not, for closest hits and occlusion (alone, in packets, in streams) and
//! for crossings and their counts, on triangles, an instance of them, a
//! sphere and a plane.

use super::csg::Csg;
use super::instance::placed;
use super::{AnalyticPrim, Geometry, GeometryParts, MeshRange, Shape, NO_TRANSFORM};
use crate::accel::{BuildQuality, Bvh8};
use crate::math::{Aabb, Ray};
use crate::shape::plane::Plane;
use crate::shape::sphere::Sphere;
use glam::{Affine3A, Vec3};

/// A mesh of `tris`, triangle `i` primitive `i`.
fn mesh(tris: &[[Vec3; 3]]) -> Geometry {
    let boxes = tris.iter().map(|t| Aabb::from_points(t)).collect();
    let parts = GeometryParts {
        meshes: vec![MeshRange {
            name: "mesh".into(),
            first: 0,
            count: tris.len() as u32,
            material: 0,
            mirrored: false,
            normals: None,
            uvs: None,
            tangents: None,
        }],
        ..GeometryParts::default()
    };
    Geometry::new(parts, Bvh8::build_from(boxes, BuildQuality::Auto), |id| {
        tris[id as usize]
    })
}

/// Two triangles, a square at z = `z` across the z axis.
fn square(z: f32) -> Geometry {
    let [a, b, c, d] =
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| Vec3::new(x, y, z));
    mesh(&[[a, b, c], [a, c, d]])
}

fn sphere() -> Geometry {
    let prim = AnalyticPrim {
        shape: Shape::Sphere(Sphere {
            center: Vec3::new(0.1, 0.2, 3.0),
            radius: 0.7,
        }),
        transform: NO_TRANSFORM,
        material: 0,
    };
    let bvh = Bvh8::build_from_with_others(
        vec![prim.shape.bounds(&Csg::default())],
        BuildQuality::Auto,
        0,
    );
    let parts = GeometryParts {
        shapes: vec![prim],
        ..GeometryParts::default()
    };
    Geometry::new(parts, bvh, |_| unreachable!("no triangles"))
}

fn plane() -> Geometry {
    let parts = GeometryParts {
        planes: vec![Plane {
            point: Vec3::new(0.0, 0.0, 2.5),
            normal: Vec3::new(0.0, 0.6, -0.8),
            material: 0,
        }],
        ..GeometryParts::default()
    };
    Geometry::new(
        parts,
        Bvh8::build_from(Vec::new(), BuildQuality::Auto),
        |_| unreachable!("no triangles"),
    )
}

/// The ray every case shoots: off every axis, so no t is a round number.
fn ray(tmin: f32, tmax: f32) -> Ray {
    Ray {
        origin: Vec3::new(0.013, -0.027, 0.0),
        direction: Vec3::new(0.031, 0.052, 1.0),
        tmin,
        tmax,
    }
}

/// Whether the closest-hit and occlusion queries, in every way of
/// tracing, find a hit at `t` on `ray`; panics if they disagree.
fn closest_finds(g: &Geometry, ray: &Ray, t: f32) -> bool {
    let one = g.intersect(ray);
    let mut packet = [None];
    g.intersect_packet(&[*ray], &mut packet);
    let mut stream = [None; 20];
    g.intersect_stream(&[*ray; 20], &mut stream);
    assert!(
        packet[0] == one && stream.iter().all(|&h| h == one),
        "{ray:?}"
    );
    let blocked = g.occluded(ray);
    let mut packet = [false];
    g.occluded_packet(&[*ray], u32::MAX, &mut packet);
    let mut stream = [false; 20];
    g.occluded_stream(&[*ray; 20], u32::MAX, &mut stream);
    assert!(packet[0] == blocked && stream.iter().all(|&b| b == blocked));
    let found = one.is_some_and(|h| h.t == t);
    assert_eq!(
        found, blocked,
        "{ray:?}: a hit at t blocks the ray, no hit does not"
    );
    found
}

/// Whether the crossing queries find a crossing at `t` on `ray`.
fn crossing_finds(g: &Geometry, ray: &Ray, t: f32) -> bool {
    let mut out = Vec::new();
    g.crossings(ray, &mut out);
    assert_eq!(g.count_crossings(ray) as usize, out.len());
    out.iter().any(|c| c.t == t)
}

/// The four cases around a hit at `t`: at `tmax` it counts, just past
/// `tmax` it does not; at `tmin` it does not, just past `tmin` it does.
fn check_ends(what: &str, finds: impl Fn(&Ray, f32) -> bool, t: f32) {
    assert!(finds(&ray(0.0, t), t), "{what}: a hit at tmax counts");
    assert!(!finds(&ray(0.0, t.next_down()), t), "{what}: past tmax");
    assert!(
        !finds(&ray(t, t.next_up()), t),
        "{what}: a hit at tmin does not"
    );
    assert!(
        finds(&ray(t.next_down(), t.next_up()), t),
        "{what}: past tmin"
    );
}

#[test]
fn every_query_answers_for_an_interval_open_at_tmin_and_closed_at_tmax() {
    let moved = Affine3A::from_scale_rotation_translation(
        Vec3::new(1.5, 0.7, 1.0),
        glam::Quat::from_rotation_z(0.3),
        Vec3::new(0.01, 0.02, 0.9),
    );
    let cases = [
        ("triangles", square(2.0), true),
        (
            "an instance",
            placed(square(1.1), &[moved], BuildQuality::Auto).unwrap(),
            true,
        ),
        ("a sphere", sphere(), false),
        ("a plane", plane(), false),
    ];
    for (what, g, mesh) in cases {
        let t = g.intersect(&ray(0.0, f32::INFINITY)).expect(what).t;
        assert!(t > 0.5, "{what}: {t}");
        check_ends(what, |r, t| closest_finds(&g, r, t), t);
        let mut all = Vec::new();
        g.crossings(&ray(0.0, f32::INFINITY), &mut all);
        if mesh {
            // An instance's crossing is its copy's, in world space: its t
            // may differ from the object-space closest hit's by rounding.
            let t = all.first().expect(what).t;
            check_ends(what, |r, t| crossing_finds(&g, r, t), t);
        } else {
            assert!(all.is_empty(), "{what}: crossings are triangles' alone");
        }
    }
}
