//! CSG booleans against analytic answers and against an independent f64
//! reference (brute-force point membership, `reference`): each operator,
//! closed meshes, capped cylinders, nesting with transforms, coincident and
//! touching surfaces, rays spawned from CSG hits, materials, bounds and bad
//! operands.
//!
//! | file | tests |
//! |---|---|
//! | `reference.rs` | (no tests) the f64 reference: a CSG tree that writes itself as scene TOML, point membership, the first boundary along a ray |
//! | `agreement.rs` | random rays, and rays spawned from hits, against the reference |
//! | `analytic.rs` | solids with known answers: a lens, a drilled cylinder, a die's pit, empty and touching solids, bounds, group operands |
//! | `scene_file.rs` | CSG as the scene file writes it: operands' materials, bad operands, the example scene |
//!
//! Here: the solids the files share, and scenes of them.

mod agreement;
mod analytic;
mod reference;
mod scene_file;

use crate::common::process::repo;
use crate::common::scene_at;
use reference::{op, sphere, Node, Op, Trs};
use std::path::PathBuf;
use strata::scene::Scene;

fn scenes_dir() -> PathBuf {
    repo().join("scenes")
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
