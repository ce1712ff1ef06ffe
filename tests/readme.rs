//! The README is what a new user reads first: it stays short, and the scene
//! it asks them to type in is a valid scene that renders something lit.

mod common;

use std::path::Path;

fn readme() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap()
}

#[test]
fn the_readme_fits_in_a_sitting() {
    let lines = readme().lines().count();
    assert!(lines <= 300, "README.md has {lines} lines");
}

#[test]
fn the_first_scene_in_the_readme_loads_and_renders_a_lit_image() {
    let text = readme();
    let section = text
        .split("## Your first scene")
        .nth(1)
        .expect("a 'Your first scene' section");
    let block = section
        .split("```toml\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .expect("a toml block in 'Your first scene'");
    // The README says to save it in the repository's root, so its mesh path
    // resolves from there.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let small = block
        .replace("width = 640", "width = 32")
        .replace("height = 480", "height = 24")
        .replace("spp = 16 ", "spp = 1 ");
    let scene = common::scene_at(&small, &root.join("first.toml"));
    let rgb = common::render_rgb(&scene, 2);
    let lit = rgb.iter().filter(|p| p.max_element() > 0.01).count();
    assert!(
        lit > rgb.len() / 4,
        "only {lit} of {} pixels lit",
        rgb.len()
    );
}
