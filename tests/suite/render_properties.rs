//! Renders checked by properties, never by image hashes.

use crate::common::{render_rgb, scene};
use glam::Vec3;

const EMITTER: &str = "[materials.glow]\ndiffuse = [0.0, 0.0, 0.0]\nemission = [1.0, 1.0, 1.0]\n";

fn covered(pixels: &[Vec3]) -> f64 {
    // Pixel value = covered fraction (emission 1 on black): a sum of coverage, not a thresholded count.
    pixels.iter().map(|p| p.x as f64).sum()
}

#[test]
fn sphere_silhouette_matches_the_analytic_projected_area() {
    // Perspective: a sphere of radius r at distance d on the view axis projects to a
    // disk of radius r/√(d²−r²) on the image plane at distance 1.
    let (r, d, fov, h) = (1.0f64, 6.0f64, 40.0f64, 400u32);
    let text = format!(
        "{EMITTER}[render]\nwidth = {h}\nheight = {h}\nspp = 16\n[camera]\nposition = [0.0, 0.0, {d}]\nlook_at = [0.0, 0.0, 0.0]\nfov = {fov}\n[[objects]]\nsphere = {{ radius = {r} }}\nmaterial = \"glow\"\n"
    );
    let s = scene(&text);
    let rho = r / (d * d - r * r).sqrt();
    let px_per_unit = h as f64 / (2.0 * (fov.to_radians() / 2.0).tan());
    let expected = std::f64::consts::PI * (rho * px_per_unit).powi(2);
    let got = covered(&render_rgb(&s, 0));
    assert!(
        (got - expected).abs() / expected < 0.01,
        "covered {got:.1} px, analytic {expected:.1} px"
    );
}

#[test]
fn orthographic_camera_shows_no_perspective_shrink() {
    let render_at = |z: f32| {
        let text = format!(
            "{EMITTER}[render]\nwidth = 200\nheight = 200\nspp = 16\n[camera]\ntype = \"orthographic\"\nposition = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\nheight = 4.0\n[[objects]]\nsphere = {{ center = [0.0, 0.0, {z}], radius = 1.0 }}\nmaterial = \"glow\"\n"
        );
        covered(&render_rgb(&scene(&text), 0))
    };
    let near = render_at(5.0);
    let far = render_at(-20.0);
    // Radius 1 in a 4-unit-high view of 200 px: 50 px radius.
    let expected = std::f64::consts::PI * 50.0 * 50.0;
    assert!(
        (near - expected).abs() / expected < 0.01,
        "{near} vs {expected}"
    );
    assert!(
        (near - far).abs() / expected < 0.002,
        "near {near} far {far}"
    );
}

#[test]
fn the_mirror_shows_the_object_it_faces() {
    // Camera looks at a mirror wall; a red emitter sits behind the camera.
    let base = "[render]\nwidth = 32\nheight = 32\n[camera]\nposition = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\nfov = 20.0\n\
        [materials.red]\ndiffuse = [0.0, 0.0, 0.0]\nemission = [1.0, 0.0, 0.0]\n\
        [[objects]]\nsphere = { center = [0.0, 0.0, 4.0], radius = 2.0 }\nmaterial = \"red\"\n\
        [[objects]]\nplane = { point = [0.0, 0.0, -5.0], normal = [0.0, 0.0, 1.0] }\nmaterial = \"wall\"\n";
    let mirror = format!("{base}[materials.wall]\ndiffuse = [0.0, 0.0, 0.0]\nreflectivity = 1.0\n");
    let matte = format!("{base}[materials.wall]\ndiffuse = [0.0, 0.0, 0.0]\n");
    let centre = 16 * 32 + 16;
    let m = render_rgb(&scene(&mirror), 0)[centre];
    assert!(
        m.x > 0.99 && m.y == 0.0 && m.z == 0.0,
        "mirror shows red: {m}"
    );
    let w = render_rgb(&scene(&matte), 0)[centre];
    assert_eq!(w, Vec3::ZERO, "a matte black wall shows nothing");
}

#[test]
fn a_glass_sphere_inverts_the_background() {
    // Emissive wall: red above y = 0, green below. A glass ball in front flips them.
    let text = "[render]\nwidth = 101\nheight = 101\nmax_depth = 8\n\
        [camera]\nposition = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 20.0\n\
        [materials.red]\ndiffuse = [0.0, 0.0, 0.0]\nemission = [1.0, 0.0, 0.0]\n\
        [materials.green]\ndiffuse = [0.0, 0.0, 0.0]\nemission = [0.0, 1.0, 0.0]\n\
        [materials.glass]\ndiffuse = [0.0, 0.0, 0.0]\ntransparency = 1.0\nior = 1.5\n\
        [[objects]]\ntriangle = { v = [[-50.0, 0.0, -10.0], [50.0, 0.0, -10.0], [0.0, 50.0, -10.0]] }\nmaterial = \"red\"\n\
        [[objects]]\ntriangle = { v = [[-50.0, 0.0, -10.0], [0.0, -50.0, -10.0], [50.0, 0.0, -10.0]] }\nmaterial = \"green\"\n\
        [[objects]]\nsphere = { radius = 1.0 }\nmaterial = \"glass\"\n";
    let img = render_rgb(&scene(text), 0);
    let at = |x: usize, y: usize| img[y * 101 + x];
    // Outside the ball (its image radius is about 28 px): upright.
    assert!(
        at(50, 5).x > 0.9 && at(50, 95).y > 0.9,
        "outside: red above, green below"
    );
    // Inside the ball's image: inverted.
    let above = at(50, 40);
    let below = at(50, 60);
    assert!(
        above.y > 0.5 && above.x < 0.1,
        "inside, above centre sees green: {above}"
    );
    assert!(
        below.x > 0.5 && below.y < 0.1,
        "inside, below centre sees red: {below}"
    );
}

#[test]
fn thin_lens_with_zero_aperture_is_exactly_the_pinhole() {
    let body = "[render]\nwidth = 64\nheight = 48\nspp = 4\n[[lights]]\ntype = \"point\"\nposition = [2.0, 5.0, 3.0]\nintensity = [20.0, 20.0, 20.0]\n\
        [[objects]]\nsphere = { center = [0.0, 0.5, 0.0], radius = 0.5 }\n[[objects]]\nplane = { normal = [0.0, 1.0, 0.0] }\n";
    let pinhole = scene(&format!(
        "{body}[camera]\ntype = \"perspective\"\nposition = [0.0, 1.0, 5.0]\nlook_at = [0.0, 0.5, 0.0]\n"
    ));
    let lens = scene(&format!(
        "{body}[camera]\ntype = \"thin_lens\"\naperture = 0.0\nfocus_distance = 3.0\nposition = [0.0, 1.0, 5.0]\nlook_at = [0.0, 0.5, 0.0]\n"
    ));
    assert_eq!(render_rgb(&pinhole, 0), render_rgb(&lens, 0));
}

#[test]
fn the_image_is_bit_identical_for_any_thread_count() {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/seed.toml")).unwrap();
    let mut s = scene(&text);
    s.settings.width = 96;
    s.settings.height = 72;
    s.settings.spp = 3;
    let one = render_rgb(&s, 1);
    for threads in [2, 3, 8] {
        assert_eq!(one, render_rgb(&s, threads), "{threads} threads");
    }
}

#[test]
fn point_light_irradiance_follows_the_inverse_square_law() {
    // A white Lambertian floor under a point light: L = ρ/π · I cosθ / r².
    let text = "[render]\nwidth = 1\nheight = 1\n[camera]\ntype = \"orthographic\"\nposition = [0.0, 5.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nheight = 0.0001\n\
        [materials.white]\ndiffuse = [0.5, 0.5, 0.5]\n[[lights]]\ntype = \"point\"\nposition = [0.0, 2.0, 0.0]\nintensity = [8.0, 8.0, 8.0]\n\
        [[objects]]\nplane = { normal = [0.0, 1.0, 0.0] }\nmaterial = \"white\"\n";
    let l = render_rgb(&scene(text), 0)[0];
    let expected = 0.5 / std::f32::consts::PI * 8.0 / 4.0;
    assert!(
        (l.x - expected).abs() / expected < 1e-4,
        "{} vs {expected}",
        l.x
    );
}

/// A cube (a mesh) on a plane seen in perspective, every length scaled
/// by `s`, lit as `light` says: `"point"` (its intensity scaled by s², so
/// that each pixel's radiance is the same at every scale), or a rect light
/// sampled by `light` (`"area"`, `"solid_angle"`) under the path
/// integrator.
fn scaled_cube(dir: &std::path::Path, s: f64, light: &str) -> String {
    let corners: Vec<String> = (0..8)
        .map(|k| {
            let c = |bit: u32| if k & bit != 0 { s } else { -s };
            format!("v {:e} {:e} {:e}\n", c(1), c(2), c(4))
        })
        .collect();
    let faces = "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
    std::fs::write(dir.join("cube.obj"), corners.concat() + faces).unwrap();
    let v = |x: f64, y: f64, z: f64| format!("[{:e}, {:e}, {:e}]", x * s, y * s, z * s);
    let (lit, how) = match light {
        "point" => (
            format!(
                "[[lights]]\ntype = \"point\"\nposition = {}\nintensity = {:e}\n",
                v(5.0, 4.0, 6.0),
                50.0 * s * s
            ),
            String::new(),
        ),
        sampling => (
            format!(
                "[[lights]]\ntype = \"rect\"\ncorner = {}\nedge_u = {}\nedge_v = {}\nradiance = 5.0\n",
                v(4.0, 5.0, 4.0),
                v(2.0, 0.0, 0.0),
                v(0.0, 0.0, 2.0)
            ),
            format!("integrator = \"path\"\nlight_sampling = \"{sampling}\"\n"),
        ),
    };
    format!(
        "[render]\nwidth = 48\nheight = 36\nspp = 2\n{how}{lit}\
         [camera]\nposition = {}\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\n\
         [[objects]]\nmesh = \"cube.obj\"\n\
         [[objects]]\nplane = {{ point = {}, normal = [0.0, 1.0, 0.0] }}\n",
        v(3.0, 2.0, 4.0),
        v(0.0, -1.0, 0.0)
    )
}

/// A scene renders the same at every scale float32's ray tests reach:
/// scaled by powers of two (exact in float32) from 2⁻⁴³ to 2³⁹, the image
/// is the unscaled one bit for bit, under a point light and under a rect
/// light sampled by area and by solid angle. Past 1e12 the scene is
/// refused, its triangle named: there the watertight test's products
/// overflow and the cube rendered black. (Before the lengths were brought
/// near 1 for them, face normals turned to +z past 4e9 and below 1e-10,
/// and a rect light's area and spherical rectangle, fourth powers of its
/// size, overflowed or underflowed: it lit nothing or part of the image.)
#[test]
fn a_scene_renders_the_same_at_every_scale_float32_reaches() {
    use crate::common::{scene_at, temp_dir};
    let dir = temp_dir("scales");
    for light in ["point", "area", "solid_angle"] {
        let image = |s: f64| {
            let text = scaled_cube(&dir, s, light);
            render_rgb(&scene_at(&text, &dir.join("cube.toml")), 1)
        };
        let unscaled = image(1.0);
        assert!(
            unscaled.iter().any(|p| p.x > 0.0),
            "{light}: the cube is lit"
        );
        for k in [-43, -37, -30, 30, 33, 39] {
            assert!(image(2f64.powi(k)) == unscaled, "{light}: scaled by 2^{k}");
        }
    }
    let far = scaled_cube(&dir, 2e12, "point");
    let cube = std::fs::read(dir.join("cube.obj")).unwrap();
    // Placed once, its triangles are the scene's; placed twice, they are
    // a prototype's, whose tree is built apart: named alike, at the first
    // placement. (The OBJ names no object, so no mesh name follows the
    // file.)
    let twice =
        format!("{far}[[objects]]\nmesh = \"cube.obj\"\ntransform = {{ translate = [0, 1, 0] }}\n");
    for (name, scene) in [("past-reach", &far), ("past-reach-placed-twice", &twice)] {
        crate::common::process::assert_rejected(
            name,
            Some(scene),
            &[("cube.obj", &cube)],
            // The object's key and line, and the mesh file, named.
            &["line 14: objects[0].mesh: cube.obj: triangle 0 lies 2.000e12 from the origin, past the 1e12"],
        );
    }
}
