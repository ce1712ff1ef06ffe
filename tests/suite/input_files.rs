//! Input files through the binary as a user meets them: a file
//! is told by its name and first bytes before any parser sees it (OFF and
//! STL are read; FBX and other formats are named), and a scene file's
//! mistakes are all reported in one run, in file order, one line each.

use super::common::{stderr, strata, temp_dir};

const OFF_CUBE: &str = "OFF\n# a unit cube, six quads\n8 6 12\n\
    0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n\
    4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 2 3 7 6\n4 1 2 6 5\n4 0 4 7 3\n";

/// `strata render FILE` in `dir`, small and quiet: its exit code and
/// standard error.
fn render(dir: &std::path::Path, file: &str) -> (Option<i32>, String) {
    let out = strata(
        dir,
        &[
            "render", file, "--width", "16", "--height", "12", "--quiet", "-o", "out.png",
        ],
    );
    (out.status.code(), stderr(&out))
}

/// The OFF cube written to `dir` as `model` renders as a model, and a
/// scene file `scene` that names it renders too.
fn the_cube_renders_as_a_model_and_as_a_scenes_mesh(
    dir: &std::path::Path,
    model: &str,
    scene: &str,
) {
    std::fs::write(dir.join(model), OFF_CUBE).unwrap();
    let (code, err) = render(dir, model);
    assert_eq!(code, Some(0), "{model}: {err}");
    assert!(dir.join("out.png").exists());
    std::fs::remove_file(dir.join("out.png")).unwrap();
    let text = format!(
        "[[lights]]\ntype = \"point\"\nposition = [2, 3, 4]\nintensity = 20\n\
         [[objects]]\nmesh = \"{model}\"\n"
    );
    std::fs::write(dir.join(scene), text).unwrap();
    let (code, err) = render(dir, scene);
    assert_eq!(code, Some(0), "{scene}: {err}");
    assert!(dir.join("out.png").exists());
}

#[test]
fn an_off_model_renders_as_a_model_and_as_a_scenes_mesh() {
    let dir = temp_dir("first-contact-off");
    the_cube_renders_as_a_model_and_as_a_scenes_mesh(&dir, "cube.off", "s.toml");
}

#[test]
fn an_stl_model_renders() {
    let dir = temp_dir("first-contact-stl");
    let stl = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
               vertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
    std::fs::write(dir.join("t.stl"), stl).unwrap();
    let (code, err) = render(&dir, "t.stl");
    assert_eq!(code, Some(0), "{err}");
}

/// A model file named without an extension renders as the model its first
/// bytes say it is (assimp reads such files too); a scene file without one
/// still renders as a scene.
#[test]
fn a_file_without_an_extension_renders_as_what_it_holds() {
    let dir = temp_dir("first-contact-bare");
    the_cube_renders_as_a_model_and_as_a_scenes_mesh(&dir, "cube", "scene");
}

/// Files strata does not read, or that hold something other than their
/// name says, are one line that says what they are, exit 2; never a TOML
/// or UTF-8 parser's complaint.
#[test]
fn files_are_told_by_name_and_first_bytes_before_any_parser() {
    let dir = temp_dir("first-contact-kinds");
    let fbx = b"Kaydara FBX Binary  \x00\x1a\x00\xe8\x1c\x00\x00";
    let cases: [(&str, &[u8], &str); 6] = [
        (
            "box.fbx",
            fbx,
            "box.fbx: strata does not read FBX files (.fbx); strata reads scene files (.toml) and meshes (.obj, .gltf, .glb, .ply, .off, .stl)",
        ),
        (
            "binary.toml",
            fbx,
            "binary.toml: holds an FBX file, not a scene file (told by its first bytes)",
        ),
        (
            "mesh.toml",
            OFF_CUBE.as_bytes(),
            "mesh.toml: holds an OFF mesh, not a scene file (told by its first bytes); name it .off to read it as one",
        ),
        (
            "box.obj",
            b"glTF\x02\x00\x00\x00\x0c\x00\x00\x00",
            "box.obj: holds a binary glTF file, not an OBJ mesh (told by its first bytes); name it .glb to read it as one",
        ),
        (
            "latin1.toml",
            b"[render]\nspp = 4\n# caf\xe9\n",
            "latin1.toml: line 3: not UTF-8 text",
        ),
        (
            "points.xyz",
            b"0 0 0\n1 0 0\n",
            "points.xyz: does not look like a scene file",
        ),
    ];
    for (name, bytes, said) in cases {
        std::fs::write(dir.join(name), bytes).unwrap();
        let (code, err) = render(&dir, name);
        assert_eq!(code, Some(2), "{name}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.starts_with(&format!("error: {said}")), "{err}");
        assert!(
            !err.contains("key with no value") && !err.contains("valid UTF-8"),
            "{err}"
        );
    }
    // A scene naming such a mesh hears the same, at its line.
    std::fs::write(dir.join("s.toml"), "\n[[objects]]\nmesh = \"box.fbx\"\n").unwrap();
    let (code, err) = render(&dir, "s.toml");
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("s.toml: line 3: objects[0].mesh: cannot load FBX files ('.fbx') as a mesh"),
        "{err}"
    );
}

/// Mistakes on lines 5, 8 and 10 (one found while compiling, one while
/// reading, one while compiling again) are three lines of one run, in file
/// order; before, each run said one, and line 8's first.
#[test]
fn a_scenes_mistakes_are_all_reported_in_file_order() {
    let dir = temp_dir("first-contact-mistakes");
    let scene = "# three mistakes\n[camera]\nposition = [0, 1, 6]\n[render]\nspp = 0\n\n\
                 [[lights]]\ntype = \"pont\"\n[[objects]]\nsphere = { radius = -1 }\n\
                 [[objects]]\nsphere = { radius = 1 }\n";
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let (code, err) = render(&dir, "s.toml");
    assert_eq!(code, Some(2), "{err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 3, "{err}");
    for (line, (number, key)) in lines.iter().zip([
        (5, "render.spp"),
        (8, "lights[0].type"),
        (10, "objects[0].sphere.radius"),
    ]) {
        let start = format!("error: s.toml: line {number}: {key}: ");
        assert!(line.starts_with(&start), "{line}\nshould start {start}");
    }
    assert!(lines[1].contains("did you mean 'point'?"), "{err}");
    assert!(
        !dir.join("out.png").exists(),
        "no image from a refused scene"
    );

    // Fixed, it renders: the mistakes were the only thing wrong.
    let fixed = scene
        .replace("spp = 0", "spp = 1")
        .replace(
            "\"pont\"",
            "\"point\"\nposition = [0, 4, 0]\nintensity = 10",
        )
        .replace("radius = -1", "radius = 0.5");
    std::fs::write(dir.join("s.toml"), fixed).unwrap();
    let (code, err) = render(&dir, "s.toml");
    assert_eq!(code, Some(0), "{err}");
}

/// The same through the library: one `InputError` holding them all, each
/// with its line.
#[test]
fn the_library_gives_every_mistake_with_its_line() {
    let text = "[[objects]]\nsphere = { radius = -1 }\n\
                [[objects]]\nplane = { normal = [0, 0, 0] }\n[materials.m]\ndiffuse = \"red\"\n";
    let e =
        strata::scene::scene_from_str(text, std::path::Path::new("t.toml"), &Default::default())
            .unwrap_err();
    let lines: Vec<Option<usize>> = e.clone().into_each().iter().map(|e| e.line).collect();
    assert_eq!(lines, [Some(2), Some(4), Some(6)], "{e}");
}

/// A mesh traced on its own (`strata trace MESH`, `Mesh.load` in Python)
/// is compiled as a made-up scene of one object; its errors name the file
/// alone, never that scene's `objects[0].mesh`, which the user never wrote.
#[test]
fn a_mesh_file_s_errors_name_no_key_of_a_made_up_scene() {
    let dir = temp_dir("first-contact-mesh-key");
    std::fs::write(dir.join("notes.md"), "# not a mesh\n").unwrap();
    for file in ["missing.obj", "notes.md"] {
        let out = strata(
            &dir,
            &[
                "trace", file, "--rays", "r.bin", "--hits", "h.bin", "--quiet",
            ],
        );
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.starts_with(&format!("error: {file}: ")), "{err}");
        assert!(!err.contains("objects["), "{err}");
    }
}
