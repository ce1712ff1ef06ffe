//! The layering of docs/ARCHITECTURE.md, checked on the source: every
//! `crate::` path in a module names a module of a lower layer, `output/`
//! imports nothing of the renderer, only the CLI starts processes, no
//! source file passes 800 lines, and the document's table lists every
//! module. Comments are ignored (a doc link is not an import).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Layers from the bottom: a module may import modules of lower layers only.
const LAYERS: &[&[&str]] = &[
    &["error", "math", "mode"],
    &["output", "sampling", "system"],
    &["shape"],
    &["accel"],
    &["geometry"],
    &["camera", "light", "material", "texture"],
    &["scene"],
    &["shade", "raycast"],
    &["render"],
    &["partial"],
    &["experiment", "rays"],
];

const MAX_LINES: usize = 800;

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level module a file of `src/` belongs to (`geometry` for
/// `src/geometry/csg/mesh.rs`, `error` for `src/error.rs`).
fn module_of(file: &Path) -> String {
    let rel = file.strip_prefix(src()).unwrap();
    let first = rel.components().next().unwrap().as_os_str();
    first.to_string_lossy().trim_end_matches(".rs").to_string()
}

/// The code of a file without its `//` comments (string contents stay,
/// which is harmless: no string of ours spells a `crate::` path).
fn code(text: &str) -> String {
    text.lines()
        .map(|line| line.find("//").map_or(line, |i| &line[..i]))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every top-level module a file's code names through `crate::`, including
/// each name in `crate::{a, b::c}`.
fn crate_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        rest = &rest[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for part in group[..end].split(',') {
                let name: String = part
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.push(name);
                }
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            out.push(name);
        }
    }
    out
}

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|layer| layer.contains(&module))
}

/// The top-level modules `src/lib.rs` declares (crate-root items such as
/// `crate::VERSION` belong to no layer and may be used anywhere).
fn modules() -> Vec<String> {
    let lib = std::fs::read_to_string(src().join("lib.rs")).unwrap();
    code(&lib)
        .lines()
        .filter_map(|line| line.trim().strip_prefix("pub mod "))
        .map(|name| name.trim_end_matches(';').to_string())
        .collect()
}

/// For each library module, the modules it imports and the files that do.
fn imports() -> BTreeMap<String, BTreeMap<String, Vec<PathBuf>>> {
    let modules = modules();
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut out: BTreeMap<String, BTreeMap<String, Vec<PathBuf>>> = BTreeMap::new();
    for file in files {
        let module = module_of(&file);
        if module == "main" || module == "lib" || module == "cli" {
            continue;
        }
        let text = std::fs::read_to_string(&file).unwrap();
        for target in crate_paths(&code(&text)) {
            if target != module && modules.contains(&target) {
                out.entry(module.clone())
                    .or_default()
                    .entry(target)
                    .or_default()
                    .push(file.clone());
            }
        }
    }
    out
}

#[test]
fn every_import_points_down_the_layers() {
    let mut wrong = Vec::new();
    for (module, targets) in imports() {
        let from = layer_of(&module)
            .unwrap_or_else(|| panic!("module `{module}` is in no layer of LAYERS"));
        for (target, files) in targets {
            let to = layer_of(&target)
                .unwrap_or_else(|| panic!("`{target}` (named in {files:?}) is in no layer"));
            if to >= from {
                wrong.push(format!(
                    "{module} (layer {from}) imports {target} (layer {to}) in {}",
                    files[0].display()
                ));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "imports that do not point down:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn output_only_writes_and_shapes_know_only_math() {
    let imports = imports();
    let output: Vec<_> = imports.get("output").map_or(vec![], |t| t.keys().collect());
    for renderer in ["render", "shade", "scene", "geometry", "accel"] {
        assert!(
            !output.iter().any(|m| *m == renderer),
            "output imports {renderer}"
        );
    }
    let shape: Vec<_> = imports.get("shape").map_or(vec![], |t| t.keys().collect());
    assert!(
        shape.iter().all(|m| *m == "math"),
        "shape imports {shape:?}"
    );
}

#[test]
fn the_layering_check_sees_imports_of_every_form() {
    let code = code(
        "use crate::accel::Bvh8;\nuse crate::{math::Ray, scene};\n// crate::render in a comment\nlet x = crate::shade::f();",
    );
    assert_eq!(crate_paths(&code), ["accel", "math", "scene", "shade"]);
    assert_eq!(module_of(&src().join("geometry/csg/mesh.rs")), "geometry");
    assert_eq!(module_of(&src().join("error.rs")), "error");
}

#[test]
fn only_the_cli_starts_processes() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    for file in files {
        if module_of(&file) == "cli" {
            continue;
        }
        let code = code(&std::fs::read_to_string(&file).unwrap());
        assert!(
            !code.contains("Command::new"),
            "{} starts a process; that belongs in src/cli/",
            file.display()
        );
    }
}

#[test]
fn no_source_file_passes_800_lines() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    // The Python package's crate too.
    rust_files(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("python/src"),
        &mut files,
    );
    let long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let n = std::fs::read_to_string(f).unwrap().lines().count();
            (n > MAX_LINES).then(|| format!("{} ({n} lines)", f.display()))
        })
        .collect();
    assert!(long.is_empty(), "split these by concern: {long:?}");
}

#[test]
fn the_architecture_document_lists_every_module_and_fits_a_screenful() {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/ARCHITECTURE.md"))
            .unwrap();
    assert!(
        doc.lines().count() <= 150,
        "docs/ARCHITECTURE.md is over 150 lines"
    );
    let lib = std::fs::read_to_string(src().join("lib.rs")).unwrap();
    for line in code(&lib).lines() {
        let Some(name) = line.trim().strip_prefix("pub mod ") else {
            continue;
        };
        let name = name.trim_end_matches(';');
        assert!(
            layer_of(name).is_some(),
            "`{name}` is in no layer of LAYERS"
        );
        let row = format!("| `{name}` |");
        assert!(
            doc.contains(&row),
            "docs/ARCHITECTURE.md has no row for `{name}`"
        );
    }
}
