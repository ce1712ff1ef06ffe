//! Degenerate geometry: none of it crashes; each case renders (with no NaN
//! or infinite sample) or fails with a clear error.

use crate::common::{scene_at, temp_dir};
use std::path::Path;
use strata::render::{render, RenderOptions};

/// Render a scene file's text (meshes resolved in `dir`) and return the film's invalid-sample count.
fn render_invalid(text: &str, dir: &Path) -> u64 {
    let scene = scene_at(text, &dir.join("scene.toml"));
    let outcome = render(&scene, &RenderOptions::default(), None, ());
    outcome.film.invalid
}

const VIEW: &str = "[render]\nwidth = 48\nheight = 36\nspp = 2\n[[lights]]\ntype = \"point\"\nposition = [1.0, 3.0, 2.0]\nintensity = [10.0, 10.0, 10.0]\n[[lights]]\ntype = \"rect\"\ncorner = [-0.5, 2.5, -0.5]\nedge_u = [1.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 1.0]\nradiance = [3.0, 3.0, 3.0]\n";

#[test]
fn zero_area_sliver_and_duplicate_vertex_triangles_render_cleanly() {
    let dir = temp_dir("degenerate-mesh");
    std::fs::write(
        dir.join("bad.obj"),
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 0 1 0\nv 1e-9 1 0\nv 0.5 0.5 0\n\
         f 1 2 3\nf 1 4 5\nf 1 4 6\nf 1 2 4\nf 4 4 4\nf 1 2 7\n",
    )
    .unwrap();
    let text = format!("{VIEW}[[objects]]\nmesh = \"bad.obj\"\n");
    assert_eq!(render_invalid(&text, &dir), 0);
}

#[test]
fn one_triangle_meshes_empty_meshes_and_empty_scenes_render() {
    let dir = temp_dir("degenerate-small");
    std::fs::write(dir.join("one.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(dir.join("empty.obj"), "# nothing here\n").unwrap();
    assert_eq!(
        render_invalid(&format!("{VIEW}[[objects]]\nmesh = \"one.obj\"\n"), &dir),
        0
    );
    assert_eq!(
        render_invalid(&format!("{VIEW}[[objects]]\nmesh = \"empty.obj\"\n"), &dir),
        0
    );
    assert_eq!(render_invalid(VIEW, &dir), 0);
    assert_eq!(
        render_invalid("", &dir),
        0,
        "an empty file is a valid, empty scene"
    );
}

#[test]
fn a_camera_inside_an_object_and_a_light_inside_a_closed_mesh() {
    let dir = temp_dir("degenerate-inside");
    let mesh = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/meshes/icosphere.obj");
    // The camera sits inside a sphere: it sees the inside, lit by a light also inside.
    let inside = "[render]\nwidth = 32\nheight = 24\n[camera]\nposition = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\n\
        [[lights]]\ntype = \"point\"\nposition = [0.0, 0.5, 0.0]\nintensity = [1.0, 1.0, 1.0]\n\
        [[objects]]\nsphere = { radius = 2.0 }\n";
    let scene = scene_at(inside, &dir.join("s.toml"));
    let film = render(&scene, &RenderOptions::default(), None, ()).film;
    assert_eq!(film.invalid, 0);
    assert!(
        film.to_rgb().iter().all(|p| p.x > 0.0),
        "every pixel sees the lit inside wall"
    );
    // A light enclosed by a closed mesh leaves the floor outside dark.
    let enclosed = format!(
        "[render]\nwidth = 32\nheight = 24\n[camera]\nposition = [0.0, 2.0, 6.0]\nlook_at = [0.0, 0.0, 0.0]\n\
         [[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [50.0, 50.0, 50.0]\n\
         [[objects]]\nmesh = \"{mesh}\"\ntransform = {{ translate = [0.0, 1.0, 0.0] }}\n\
         [[objects]]\nplane = {{ normal = [0.0, 1.0, 0.0] }}\n"
    );
    let scene = scene_at(&enclosed, &dir.join("s.toml"));
    let film = render(&scene, &RenderOptions::default(), None, ()).film;
    assert_eq!(film.invalid, 0);
    assert!(
        film.to_rgb().iter().all(|p| p.x == 0.0),
        "no light escapes a closed mesh"
    );
}

#[test]
fn coordinates_near_1e30_render_without_nan_or_panic() {
    let dir = temp_dir("degenerate-huge");
    let text = "[render]\nwidth = 24\nheight = 16\n[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
        [[lights]]\ntype = \"point\"\nposition = [1e30, 1e30, 1e30]\nintensity = [1e30, 1e30, 1e30]\n\
        [[objects]]\nsphere = { center = [0.0, 0.0, -1e30], radius = 1e29 }\n\
        [[objects]]\nsphere = { radius = 0.5 }\n";
    assert_eq!(render_invalid(text, &dir), 0);
    // A triangle that far is past float32's ray tests (scene::compile::REACH):
    // refused, named, rather than rendered wrong.
    let with_triangle = format!(
        "{text}[[objects]]\ntriangle = {{ v = [[-1e30, -1e30, -1e29], [1e30, -1e30, -1e29], [0.0, 1e30, -1e29]] }}\n"
    );
    let path = dir.join("scene.toml");
    let Err(e) = strata::scene::scene_from_str(&with_triangle, &path, &Default::default()) else {
        panic!("a triangle at 1e30 was not refused");
    };
    assert!(
        e.to_string()
            .contains("objects[2]: triangle 0 lies 1.000e30 from the origin"),
        "{e}"
    );
}

#[test]
fn every_scene_in_scenes_renders_without_nan_or_infinity() {
    let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes"));
    let mut rendered = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        // Small and quick, but with every effect the scene asks for.
        let overrides = strata::scene::RenderOverrides {
            width: Some(48),
            height: Some(36),
            spp: Some(4),
            ..Default::default()
        };
        let (scene, _) = crate::common::load_scene(&path, &overrides, Default::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let film = render(&scene, &RenderOptions::default(), None, ()).film;
        assert_eq!(
            film.invalid,
            0,
            "{}: first bad sample {:?}",
            path.display(),
            film.first_invalid
        );
        rendered += 1;
    }
    assert!(rendered >= 8, "found the scenes ({rendered})");
}
