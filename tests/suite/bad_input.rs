//! Bad input through the real binary: one line naming the file and the key
//! or line, exit code 2, no panic, and no output file left behind.

use crate::common::process::{assert_rejected, strata};

#[test]
fn malformed_toml_names_the_line() {
    assert_rejected(
        "syntax",
        Some("[render]\nwidth = 10\n[camera\n"),
        &[],
        &["scene.toml", "line 3"],
    );
}

#[test]
fn unknown_keys_name_the_key_and_line() {
    assert_rejected(
        "unknown",
        Some("[render]\nwidth = 10\nwdth = 3\n"),
        &[],
        &["scene.toml", "line 3", "wdth"],
    );
    assert_rejected(
        "unknown-obj",
        Some("[[objects]]\nsphere = { radius = 1.0, centre = [0.0, 0.0, 0.0] }\n"),
        &[],
        &["centre"],
    );
}

#[test]
fn nan_infinite_and_negative_numbers_name_the_key() {
    assert_rejected(
        "nan",
        Some("[[objects]]\nsphere = { radius = nan }\n"),
        &[],
        &["objects[0].sphere.radius"],
    );
    assert_rejected(
        "inf",
        Some("[[objects]]\nsphere = { center = [inf, 0.0, 0.0], radius = 1.0 }\n"),
        &[],
        &["objects[0].sphere.center"],
    );
    assert_rejected(
        "neg",
        Some("[[objects]]\ncylinder = { radius = -1.0, height = 1.0 }\n"),
        &[],
        &["objects[0].cylinder.radius"],
    );
    assert_rejected(
        "neg-light",
        Some("[[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [-1.0, 1.0, 1.0]\n"),
        &[],
        &["lights[0].intensity"],
    );
}

#[test]
fn zero_length_normals_and_axes_are_rejected() {
    assert_rejected(
        "normal",
        Some("[[objects]]\nplane = { normal = [0.0, 0.0, 0.0] }\n"),
        &[],
        &["objects[0].plane.normal"],
    );
    assert_rejected(
        "axis",
        Some("[[objects]]\ncylinder = { axis = [0.0, 0.0, 0.0], radius = 1.0, height = 1.0 }\n"),
        &[],
        &["objects[0].cylinder.axis"],
    );
    assert_rejected(
        "scale",
        Some("[[objects]]\nsphere = { radius = 1.0 }\ntransform = { scale = [1.0, 0.0, 1.0] }\n"),
        &[],
        &["objects[0].transform.scale"],
    );
}

#[test]
fn a_camera_up_parallel_to_the_view_is_rejected() {
    let text =
        "[camera]\nposition = [0.0, 5.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\n";
    assert_rejected("up", Some(text), &[], &["camera.up"]);
}

/// Two facing perfect mirrors: every camera ray bounces to `max_depth`.
const MIRRORS: &str = "[render]\nwidth = 4\nheight = 3\nmax_depth = DEPTH\n\
[camera]\nposition = [0, 0, 0]\nlook_at = [0, 0, -1]\n\
[materials.m]\ndiffuse = 0\nreflectivity = 1.0\n\
[[lights]]\ntype = \"point\"\nposition = [0, 0.5, 0]\nintensity = 1\n\
[[objects]]\nplane = { point = [0, 0, -1], normal = [0, 0, 1] }\nmaterial = \"m\"\n\
[[objects]]\nplane = { point = [0, 0, 1], normal = [0, 0, -1] }\nmaterial = \"m\"\n";

/// The distribution integrator recurses once a bounce: a depth past the
/// limit is refused (it overflowed a worker's stack and aborted the
/// process at 1,500), and the limit itself renders, on the workers'
/// stacks and on the main thread's (`--debug-sample`).
#[test]
fn a_depth_past_the_limit_is_refused_and_the_limit_renders() {
    assert_rejected(
        "depth",
        Some(&MIRRORS.replace("DEPTH", "257")),
        &[],
        &["scene.toml", "line 4", "render.max_depth", "at most 256"],
    );
    let dir = crate::common::temp_dir("depth-limit");
    std::fs::write(dir.join("m.toml"), MIRRORS.replace("DEPTH", "5")).unwrap();
    let flag = strata(&dir, &["render", "m.toml", "-q", "--max-depth", "1500"]);
    let err = String::from_utf8_lossy(&flag.stderr);
    assert_eq!(flag.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--max-depth 1500: at most 256 bounces"),
        "{err}"
    );
    for extra in [
        &["--threads", "1"][..],
        &["--threads", "2"],
        &["--debug-sample", "1,1,0"],
    ] {
        let mut args = vec![
            "render",
            "m.toml",
            "-q",
            "-o",
            "m.png",
            "--max-depth",
            "256",
        ];
        args.extend(extra);
        let out = strata(&dir, &args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{extra:?}: {err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Every mistake of one table is named in one run, in the file's order
/// (the checks stopped at the first key of the struct's order).
#[test]
fn every_mistake_of_a_material_is_named_in_file_order() {
    let dir = crate::common::temp_dir("material-mistakes");
    for (text, keys) in [
        (
            "[materials.a]\nior = 0\nshininess = -1\nglossiness = inf\ntransparency = -0.5\n",
            &["ior", "shininess", "glossiness", "transparency"][..],
        ),
        (
            "[materials.a]\nroughness = 2\nmetallic = -1\n",
            &["roughness", "metallic"],
        ),
    ] {
        std::fs::write(dir.join("m.toml"), text).unwrap();
        let out = strata(&dir, &["render", "m.toml", "-q", "-o", "m.png"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        let lines: Vec<&str> = err.trim_end().lines().collect();
        assert_eq!(lines.len(), keys.len(), "{err}");
        for (i, (line, key)) in lines.iter().zip(keys).enumerate() {
            let at = format!("m.toml: line {}: materials.a.{key}: ", i + 2);
            assert!(line.contains(&at), "{line}");
        }
        assert!(!dir.join("m.png").exists());
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn missing_files_are_named() {
    assert_rejected("no-scene", None, &[], &["scene.toml", "cannot read"]);
    assert_rejected(
        "no-mesh",
        Some("[[objects]]\nsphere = { radius = 1.0 }\n\n[[objects]]\nmesh = \"gone.obj\"\n"),
        &[],
        &[
            "scene.toml: line 5: objects[1].mesh: cannot read",
            "gone.obj",
        ],
    );
}

#[test]
fn errors_in_lights_name_their_own_line_and_key() {
    let scene = r#"[render]
width = 8
height = 6

[[lights]]
type = "point"
position = [0.0, 4.0, 0.0]
intensity = [1.0, 1.0, 1.0]

[[lights]]
type = "rect"
corner = [0.0, 3.0, 0.0]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.0]
radiance = [1.0, 1.0]
"#;
    assert_rejected(
        "light-line",
        Some(scene),
        &[],
        &["scene.toml: line 15: lights[1].radiance: expected three numbers [r, g, b] or one, found an array of 2"],
    );
    assert_rejected(
        "light-key",
        Some(&scene.replace(
            "radiance = [1.0, 1.0]",
            "radiance = [1.0, 1.0, 1.0]\nintensity = [1.0, 1.0, 1.0]",
        )),
        &[],
        &["line 16: lights[1].intensity: does not apply to a rect light"],
    );
}

#[test]
fn malformed_obj_and_gltf_name_the_file_and_line_or_location() {
    let scene = "[[objects]]\nmesh = \"bad.obj\"\n";
    assert_rejected(
        "obj",
        Some(scene),
        &[("bad.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")],
        &["bad.obj", "line 4"],
    );
    assert_rejected(
        "obj-nan",
        Some(scene),
        &[("bad.obj", b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n")],
        &["bad.obj", "line 2"],
    );
    let scene = "[[objects]]\nmesh = \"bad.gltf\"\n";
    assert_rejected(
        "gltf",
        Some(scene),
        &[(
            "bad.gltf",
            b"{ \"asset\": { \"version\": \"2.0\" }, \"meshes\": [",
        )],
        &["bad.gltf"],
    );
    let scene = "[[objects]]\nmesh = \"bad.glb\"\n";
    assert_rejected(
        "glb",
        Some(scene),
        &[("bad.glb", b"glTF\x02\x00\x00\x00\x05\x00\x00\x00")],
        &["bad.glb"],
    );
}

#[test]
fn a_missing_or_broken_texture_names_the_file_and_the_mtl_line_or_gltf_image() {
    let scene = "[[objects]]\nmesh = \"quad.obj\"\n";
    let obj: &[u8] =
        b"mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nusemtl wood\nf 1/1 2/1 3/1\n";
    assert_rejected(
        "map_Kd-missing",
        Some(scene),
        &[
            ("quad.obj", obj),
            (
                "quad.mtl",
                b"newmtl wood\nKd 1 1 1\nmap_Kd wood grain.png\n",
            ),
        ],
        &[
            "quad.mtl",
            "line 3",
            "wood grain.png",
            "No such file or directory",
        ],
    );
    assert_rejected(
        "map_Kd-not-an-image",
        Some(scene),
        &[
            ("quad.obj", obj),
            ("quad.mtl", b"newmtl wood\n\nmap_Kd -clamp on notes.jpg\n"),
            ("notes.jpg", b"shopping list"),
        ],
        &[
            "quad.mtl",
            "line 3",
            "notes.jpg",
            "a text file, not an image",
        ],
    );
    let gltf = br#"{"asset":{"version":"2.0"},"materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
        "textures":[{"source":1}],"images":[{"uri":"a.png"},{"uri":"gone.png"}]}"#;
    assert_rejected(
        "gltf-image-missing",
        Some("[[objects]]\nmesh = \"t.gltf\"\n"),
        &[("t.gltf", gltf)],
        &["t.gltf", "images[1]", "gone.png", "textures[0]"],
    );
}

#[test]
fn unknown_materials_and_shapeless_objects_are_rejected() {
    assert_rejected(
        "mat",
        Some("[[objects]]\nsphere = { radius = 1.0 }\nmaterial = \"nope\"\n"),
        &[],
        &[
            "objects[0].material",
            "nope",
            "the scene has no [materials] tables",
        ],
    );
    // A near miss of a [materials] table's name is suggested, else the names.
    let scene = "[materials.floor]\ndiffuse = 0.5\n[materials.jade]\ndiffuse = 0.3\n\
                 [[objects]]\nsphere = { radius = 1.0 }\nmaterial = \"NAME\"\n";
    assert_rejected(
        "mat-near",
        Some(&scene.replace("NAME", "flor")),
        &[],
        &["unknown material 'flor'; did you mean 'floor'?"],
    );
    assert_rejected(
        "mat-far",
        Some(&scene.replace("NAME", "A")),
        &[],
        &["unknown material 'A' (expected floor or jade)"],
    );
    assert_rejected(
        "shapeless",
        Some("[[objects]]\nmaterial = \"x\"\n"),
        &[],
        &["objects[0]"],
    );
    assert_rejected(
        "two",
        Some("[[objects]]\nsphere = { radius = 1.0 }\nplane = { normal = [0.0, 1.0, 0.0] }\n"),
        &[],
        &["objects[0]"],
    );
}

#[test]
fn a_bad_output_extension_writes_nothing() {
    let dir = crate::common::temp_dir("bad-ext");
    std::fs::write(dir.join("s.toml"), "").unwrap();
    let output = strata(
        &dir,
        &[
            "render",
            dir.join("s.toml").to_str().unwrap(),
            "-o",
            dir.join("out.jpg").to_str().unwrap(),
        ],
    );
    assert_eq!(output.status.code(), Some(2));
    assert!(!dir.join("out.jpg").exists());
}
