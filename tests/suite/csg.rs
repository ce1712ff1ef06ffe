//! CSG booleans against analytic answers and against an independent f64
//! reference (brute-force point membership, `csg_reference`): each operator,
//! closed meshes, capped cylinders, nesting with transforms, coincident and
//! touching surfaces, rays spawned from CSG hits, materials, bounds and bad
//! operands.

use crate::csg_reference;

use crate::common::{render_rgb, scene, scene_at, seeded, Draw, StreamRng};
use csg_reference::{op, sphere, Node, Op, Reference, Trs};
use glam::Vec3;
use std::path::{Path, PathBuf};
use std::process::Command;
use strata::math::offset::spawn_origin;
use strata::math::Ray;
use strata::scene::Scene;
use strata::shade::bsdf::refract;

/// Disagreements with the reference closer than this (in t, along unit
/// directions, for solids of size ~1) are rounding, not errors.
const DELTA: f64 = 1e-4;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// A scene holding just `node`, read as if from scenes/ so that
/// `meshes/cube.obj` resolves.
fn csg_scene(node: &Node, extra: &str) -> Scene {
    scene_at(&node.object(extra), &scenes_dir().join("csg-test.toml"))
}

fn cube(t: Trs) -> Node {
    Node::Cube {
        path: "meshes/cube.obj".into(),
        t,
    }
}

fn cylinder(base: [f64; 3], axis: [f64; 3], radius: f64, height: f64) -> Node {
    Node::Cylinder {
        base,
        axis,
        radius,
        height,
        t: Trs::default(),
    }
}

/// Two overlapping spheres of different sizes.
fn two_spheres(o: Op) -> Node {
    op(
        o,
        sphere([-0.5, 0.0, 0.0], 1.0),
        sphere([0.4, 0.3, 0.1], 0.8),
    )
}

/// A rounded die (a cube meet a sphere) with two pits.
fn die() -> Node {
    let body = op(
        Op::Intersection,
        cube(Trs::default()),
        sphere([0.0, 0.0, 0.0], 1.35),
    );
    let pits = op(
        Op::Union,
        sphere([0.0, 0.0, 1.2], 0.5),
        sphere([1.1, 0.3, -0.3], 0.4),
    );
    op(Op::Difference, body, pits)
}

/// A cylinder along y with a hole along x through its middle.
fn drilled() -> Node {
    op(
        Op::Difference,
        cylinder([0.0, -1.0, 0.0], [0.0, 1.0, 0.0], 1.0, 2.0),
        cylinder([-2.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.4, 4.0),
    )
}

/// Three levels of operations, with transforms (non-uniform scales and
/// rotations included) at every level, over every kind of leaf.
fn nested() -> Node {
    let rot = |axis: [f64; 3], deg: f64| Some([axis[0], axis[1], axis[2], deg]);
    let ellipsoid = sphere([0.3, 0.0, 0.0], 0.5).with(Trs {
        scale: Some([1.0, 0.5, 1.5]),
        ..Trs::default()
    });
    let level3 = op(Op::Difference, sphere([0.0, 0.0, 0.0], 0.6), ellipsoid).with(Trs {
        translate: [0.2, 0.1, 0.3],
        rotate: rot([0.0, 1.0, 1.0], 40.0),
        scale: None,
    });
    let rod = Node::Cylinder {
        base: [0.0, -1.5, 0.2],
        axis: [0.2, 1.0, 0.0],
        radius: 0.35,
        height: 3.0,
        t: Trs {
            rotate: rot([0.0, 0.0, 1.0], 10.0),
            ..Trs::default()
        },
    };
    let box_ = cube(Trs {
        scale: Some([1.0, 0.8, 1.2]),
        rotate: rot([1.0, 0.0, 0.0], 15.0),
        translate: [0.0; 3],
    });
    let a = op(Op::Intersection, box_, sphere([0.0, 0.0, 0.0], 1.3))
        .with(Trs::translate([0.1, 0.0, 0.0]));
    let b = op(Op::Union, rod, level3).with(Trs {
        translate: [0.5, 0.2, 0.4],
        rotate: rot([1.0, 0.0, 0.0], -20.0),
        scale: Some([1.1, 1.0, 0.9]),
    });
    op(Op::Difference, a, b).with(Trs {
        translate: [0.2, -0.1, 0.3],
        rotate: rot([1.0, 1.0, 0.0], 30.0),
        scale: Some([1.2, 1.2, 1.2]),
    })
}

/// Agreement of strata's CSG with the reference over many rays.
#[derive(Debug, Default)]
struct Tally {
    rays: usize,
    hits: usize,
    /// Disagreements where surfaces of two different leaves cross the ray
    /// within 2δ of each other there: which one is first is up to rounding.
    coincident: usize,
    /// Other disagreements where strata and the reference differ only on a
    /// stretch of ray that lies wholly within δ of the solid's boundary (a
    /// ray grazing a surface, where t is ill-conditioned).
    in_band: usize,
    /// Everything else: real errors, described.
    real: Vec<String>,
}

/// Whether `p` lies within about `DELTA` of the reference solid's boundary:
/// membership is not the same at all 26 points around it at that distance.
fn near_boundary(reference: &Reference, p: glam::DVec3) -> bool {
    let inside = reference.contains(p);
    (0..27).filter(|&i| i != 13).any(|i| {
        let u = glam::DVec3::new(
            (i % 3) as f64 - 1.0,
            ((i / 3) % 3) as f64 - 1.0,
            (i / 9) as f64 - 1.0,
        );
        reference.contains(p + DELTA * u.normalize()) != inside
    })
}

impl Tally {
    /// Judge strata's answer `got` for the ray `o + t d`, t > `tmin`: it
    /// must be the reference's first boundary (within δ), and membership
    /// must change across it (the point-membership test). `next(t)` is
    /// strata's first boundary after t, to find where the answers differ.
    fn judge(
        &mut self,
        reference: &Reference,
        o: Vec3,
        d: Vec3,
        tmin: f64,
        got: Option<f32>,
        next: impl Fn(f64) -> Option<f64>,
    ) {
        let (o, d) = (o.as_dvec3(), d.as_dvec3().normalize());
        let got = got.map(f64::from);
        self.rays += 1;
        self.hits += got.is_some() as usize;
        let expected = reference.first_boundary(o, d, tmin);
        let ok = match (got, expected) {
            (None, None) => true,
            (Some(t), Some(e)) => {
                (t - e).abs() <= DELTA
                    && reference.contains(o + (t - DELTA) * d)
                        != reference.contains(o + (t + DELTA) * d)
            }
            _ => false,
        };
        if ok {
            return;
        }
        // Two leaves crossing the ray within 2δ near a disputed point?
        let disputed: Vec<f64> = got.into_iter().chain(expected).collect();
        let near: Vec<(f64, usize)> = reference
            .crossings(o, d)
            .into_iter()
            .filter(|c| disputed.iter().any(|t| (c.0 - t).abs() <= 2.0 * DELTA))
            .collect();
        let coincident = near.iter().enumerate().any(|(i, a)| {
            near[i + 1..]
                .iter()
                .any(|b| a.1 != b.1 && (a.0 - b.0).abs() <= 2.0 * DELTA)
        });
        if coincident {
            self.coincident += 1;
            return;
        }
        // The stretch where the two answers disagree about membership: between
        // the two boundaries, or, where one side sees none, up to the other
        // side's next boundary.
        let (from, to) = match (got, expected) {
            (Some(t), Some(e)) => (t.min(e), t.max(e)),
            (None, Some(e)) => (e, reference.first_boundary(o, d, e).unwrap_or(e + 1.0)),
            (Some(t), None) => (t, next(t).unwrap_or(t + 1.0)),
            (None, None) => unreachable!(),
        };
        let in_band = (0..=8)
            .all(|k| near_boundary(reference, o + (from + (to - from) * k as f64 / 8.0) * d));
        if in_band {
            self.in_band += 1;
            return;
        }
        let at = |t: Option<f64>| t.map(|t| (o + t * d).to_array());
        self.real.push(format!(
            "ray o={:?} d={:?} tmin={tmin}: strata t={got:?} at {:?}, reference t={expected:?} at {:?}",
            o.to_array(),
            d.to_array(),
            at(got),
            at(expected)
        ));
    }

    fn summary(&self, name: &str) -> String {
        format!(
            "{name}: {} rays, {} hits; disagreements: {} real, {} at coincident surfaces (two leaves within 2e-4 along the ray), {} elsewhere within the 1e-4 band (grazing)",
            self.rays,
            self.hits,
            self.real.len(),
            self.coincident,
            self.in_band
        )
    }
}

/// strata's first boundary along `o + t d` after `t`.
fn next_boundary(s: &Scene, o: Vec3, d: Vec3) -> impl Fn(f64) -> Option<f64> + '_ {
    move |t| {
        let ray = Ray {
            tmin: t as f32,
            ..Ray::new(o, d)
        };
        s.geometry.intersect(&ray).map(|h| h.t as f64)
    }
}

/// Random rays from inside and around the solid (half of them aimed at a
/// point inside its neighbourhood), judged against the reference.
fn random_rays(node: &Node, rays: usize, seed: u32) -> Tally {
    let s = csg_scene(node, "");
    let reference = Reference::new(node);
    let mut rng = seeded(seed.into());
    let mut tally = Tally::default();
    let point = |rng: &mut StreamRng, r: f32| {
        Vec3::new(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r))
    };
    for i in 0..rays {
        let o = point(&mut rng, 3.0);
        let d = if i % 2 == 0 {
            rng.unit_vector()
        } else {
            (point(&mut rng, 1.5) - o).normalize()
        };
        let ray = Ray::new(o, d);
        tally.judge(
            &reference,
            o,
            d,
            0.0,
            s.geometry.intersect(&ray).map(|h| h.t),
            next_boundary(&s, o, d),
        );
    }
    tally
}

fn configurations() -> Vec<(&'static str, Node)> {
    vec![
        ("union of two spheres", two_spheres(Op::Union)),
        ("intersection of two spheres", two_spheres(Op::Intersection)),
        ("difference of two spheres", two_spheres(Op::Difference)),
        ("die: (cube mesh ∩ sphere) − (sphere ∪ sphere)", die()),
        ("cylinder drilled by a cylinder", drilled()),
        ("three levels nested, transforms at each", nested()),
    ]
}

#[test]
fn every_operator_and_operand_agrees_with_point_membership_on_20k_rays() {
    for (i, (name, node)) in configurations().into_iter().enumerate() {
        let tally = random_rays(&node, 20_000, 1000 + i as u32);
        println!("{}", tally.summary(name));
        assert!(
            tally.hits > 1000,
            "{name}: the rays exercise the solid ({} hits)",
            tally.hits
        );
        assert!(
            tally.real.is_empty(),
            "{}\n{}",
            tally.summary(name),
            tally.real[..tally.real.len().min(10)].join("\n")
        );
    }
}

/// The stability count: 1M random rays per configuration.
/// Run with `cargo test --release --test suite csg:: -- --ignored --nocapture`.
#[test]
#[ignore]
fn stability_over_a_million_rays_per_configuration() {
    let mut total_real = 0;
    for (i, (name, node)) in configurations().into_iter().enumerate() {
        let tally = random_rays(&node, 1_000_000, 7000 + i as u32);
        println!("{}", tally.summary(name));
        for r in tally.real.iter().take(10) {
            println!("    {r}");
        }
        total_real += tally.real.len();
    }
    assert_eq!(total_real, 0);
}

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

/// Rays spawned from CSG hits, as the integrator spawns them (refracted
/// through the surface, and random directions on either side), must see
/// the reference's first boundary: never their own surface again at t ≈ 0.
fn spawned_rays(node: &Node, seed: u32, paths: usize) -> Tally {
    let s = csg_scene(node, "");
    let reference = Reference::new(node);
    let mut rng = seeded(seed.into());
    let mut tally = Tally::default();
    for _ in 0..paths {
        let target = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let mut ray = Ray::new(target + 4.0 * rng.unit_vector(), Vec3::ZERO);
        ray.direction = (target - ray.origin).normalize();
        let Some(mut hit) = s.geometry.intersect(&ray) else {
            continue;
        };
        for bounce in 0..6 {
            let surf = s.geometry.surface(&ray, &hit);
            let n = surf.geometric_normal;
            let wo = -ray.direction;
            let dir = match bounce % 3 {
                // Refraction, entering or leaving (glass of index 1.5).
                0 => {
                    let (nf, eta) = if n.dot(wo) > 0.0 {
                        (n, 1.0 / 1.5)
                    } else {
                        (-n, 1.5)
                    };
                    refract(wo, nf, eta).unwrap_or(2.0 * nf.dot(wo) * nf - wo)
                }
                // Onwards through the surface, or back the way it came.
                k => {
                    let d = rng.unit_vector();
                    let through = (k == 1) == (d.dot(n) * ray.direction.dot(n) > 0.0);
                    if through {
                        d
                    } else {
                        -d
                    }
                }
            };
            let next = Ray::new(spawn_origin(surf.p, surf.p_error, n, dir), dir);
            let got = s.geometry.intersect(&next);
            tally.judge(
                &reference,
                next.origin,
                next.direction,
                0.0,
                got.map(|h| h.t),
                next_boundary(&s, next.origin, next.direction),
            );
            match got {
                Some(h) => (ray, hit) = (next, h),
                None => break,
            }
        }
    }
    tally
}

#[test]
fn rays_spawned_from_csg_hits_never_rehit_their_own_surface() {
    let lens = op(
        Op::Intersection,
        sphere([0.0, 0.0, -0.9], 1.2),
        sphere([0.0, 0.0, 0.9], 1.2),
    );
    for (name, node) in [
        ("lens", lens),
        ("die", die()),
        ("drilled cylinder", drilled()),
        ("nested", nested()),
    ] {
        let tally = spawned_rays(&node, 17, 3000);
        println!("spawned, {}", tally.summary(name));
        assert!(tally.rays > 1500, "{name}: {} spawned rays", tally.rays);
        assert!(
            tally.real.is_empty(),
            "{}\n{}",
            tally.summary(name),
            tally.real[..tally.real.len().min(10)].join("\n")
        );
    }
}

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

/// Render `scene_text` (plus files) with the real binary; expect exit code 2
/// and one line naming every string in `must_mention`.
fn assert_rejected(name: &str, scene_text: &str, files: &[(&str, &str)], must_mention: &[&str]) {
    let dir = crate::common::temp_dir(&format!("csg-bad-{name}"));
    std::fs::write(dir.join("scene.toml"), scene_text).unwrap();
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    let out = dir.join("out.png");
    let output = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args([
            "render",
            dir.join("scene.toml").to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{name}: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{name}: {stderr}");
    for m in must_mention {
        assert!(stderr.contains(m), "{name}: '{m}' missing from: {stderr}");
    }
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).ok();
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
        &csg(sphere, "{ mesh = \"open.obj\" }"),
        &[("open.obj", &open_box)],
        &[
            "objects[1].csg.b.mesh",
            "open.obj",
            "not a closed mesh",
            "1 triangle(s)",
        ],
    );
    assert_rejected(
        "uncapped",
        &csg(
            "{ cylinder = { radius = 1.0, height = 1.0, caps = false } }",
            sphere,
        ),
        &[],
        &["objects[1].csg.a.cylinder.caps", "uncapped"],
    );
    assert_rejected(
        "plane",
        &csg(sphere, "{ plane = { normal = [0.0, 1.0, 0.0] } }"),
        &[],
        &["objects[1].csg.b.plane"],
    );
    assert_rejected(
        "triangle",
        &csg(
            sphere,
            "{ triangle = { v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] } }",
        ),
        &[],
        &["objects[1].csg.b.triangle"],
    );
    assert_rejected(
        "empty-group",
        &csg(sphere, "{ group = [] }"),
        &[],
        &["objects[1].csg.b.group"],
    );
    // Deep inside nesting, the plain objects' validation reports the full path.
    let nested = format!(
        "{{ csg = {{ op = \"union\", a = {sphere}, b = {{ sphere = {{ radius = -1.0 }} }} }} }}"
    );
    assert_rejected(
        "nested-radius",
        &csg(sphere, &nested),
        &[],
        &["objects[1].csg.b.csg.b.sphere.radius"],
    );
    let nested = format!("{{ group = [{sphere}, {{ sphere = {{ radius = nan }} }}] }}");
    assert_rejected(
        "group-nan",
        &csg(&nested, sphere),
        &[],
        &["objects[1].csg.a.group[1].sphere.radius"],
    );
    assert_rejected(
        "material",
        &csg("{ sphere = { radius = 1.0 }, material = \"nope\" }", sphere),
        &[],
        &["objects[1].csg.a.material", "nope"],
    );
    assert_rejected(
        "no-shape",
        &csg(sphere, "{ material = \"x\" }"),
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
