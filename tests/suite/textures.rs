//! Diffuse textures end to end: mesh files with textures rendered under a
//! head-on directional light, where a diffuse surface's radiance is known
//! exactly: L = ρ/π · E with ρ = Kd × texture (Lambert).

use crate::common::meshes::base64;
use crate::common::process::strata_ok;
use glam::Vec3;
use std::path::Path;

/// The sRGB decoding curve (IEC 61966-2-1), computed here on its own so the
/// renderer's table is checked against it.
fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f64 / 255.0;
    let linear = if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    };
    linear as f32
}

fn linear(texel: [u8; 3]) -> Vec3 {
    Vec3::from(texel.map(srgb_to_linear))
}

fn write_png(path: &Path, width: u32, height: u32, texels: &[[u8; 3]]) {
    image::RgbImage::from_raw(width, height, texels.concat())
        .unwrap()
        .save(path)
        .unwrap();
}

/// An 8 × 4 image of the plane z = 0 seen head on: x from 0 to 2, y from 0
/// to 1 (pixel column i covers x ∈ [i/4, (i+1)/4], row j covers y from
/// 1 − j/4 down), lit along −z with irradiance E = π, so that a diffuse
/// surface facing +z has radiance exactly ρ.
fn head_on_scene(mesh: &str, kd: Option<&str>) -> String {
    let material = kd.map_or(String::new(), |m| format!("material = \"{m}\"\n"));
    format!(
        r#"
[render]
width = 8
height = 4
spp = 4

[camera]
type = "orthographic"
position = [1.0, 0.5, 5.0]
look_at = [1.0, 0.5, 0.0]
height = 1.0

[[lights]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = [{pi}, {pi}, {pi}]

[[objects]]
mesh = "{mesh}"
{material}"#,
        pi = std::f32::consts::PI
    )
}

/// A quad over x ∈ [−1, 3], y ∈ [−1, 2], larger than the view, with
/// u = x/2 and OBJ's v = y (up), textured by `map_Kd`.
fn write_quad_obj(dir: &Path, kd: [f32; 3], map_kd: &str) {
    std::fs::write(
        dir.join("quad.mtl"),
        format!(
            "newmtl tex\nKd {} {} {}\nmap_Kd {map_kd}\n",
            kd[0], kd[1], kd[2]
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("quad.obj"),
        "mtllib quad.mtl\nv -1 -1 0\nv 3 -1 0\nv 3 2 0\nv -1 2 0\n\
         vt -0.5 -1\nvt 1.5 -1\nvt 1.5 2\nvt -0.5 2\nusemtl tex\nf 1/1 2/2 3/3 4/4\n",
    )
    .unwrap();
}

#[test]
fn a_textured_obj_quad_shows_each_half_of_its_texture_at_the_lambert_radiance() {
    let dir = crate::common::temp_dir("texture-render");
    // A 2 × 1 texture: orange on the left, blue on the right. With the
    // texture clamped, u = x/2 < 1/4 (columns 0 and 1) sees only the left
    // texel and u > 3/4 (columns 6 and 7) only the right one; between,
    // bilinear filtering blends them.
    let (left, right) = ([255, 128, 0], [0, 64, 255]);
    write_png(&dir.join("two.png"), 2, 1, &[left, right]);
    let kd = [0.5, 0.8, 1.0];
    write_quad_obj(&dir, kd, "-clamp on two.png");
    let scene = crate::common::scene_at(&head_on_scene("quad.obj", None), &dir.join("s.toml"));
    let rgb = crate::common::render_rgb(&scene, 2);

    // sRGB 128 is 0.2158 in linear units.
    assert!((srgb_to_linear(128) - 0.21586).abs() < 1e-4);
    let kd = Vec3::from(kd);
    let (want_left, want_right) = (linear(left) * kd, linear(right) * kd);
    for row in 0..4 {
        let pixel = |column: usize| rgb[row * 8 + column];
        for column in [0, 1] {
            let got = pixel(column);
            assert!(
                got.abs_diff_eq(want_left, 1e-4),
                "({column}, {row}): {got} != {want_left}"
            );
        }
        for column in [6, 7] {
            let got = pixel(column);
            assert!(
                got.abs_diff_eq(want_right, 1e-4),
                "({column}, {row}): {got} != {want_right}"
            );
        }
        // The middle blends: more red left of centre, more blue right of it.
        assert!(pixel(3).x > pixel(4).x && pixel(3).z < pixel(4).z);
        for column in 2..6 {
            let p = pixel(column);
            assert!(p.cmpge(want_left.min(want_right) - 1e-4).all(), "{p}");
            assert!(p.cmple(want_left.max(want_right) + 1e-4).all(), "{p}");
        }
    }

    // The albedo AOV is the textured albedo too, the same ρ in every pixel
    // since E = π makes the radiance equal to it.
    std::fs::write(dir.join("s.toml"), head_on_scene("quad.obj", None)).unwrap();
    strata_ok(
        &dir,
        &["render", "s.toml", "-q", "--aov", "albedo", "-o", "a.exr"],
    );
    let albedo = read_albedo(&dir.join("a.exr"));
    for (i, (a, c)) in albedo.iter().zip(&rgb).enumerate() {
        assert!(
            a.abs_diff_eq(*c, 1e-4),
            "pixel {i}: albedo {a} vs radiance {c}"
        );
    }

    // A scene material on the same mesh replaces the textured one.
    let text = format!(
        "[materials.grey]\ndiffuse = [0.5, 0.5, 0.5]\n{}",
        head_on_scene("quad.obj", Some("grey"))
    );
    let plain = crate::common::render_rgb(&crate::common::scene_at(&text, &dir.join("s.toml")), 2);
    assert!(plain.iter().all(|p| p.abs_diff_eq(Vec3::splat(0.5), 1e-5)));
    std::fs::remove_dir_all(&dir).ok();
}

/// The `albedo.R/G/B` channels of an EXR written with `--aov albedo`.
fn read_albedo(path: &Path) -> Vec<Vec3> {
    let exr = crate::common::exr::read_exr(path);
    let (r, g, b) = (
        exr.channel("albedo.R"),
        exr.channel("albedo.G"),
        exr.channel("albedo.B"),
    );
    (0..r.len()).map(|i| Vec3::new(r[i], g[i], b[i])).collect()
}

/// The quad of [`write_quad_obj`] as glTF: the same positions and
/// triangles, its UVs written directly in glTF's space (v = 1 − y, down
/// from the image's top row), and the texture clamped on both axes.
fn write_quad_gltf(dir: &Path, kd: [f32; 3], image: &str) {
    let positions: [[f32; 3]; 4] = [[-1., -1., 0.], [3., -1., 0.], [3., 2., 0.], [-1., 2., 0.]];
    let mut bin: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let uvs = positions.map(|p| [p[0] / 2.0, 1.0 - p[1]]);
    bin.extend(uvs.iter().flatten().flat_map(|v| v.to_le_bytes()));
    bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},
  "buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{data}"}}],
  "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":32}},
                 {{"buffer":0,"byteOffset":80,"byteLength":12}}],
  "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}},
               {{"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"}},
               {{"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}}],
  "materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[{r},{g},{b},1],"metallicFactor":0,
                 "baseColorTexture":{{"index":0}}}}}}],
  "textures":[{{"source":0,"sampler":0}}],
  "samplers":[{{"wrapS":33071,"wrapT":33071}}],
  "images":[{{"uri":"{image}"}}],
  "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,"material":0}}]}}],
  "nodes":[{{"mesh":0}}]}}"#,
        len = bin.len(),
        data = base64(&bin),
        r = kd[0],
        g = kd[1],
        b = kd[2],
    );
    std::fs::write(dir.join("quad.gltf"), json).unwrap();
}

#[test]
fn obj_and_gltf_quads_with_one_texture_render_alike_and_the_right_way_up() {
    let dir = crate::common::temp_dir("texture-gltf");
    // 2 × 2 texels, row by row from the top of the picture.
    let texels = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]];
    write_png(&dir.join("four.png"), 2, 2, &texels);
    let kd = [0.9, 0.7, 0.5];
    write_quad_obj(&dir, kd, "-clamp on four.png");
    write_quad_gltf(&dir, kd, "four.png");
    let render = |mesh: &str| {
        let scene = crate::common::scene_at(&head_on_scene(mesh, None), &dir.join("s.toml"));
        crate::common::render_rgb(&scene, 2)
    };
    let (obj, gltf) = (render("quad.obj"), render("quad.gltf"));
    // glTF's dielectric adds a grey highlight, k_s = 0.04 with exponent 1
    // (roughness 1): seen and lit head on, (n+2)/(2π) k_s E = 3/(2π) · 0.04 · π.
    let highlight = Vec3::splat(0.06);
    for (i, (o, g)) in obj.iter().zip(&gltf).enumerate() {
        assert!(
            (*g - highlight).abs_diff_eq(*o, 1e-5),
            "pixel {i}: glTF {g}, OBJ {o}"
        );
    }

    // The image's top-left texel shows at the view's top left, and so on:
    // corner pixels see a single texel (u and v within 1/4 of the edges).
    let kd = Vec3::from(kd);
    let corners = [(0, 0, 0), (7, 0, 1), (0, 3, 2), (7, 3, 3)];
    for (column, row, texel) in corners {
        let want = linear(texels[texel]) * kd;
        let got = obj[row * 8 + column];
        assert!(
            got.abs_diff_eq(want, 1e-4),
            "({column}, {row}): {got} != {want}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
