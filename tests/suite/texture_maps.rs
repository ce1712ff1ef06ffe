//! Texture maps beyond the diffuse one, end to end: normal maps (glTF
//! `normalTexture`, MTL `norm`) and bump maps (MTL `bump`) against the
//! analytic cosine of the normal they give, metallic-roughness and
//! emissive textures against the factors they equal, a textured glowing
//! surface as a light, and hostile maps that must fall back or fail
//! cleanly. Planes face +z, seen head on by an orthographic camera under a
//! directional light of irradiance π, so a white Lambertian surface shows
//! exactly the cosine between its shading normal and the light.

use crate::common::films::pixel_means;
use crate::common::meshes::base64;
use crate::common::scene_at;
use glam::Vec3;
use std::path::Path;
use strata::scene::Scene;

/// Each pixel's mean of `spp` samples, with no sample dropped as NaN.
fn pixels(scene: &Scene, spp: u32) -> Vec<Vec3> {
    pixel_means(scene, scene.settings.seed, spp)
}

fn write_png(path: &Path, width: u32, height: u32, texels: &[[u8; 3]]) {
    image::RgbImage::from_raw(width, height, texels.concat())
        .unwrap()
        .save(path)
        .unwrap();
}

fn png_bytes(width: u32, height: u32, texels: &[[u8; 3]]) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    image::RgbImage::from_raw(width, height, texels.concat())
        .unwrap()
        .write_to(&mut out, image::ImageFormat::Png)
        .unwrap();
    out.into_inner()
}

/// An 8 × 4 head-on view of the plane z = 0 over x ∈ [0, 2], y ∈ [0, 1],
/// lit by a directional light from `to_light` with irradiance π, under
/// `integrator`.
fn head_on(mesh: &str, to_light: Vec3, integrator: &str) -> String {
    let d = -to_light.normalize();
    format!(
        r#"
[render]
width = 8
height = 4
spp = 4
integrator = "{integrator}"
max_depth = 0

[camera]
type = "orthographic"
position = [1.0, 0.5, 5.0]
look_at = [1.0, 0.5, 0.0]
height = 1.0

[[lights]]
type = "directional"
direction = [{}, {}, {}]
irradiance = [{pi}, {pi}, {pi}]

[[objects]]
mesh = "{mesh}"
"#,
        d.x,
        d.y,
        d.z,
        pi = std::f32::consts::PI
    )
}

/// A white quad over x ∈ [−1, 3], y ∈ [−1, 2] (u = x/2, OBJ's v = y) whose
/// material adds `statement` (a map line, or nothing).
fn write_quad_obj(dir: &Path, statement: &str) {
    std::fs::write(
        dir.join("quad.mtl"),
        format!("newmtl m\nKd 1 1 1\n{statement}\n"),
    )
    .unwrap();
    std::fs::write(
        dir.join("quad.obj"),
        "mtllib quad.mtl\nv -1 -1 0\nv 3 -1 0\nv 3 2 0\nv -1 2 0\n\
         vt -0.5 -1\nvt 1.5 -1\nvt 1.5 2\nvt -0.5 2\nusemtl m\nf 1/1 2/2 3/3 4/4\n",
    )
    .unwrap();
}

/// The scene of `toml` read as if from `dir/scene.toml`.
fn scene_in(dir: &Path, toml: &str) -> Scene {
    scene_at(toml, &dir.join("scene.toml"))
}

/// The error reading the scene `toml` in `dir` gives.
fn load_error(dir: &Path, toml: &str) -> String {
    let overrides = strata::scene::RenderOverrides::default();
    match crate::common::checked::scene_from_str(toml, &dir.join("scene.toml"), &overrides) {
        Ok(_) => panic!("no error"),
        Err(e) => e.to_string(),
    }
}

/// What a normal map's texel decodes to: (2c/255 − 1), normalised.
fn decoded(texel: [u8; 3]) -> Vec3 {
    (Vec3::from(texel.map(|c| c as f32)) * (2.0 / 255.0) - Vec3::ONE).normalize()
}

/// A map of flat normals (128, 128, 255) shades as no map: the same
/// radiance within 2e-3 (not bit for bit: 128/255 decodes to 0.0039, not
/// 0, a tilt of 0.3°), under both integrators.
#[test]
fn a_flat_normal_map_renders_as_no_map() {
    let dir = crate::common::temp_dir("flat-normal-map");
    write_png(&dir.join("flat.png"), 2, 2, &[[128, 128, 255]; 4]);
    for integrator in ["distribution", "path"] {
        let toml = head_on("quad.obj", Vec3::new(0.3, 0.2, 1.0), integrator);
        write_quad_obj(&dir, "");
        let plain = pixels(&scene_in(&dir, &toml), 4);
        write_quad_obj(&dir, "norm flat.png");
        let mapped_scene = scene_in(&dir, &toml);
        assert!(mapped_scene
            .materials
            .iter()
            .any(|m| m.maps.normal.is_some()));
        let mapped = pixels(&mapped_scene, 4);
        for (a, b) in plain.iter().zip(&mapped) {
            assert!(
                (*a - *b).abs().max_element() < 2e-3,
                "{integrator}: {a} vs {b}"
            );
        }
        let want = Vec3::new(0.3, 0.2, 1.0).normalize().z;
        assert!((plain[10].x - want).abs() < 1e-4, "{}", plain[10]);
    }
}

/// A constant tilted normal map: the plane shows the cosine between the
/// map's normal (in the frame +x = ∂p/∂u, +y = up the image) and the
/// light, under both integrators; lit from the side the normal leans
/// away from, it shows the smaller cosine, so a flipped axis fails.
#[test]
fn a_constant_tilted_normal_map_shows_the_cosine_of_the_tilted_normal() {
    let dir = crate::common::temp_dir("tilted-normal-map");
    let texel = [189, 173, 230]; // about (0.48, 0.36, 0.8)
    write_png(&dir.join("tilt.png"), 1, 1, &[texel]);
    write_quad_obj(&dir, "norm tilt.png");
    let n = decoded(texel);
    for to_light in [Vec3::new(1.0, 0.0, 1.0), Vec3::new(-0.5, -1.0, 1.0)] {
        let want = n.dot(to_light.normalize());
        for integrator in ["distribution", "path"] {
            let s = scene_in(&dir, &head_on("quad.obj", to_light, integrator));
            for p in pixels(&s, 4) {
                assert!(
                    (p - Vec3::splat(want)).abs().max_element() < 1e-4,
                    "{integrator} {to_light}: {p} vs {want}"
                );
            }
        }
    }
}

/// Blinn's bump mapping of a height ramp h = s·texel/255 rising along x
/// tilts the normal to (−h′(x), 0, 1): a slope of ½ here.
#[test]
fn a_bump_map_of_a_linear_ramp_tilts_the_normal_by_the_analytic_angle() {
    let dir = crate::common::temp_dir("bump-ramp");
    let ramp: Vec<[u8; 3]> = (0..=255u8).map(|i| [i, i, i]).collect();
    write_png(&dir.join("ramp.png"), 256, 1, &ramp);
    // Texel i has its centre at u = (i + ½)/256, so h(u) = s (256u − ½)/255
    // and dh/dx = s · 256/255 / 2 (u = x/2): s = 255/256 gives ½.
    let s = 255.0 / 256.0;
    write_quad_obj(&dir, &format!("bump -bm {s} -clamp on ramp.png"));
    let n = Vec3::new(-0.5, 0.0, 1.0).normalize();
    for to_light in [Vec3::new(-1.0, 0.0, 1.0), Vec3::new(1.0, 0.3, 1.0)] {
        let want = n.dot(to_light.normalize());
        for integrator in ["distribution", "path"] {
            let sc = scene_in(&dir, &head_on("quad.obj", to_light, integrator));
            let image = pixels(&sc, 4);
            // Columns 1..7: away from u = 0 and 1, where the clamped ramp ends.
            for row in 0..4 {
                for col in 1..7 {
                    let p = image[row * 8 + col];
                    assert!(
                        (p - Vec3::splat(want)).abs().max_element() < 1e-3,
                        "{integrator} {to_light} ({col}, {row}): {p} vs {want}"
                    );
                }
            }
        }
    }
}

/// Maps that cannot give a normal fall back to the unmapped one, finite:
/// a map pointing into the surface, and a quad whose texture coordinates
/// are all one point (no tangent frame).
#[test]
fn maps_without_a_usable_normal_fall_back_to_the_surface_normal() {
    let dir = crate::common::temp_dir("bad-normal-map");
    write_png(&dir.join("inward.png"), 1, 1, &[[128, 128, 0]]);
    write_png(&dir.join("tilt.png"), 1, 1, &[[230, 128, 150]]);
    let to_light = Vec3::new(0.5, 0.2, 1.0);
    let want = to_light.normalize().z;
    for integrator in ["distribution", "path"] {
        let toml = head_on("quad.obj", to_light, integrator);
        write_quad_obj(&dir, "norm inward.png");
        for p in pixels(&scene_in(&dir, &toml), 2) {
            assert!((p.x - want).abs() < 1e-4, "{integrator} inward: {p}");
        }
        std::fs::write(
            dir.join("point.obj"),
            "mtllib quad.mtl\nv -1 -1 0\nv 3 -1 0\nv 3 2 0\nv -1 2 0\n\
             vt 0.5 0.5\nusemtl m\nf 1/1 2/1 3/1 4/1\n",
        )
        .unwrap();
        write_quad_obj(&dir, "norm tilt.png");
        let toml = head_on("point.obj", to_light, integrator);
        for p in pixels(&scene_in(&dir, &toml), 2) {
            assert!((p.x - want).abs() < 1e-4, "{integrator} no frame: {p}");
        }
    }
}

/// A normal map that turns the normal far from the viewer, seen at a
/// grazing angle: the shading normal is bent back towards the viewer,
/// every sample is finite, and the plane is never lit from behind.
#[test]
fn a_normal_map_facing_away_from_the_viewer_is_bent_back_and_stays_finite() {
    let dir = crate::common::temp_dir("bent-normal-map");
    write_png(&dir.join("steep.png"), 1, 1, &[[250, 128, 140]]); // about (0.96, 0, 0.1)
    write_quad_obj(&dir, "norm steep.png");
    for integrator in ["distribution", "path"] {
        let toml = format!(
            r#"
[render]
width = 8
height = 4
spp = 4
integrator = "{integrator}"
max_depth = 3
[camera]
position = [6.0, 0.5, 0.3]
look_at = [1.0, 0.5, 0.0]
fov = 20.0
[[lights]]
type = "directional"
direction = [-0.3, 0.0, -1.0]
irradiance = [3.0, 3.0, 3.0]
[[objects]]
mesh = "quad.obj"
"#
        );
        for p in pixels(&scene_in(&dir, &toml), 4) {
            assert!(p.is_finite() && p.min_element() >= 0.0, "{integrator}: {p}");
        }
    }
}

/// A glTF file of one quad over x ∈ [−1, 3], y ∈ [−1, 2] at z = `z`,
/// facing +z (or −z when `down`), u = x/2 and v falling from 1 to −1 as y rises (glTF's
/// v runs down the image), its material `material` (JSON), with `extra` top-level
/// keys (textures, images).
fn quad_gltf(z: f32, down: bool, material: &str, extra: &str) -> String {
    quad_gltf_with(z, down, material, extra, None)
}

/// [`quad_gltf`] with the same `TANGENT` at every corner, if given.
fn quad_gltf_with(
    z: f32,
    down: bool,
    material: &str,
    extra: &str,
    tangent: Option<[f32; 4]>,
) -> String {
    let positions = [
        [-1.0f32, -1.0, z],
        [3.0, -1.0, z],
        [3.0, 2.0, z],
        [-1.0, 2.0, z],
    ];
    let uvs = [[-0.5f32, 1.0], [1.5, 1.0], [1.5, -1.0], [-0.5, -1.0]];
    let indices: [u16; 6] = if down {
        [0, 2, 1, 0, 3, 2]
    } else {
        [0, 1, 2, 0, 2, 3]
    };
    let mut bytes = Vec::new();
    for p in positions {
        bytes.extend(p.iter().flat_map(|c| c.to_le_bytes()));
    }
    for uv in uvs {
        bytes.extend(uv.iter().flat_map(|c| c.to_le_bytes()));
    }
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let (view, accessor, attribute) = match tangent {
        Some(t) => {
            for _ in 0..4 {
                bytes.extend(t.iter().flat_map(|c| c.to_le_bytes()));
            }
            (
                r#",{"buffer":0,"byteOffset":92,"byteLength":64}"#,
                r#",{"bufferView":3,"componentType":5126,"count":4,"type":"VEC4"}"#,
                r#","TANGENT":3"#,
            )
        }
        None => ("", "", ""),
    };
    format!(
        r#"{{"asset":{{"version":"2.0"}},
  "buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{data}"}}],
  "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":32}},
                 {{"buffer":0,"byteOffset":80,"byteLength":12}}{view}],
  "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,-1,{z}],"max":[3,2,{z}]}},
               {{"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"}},
               {{"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}}{accessor}],
  "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1{attribute}}},"indices":2,"material":0}}]}}],
  "nodes":[{{"mesh":0}}],
  "materials":[{material}]{extra}}}"#,
        len = bytes.len(),
        data = base64(&bytes)
    )
}

/// A texture whose image is the PNG `png` in a data: URI.
fn texture_json(png: &[u8]) -> String {
    format!(
        r#","textures":[{{"source":0}}],"images":[{{"uri":"data:image/png;base64,{}"}}]"#,
        base64(png)
    )
}

/// A constant metallic-roughness texture (blue metalness, green
/// roughness, read linearly) equals the factors it scales: a glossy plane
/// under the path integrator's direct light shows the same radiance.
#[test]
fn a_constant_metallic_roughness_texture_equals_the_factors() {
    let dir = crate::common::temp_dir("mr-texture");
    let (g, b) = (128u8, 200u8);
    let png = png_bytes(2, 2, &[[0, g, b]; 4]);
    let textured = quad_gltf(
        0.0,
        false,
        r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.9,0.6,0.3,1],"metallicFactor":1,"roughnessFactor":0.8,
            "metallicRoughnessTexture":{"index":0}}}"#,
        &texture_json(&png),
    );
    let factors = quad_gltf(
        0.0,
        false,
        &format!(
            r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[0.9,0.6,0.3,1],"metallicFactor":{},"roughnessFactor":{}}}}}"#,
            b as f32 / 255.0,
            0.8 * (g as f32 / 255.0)
        ),
        "",
    );
    std::fs::write(dir.join("textured.gltf"), textured).unwrap();
    std::fs::write(dir.join("factors.gltf"), factors).unwrap();
    let to_light = Vec3::new(0.4, 0.3, 1.0);
    let a = pixels(
        &scene_in(&dir, &head_on("textured.gltf", to_light, "path")),
        4,
    );
    let b = pixels(
        &scene_in(&dir, &head_on("factors.gltf", to_light, "path")),
        4,
    );
    for (a, b) in a.iter().zip(&b) {
        assert!(
            (*a - *b).abs().max_element() < 1e-4 * (1.0 + b.max_element()),
            "{a} vs {b}"
        );
    }
    // And the texture is read: metallic 1 and roughness 0.8 look otherwise.
    let untextured = quad_gltf(
        0.0,
        false,
        r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.9,0.6,0.3,1],"metallicFactor":1,"roughnessFactor":0.8}}"#,
        "",
    );
    std::fs::write(dir.join("untextured.gltf"), untextured).unwrap();
    let c = pixels(
        &scene_in(&dir, &head_on("untextured.gltf", to_light, "path")),
        4,
    );
    assert!(
        (c[10] - b[10]).abs().max_element() > 1e-2,
        "{} vs {}",
        c[10],
        b[10]
    );
}

/// A room lit by a glowing quad (facing down at z = 2) over a white
/// floor (z = 0), seen from below the ceiling: the floor's mean radiance.
fn floor_under(dir: &Path, ceiling: &str) -> f32 {
    let toml = format!(
        r#"
[render]
width = 8
height = 4
spp = 64
integrator = "path"
max_depth = 1

[camera]
type = "orthographic"
position = [1.0, 0.5, 1.0]
look_at = [1.0, 0.5, 0.0]
height = 1.0

[materials.white]
diffuse = [0.8, 0.8, 0.8]

[[objects]]
mesh = "floor.obj"
material = "white"

[[objects]]
mesh = "{ceiling}"
"#
    );
    std::fs::write(
        dir.join("floor.obj"),
        "v -1 -1 0\nv 3 -1 0\nv 3 2 0\nv -1 2 0\nf 1 2 3 4\n",
    )
    .unwrap();
    let s = scene_in(dir, &toml);
    assert!(!s.emitters.is_empty(), "the ceiling is a light");
    let image = pixels(&s, 64);
    image.iter().map(|p| p.x).sum::<f32>() / image.len() as f32
}

/// An emissive texture multiplies emissiveFactor, also as a light: a
/// constant texture lights the floor as the factor times its colour
/// does, and a texture half black (its left half white) lights it as a
/// ceiling whose left half alone glows, within noise. The glowing
/// triangles are chosen by power (factor × the texture's mean) and emit
/// the texel at the point drawn, so the estimate stays unbiased.
#[test]
fn an_emissive_texture_multiplies_the_factor_also_as_a_light() {
    let dir = crate::common::temp_dir("emissive-texture");
    let texel = [255u8, 128, 64];
    let srgb = |c: u8| {
        let c = c as f64 / 255.0;
        (if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }) as f32
    };
    let lin = Vec3::from(texel.map(srgb));
    let textured = quad_gltf(
        2.0,
        true,
        r#"{"emissiveFactor":[2,2,2],"emissiveTexture":{"index":0}}"#,
        &texture_json(&png_bytes(1, 1, &[texel])),
    );
    let e = lin * 2.0;
    let factor = quad_gltf(
        2.0,
        true,
        &format!(r#"{{"emissiveFactor":[{},{},{}]}}"#, e.x, e.y, e.z),
        "",
    );
    std::fs::write(dir.join("textured.gltf"), textured).unwrap();
    std::fs::write(dir.join("factor.gltf"), factor).unwrap();
    let a = floor_under(&dir, "textured.gltf");
    let b = floor_under(&dir, "factor.gltf");
    assert!(b > 0.05, "{b}");
    assert!((a - b).abs() < 0.01 * b, "{a} vs {b}");

    // Half black: white for u < ½ (x < 1), black beyond, clamped.
    let mut half = vec![[255u8; 3]; 32];
    half.extend(vec![[0u8; 3]; 32]);
    let clamp = r#","samplers":[{"wrapS":33071,"wrapT":33071}]"#;
    let extra = format!(
        r#","textures":[{{"source":0,"sampler":0}}],"images":[{{"uri":"data:image/png;base64,{}"}}]{clamp}"#,
        base64(&png_bytes(64, 1, &half))
    );
    let half_lit = quad_gltf(
        2.0,
        true,
        r#"{"emissiveFactor":[3,3,3],"emissiveTexture":{"index":0}}"#,
        &extra,
    );
    std::fs::write(dir.join("half.gltf"), half_lit).unwrap();
    // The same ceiling as two quads: x < 1 glowing, x > 1 dark.
    std::fs::write(
        dir.join("halves.obj"),
        "mtllib halves.mtl\nv -1 -1 2\nv 1 -1 2\nv 1 2 2\nv -1 2 2\nv 3 -1 2\nv 3 2 2\n\
         usemtl glow\nf 1 4 3 2\nusemtl dark\nf 2 3 6 5\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("halves.mtl"),
        "newmtl glow\nKd 0 0 0\nKe 3 3 3\nnewmtl dark\nKd 0 0 0\n",
    )
    .unwrap();
    let a = floor_under(&dir, "half.gltf");
    let b = floor_under(&dir, "halves.obj");
    assert!(b > 0.05, "{b}");
    assert!((a - b).abs() < 0.03 * b, "{a} vs {b}");
}

/// Hostile maps: a normal texture index out of range, and a bump map that
/// is no image, are errors naming the file and the key or line.
#[test]
fn broken_maps_are_errors_naming_the_file_and_key() {
    let dir = crate::common::temp_dir("broken-maps");
    std::fs::write(
        dir.join("bad.gltf"),
        quad_gltf(0.0, false, r#"{"normalTexture":{"index":3}}"#, ""),
    )
    .unwrap();
    let toml = head_on("bad.gltf", Vec3::Z, "path");
    let err = load_error(&dir, &toml);
    assert!(
        err.contains("bad.gltf") && err.contains("materials[0].normalTexture"),
        "{err}"
    );
    assert!(err.contains("out of bounds"), "{err}");

    std::fs::write(dir.join("notes.png"), "not an image").unwrap();
    write_quad_obj(&dir, "bump -bm 0.5 notes.png");
    let toml = head_on("quad.obj", Vec3::Z, "distribution");
    let err = load_error(&dir, &toml);
    assert!(err.contains("quad.mtl") && err.contains("line 3"), "{err}");
    assert!(err.contains("not an image"), "{err}");
}

/// glTF's `TANGENT` and the tangent worked out from positions and UVs
/// agree where both are known (u along +x, v down the image along −y:
/// t = +x, w = +1), so a tilted normal map shades alike either way; the
/// attribute is read, as w = −1 (the bitangent turned) and a tangent
/// along +y show; a NaN tangent is an error naming the accessor.
#[test]
fn tangents_from_the_attribute_and_from_uvs_agree() {
    let dir = crate::common::temp_dir("gltf-tangents");
    let texel = [189u8, 173, 230];
    let n = decoded(texel);
    let material = r#"{"pbrMetallicRoughness":{"metallicFactor":0,"roughnessFactor":1},"normalTexture":{"index":0}}"#;
    let extra = texture_json(&png_bytes(1, 1, &[texel]));
    let to_light = Vec3::new(-0.5, -1.0, 1.0);
    let radiance = |tangent: Option<[f32; 4]>| {
        let name = format!(
            "t{}.gltf",
            tangent.map_or(0.0, |t| t[0] * 4.0 + t[1] * 2.0 + t[3])
        );
        std::fs::write(
            dir.join(&name),
            quad_gltf_with(0.0, false, material, &extra, tangent),
        )
        .unwrap();
        let s = scene_in(&dir, &head_on(&name, to_light, "distribution"));
        pixels(&s, 2)
    };
    let from_uvs = radiance(None);
    let from_attribute = radiance(Some([1.0, 0.0, 0.0, 1.0]));
    for (a, b) in from_uvs.iter().zip(&from_attribute) {
        assert!((*a - *b).abs().max_element() < 1e-5, "{a} vs {b}");
    }
    // The Phong stand-in of a rough dielectric: its diffuse part 1 (white)
    // follows the cosine; compare the cosines' order rather than values.
    let l = to_light.normalize();
    let flipped = radiance(Some([1.0, 0.0, 0.0, -1.0]));
    let turned = radiance(Some([0.0, 1.0, 0.0, 1.0]));
    let cos = |m: Vec3| m.dot(l);
    // w = −1: y negated; t = +y (b = n × t = −x): (x, y) → (−y, x).
    let want_flipped = cos(Vec3::new(n.x, -n.y, n.z));
    let want_turned = cos(Vec3::new(-n.y, n.x, n.z));
    let want = cos(n);
    let ratio = |p: Vec3, w: f32| p.x / w;
    let k = ratio(from_uvs[10], want);
    assert!(
        (ratio(flipped[10], want_flipped) - k).abs() < 0.02 * k,
        "{} {}",
        flipped[10],
        from_uvs[10]
    );
    assert!(
        (ratio(turned[10], want_turned) - k).abs() < 0.02 * k,
        "{} {}",
        turned[10],
        from_uvs[10]
    );

    std::fs::write(
        dir.join("nan.gltf"),
        quad_gltf_with(
            0.0,
            false,
            material,
            &extra,
            Some([f32::NAN, 0.0, 0.0, 1.0]),
        ),
    )
    .unwrap();
    let err = load_error(&dir, &head_on("nan.gltf", to_light, "path"));
    assert!(
        err.contains("nan.gltf") && err.contains("accessors[3]"),
        "{err}"
    );
}

/// Maps keep the image the same for any thread count: a normal-mapped,
/// emissive-textured scene under the path integrator, on one thread and
/// on three.
#[test]
fn mapped_scenes_are_bit_identical_across_thread_counts() {
    let dir = crate::common::temp_dir("maps-threads");
    write_png(
        &dir.join("tilt.png"),
        2,
        1,
        &[[189, 173, 230], [100, 140, 240]],
    );
    write_quad_obj(&dir, "norm tilt.png");
    let glow = quad_gltf(
        2.0,
        true,
        r#"{"emissiveFactor":[2,2,2],"emissiveTexture":{"index":0}}"#,
        &texture_json(&png_bytes(2, 1, &[[255, 128, 64], [10, 200, 90]])),
    );
    std::fs::write(dir.join("glow.gltf"), glow).unwrap();
    let toml = head_on("quad.obj", Vec3::new(0.2, 0.1, 1.0), "path")
        .replace("max_depth = 0", "max_depth = 3")
        // The camera under the glowing ceiling, which lights the floor.
        .replace("position = [1.0, 0.5, 5.0]", "position = [1.0, 0.5, 1.0]")
        + "[[objects]]\nmesh = \"glow.gltf\"\n";
    let s = scene_in(&dir, &toml);
    assert!(!s.emitters.is_empty());
    let one = crate::common::render_rgb(&s, 1);
    let three = crate::common::render_rgb(&s, 3);
    assert!(one.iter().any(|p| p.max_element() > 0.0));
    assert_eq!(one, three);
}
