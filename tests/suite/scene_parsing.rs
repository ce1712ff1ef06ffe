//! The scene format as it is read, and its errors in the user's words
//! (issue 48): type errors say what was expected and what was found (in
//! the file and through `--set`, on one line with exit code 2), one number
//! is a grey wherever a colour is read, and unknown keys and values
//! suggest the valid one they are a typo of.

use crate::common::scenes::LIT_SPHERE;
use crate::common::{stderr, strata};
use std::path::Path;
use strata::scene::parse::parse_description;

/// The one-line error strata gives for scene `text`.
fn error(text: &str) -> String {
    parse_description(Path::new("scene.toml"), text)
        .expect_err(text)
        .to_string()
}

#[test]
fn type_errors_say_what_was_expected_and_what_was_found() {
    for (text, message) in [
        (
            "[render]\nspp = \"16\"\n",
            "scene.toml: line 2: render.spp: expected a whole number, found the string \"16\" (write it without the quotes)",
        ),
        (
            "[render]\nspp = \"many\"\n",
            "render.spp: expected a whole number, found the string \"many\"",
        ),
        (
            "[camera]\nfov = \"wide\"\n",
            "camera.fov: expected a number, found the string \"wide\"",
        ),
        (
            "[render]\nspp = -1\n",
            "render.spp: expected a whole number of 0 or more, found -1",
        ),
        (
            "[render]\nseed = 1.5\n",
            "render.seed: expected a whole number, found 1.5",
        ),
        (
            "[render]\nwidth = 99999999999\n",
            "render.width: expected a whole number of at most 4294967295, found 99999999999",
        ),
        (
            "[materials.m]\nfresnel = 1\n",
            "materials.m.fresnel: expected true or false, found 1",
        ),
        (
            "[materials.m]\ndiffuse = [0.5, 0.5]\n",
            "line 2: materials.m.diffuse: expected three numbers [r, g, b] or one, found an array of 2",
        ),
        (
            "[render]\nbackground = \"black\"\n",
            "render.background: expected three numbers [r, g, b] or one, found the string \"black\"",
        ),
        (
            "[camera]\nposition = [0.0, 1.0]\n",
            "camera.position: expected three numbers [x, y, z], found an array of 2",
        ),
        (
            "[[objects]]\nsphere = { radius = 1.0 }\ntransform = { scale = \"big\" }\n",
            "objects[0].transform.scale: expected three numbers [x, y, z] or one, found the string \"big\"",
        ),
        (
            "[[objects]]\nsphere = { center = [0.0, 0.0, 0.0] }\n",
            "objects[0].sphere: missing key 'radius'",
        ),
    ] {
        let e = error(text);
        assert!(e.contains(message), "{text:?}: {e}");
        for rust in ["invalid type", "invalid value", "u32", "f32", "`"] {
            assert!(!e.contains(rust), "{text:?}: '{rust}' in {e}");
        }
    }
}

#[test]
fn set_values_get_the_same_words_on_one_line_with_exit_code_2() {
    let dir = crate::common::temp_dir("words-set");
    std::fs::write(dir.join("scene.toml"), LIT_SPHERE).unwrap();
    for (set, message) in [
        (
            "render.spp=\"16\"",
            "error: <command line>: --set render.spp: expected a whole number, found the string \"16\"",
        ),
        (
            "render.spp=1.5",
            "--set render.spp: expected a whole number, found 1.5",
        ),
        (
            "render.shadow_sample=2",
            "--set render.shadow_sample: unknown key 'shadow_sample'; did you mean 'shadow_samples'?",
        ),
    ] {
        let o = strata(&dir, &["render", "scene.toml", "-q", "-o", "x.png", "--set", set]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{set}: {e}");
        assert_eq!(e.trim_end().lines().count(), 1, "{set}: {e}");
        assert!(e.contains(message), "{set}: {e}");
        assert!(!dir.join("x.png").exists());
    }
}

#[test]
fn one_number_is_a_grey_wherever_a_colour_is_read() {
    let colours = |grey: &dyn Fn(f32) -> String| {
        format!(
            r#"[render]
width = 8
height = 6
background = {}

[materials.m]
diffuse = {}
specular = {}
shininess = 20.0
emission = {}

[[lights]]
type = "point"
position = [0.0, 4.0, 0.0]
intensity = {}

[[lights]]
type = "directional"
direction = [0.0, -1.0, 0.0]
irradiance = {}

[[lights]]
type = "sphere"
center = [2.0, 3.0, 0.0]
radius = 0.5
radiance = {}

[[objects]]
sphere = {{ radius = 1.0 }}
material = "m"
"#,
            grey(0.25),
            grey(0.5),
            grey(0.125),
            grey(0.0625),
            grey(10.0),
            grey(2.0),
            grey(3.0)
        )
    };
    let one = crate::common::scene(&colours(&|x| format!("{x:?}")));
    let three = crate::common::scene(&colours(&|x| format!("[{x:?}, {x:?}, {x:?}]")));
    assert_eq!(one.materials, three.materials);
    assert_eq!(one.lights, three.lights);
    assert_eq!(one.settings, three.settings);
    assert_eq!(one.settings.background, glam::Vec3::splat(0.25));
    assert!(one
        .materials
        .iter()
        .any(|m| m.diffuse == glam::Vec3::splat(0.5)));
    // A whole number is a grey too, and a colour stays checked after.
    let whole = crate::common::scene(
        "[materials.m]\ndiffuse = 1\n[[objects]]\nsphere = { radius = 1.0 }\nmaterial = \"m\"\n",
    );
    assert!(whole.materials.iter().any(|m| m.diffuse == glam::Vec3::ONE));
    let e = error("[materials.m]\ndiffuse = [1.0, 1.0, 1.0, 1.0]\n");
    assert!(
        e.contains("expected three numbers [r, g, b] or one, found an array of 4"),
        "{e}"
    );

    // The command line's --background takes one number as well.
    let dir = crate::common::temp_dir("words-grey");
    std::fs::write(dir.join("scene.toml"), LIT_SPHERE).unwrap();
    let o = strata(
        &dir,
        &[
            "render",
            "scene.toml",
            "-q",
            "-o",
            "x.png",
            "--background",
            "0.5",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

#[test]
fn unknown_keys_and_values_suggest_the_nearest_valid_one() {
    for (text, message) in [
        (
            "[render]\nshadow_sample = 2\n",
            "line 2: render.shadow_sample: unknown key 'shadow_sample'; did you mean 'shadow_samples'?",
        ),
        (
            "[render]\nssp = 4\n",
            "render.ssp: unknown key 'ssp'; did you mean 'spp'?",
        ),
        (
            "[[objects]]\nsphre = { radius = 1.0 }\n",
            "objects[0].sphre: unknown key 'sphre'; did you mean 'sphere'?",
        ),
        (
            "[render]\nsampler = \"stratifed\"\n",
            "render.sampler: unknown sampler 'stratifed'; did you mean 'stratified'?",
        ),
        (
            "[camera]\ntype = \"thin-lens\"\n",
            "camera.type: unknown camera type 'thin-lens'; did you mean 'thin_lens'?",
        ),
        (
            "[[lights]]\ntype = \"pont\"\n",
            "lights[0].type: unknown light type 'pont'; did you mean 'point'?",
        ),
        (
            "[[objects]]\ncsg = { op = \"unon\", a = { sphere = { radius = 1.0 } }, b = { sphere = { radius = 1.0 } } }\n",
            "unknown CSG operation 'unon'; did you mean 'union'?",
        ),
    ] {
        let e = error(text);
        assert!(e.contains(message), "{text:?}: {e}");
    }
    // Nothing close: the valid keys and values, and no guess.
    let e = error("[render]\ncolour = 1\n");
    assert!(
        e.contains(
            "render.colour: unknown key 'colour' (expected width, height, spp, shadow_samples,"
        ),
        "{e}"
    );
    assert!(
        e.ends_with("noise, exposure, tonemap or integrator)"),
        "{e}"
    );
    let e = error("[render]\nsampler = \"halton\"\n");
    assert!(
        e.contains("unknown sampler 'halton' (expected random, stratified or sobol)"),
        "{e}"
    );
    assert!(!e.contains("did you mean"), "{e}");
}
