//! The layering of docs/ARCHITECTURE.md, checked on the source: every
//! path a module names through `crate::` (each name of a nested group) or
//! through a `super::` chain that climbs to the crate root names a module
//! of a lower layer; the document's layer numbers are those of `LAYERS`;
//! `output/` imports nothing of the renderer; only the CLI starts
//! processes; the Python crate (`python/src`) names the library only
//! through its facade; no source file passes 800 lines; and the
//! document's table lists every module. Comments and strings are ignored
//! (a doc link is not an import).

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
/// which is harmless: no string of ours spells `Command::new`, and the
/// paths are read by [`tokens`], which skips comments and strings).
fn code(text: &str) -> String {
    text.lines()
        .map(|line| line.find("//").map_or(line, |i| &line[..i]))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The module path of a file of `src/` below the crate root:
/// `geometry::csg::mesh` for `src/geometry/csg/mesh.rs`, `geometry::csg`
/// for `src/geometry/csg/mod.rs`, nothing for `src/lib.rs`.
fn module_path(file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src()).unwrap().with_extension("");
    let mut path: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().to_string())
        .collect();
    if matches!(
        path.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        path.pop();
    }
    path
}

/// What the path reader needs of Rust's tokens.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    /// `::`
    Sep,
    Open,
    Close,
    Comma,
    Other,
}

/// A file's tokens, without comments (`//`, nested `/* */`), string,
/// raw string and char literals, so that neither a doc link nor a brace
/// in a string is read as code.
fn tokens(text: &str) -> Vec<Tok> {
    let c: Vec<char> = text.chars().collect();
    let at = |i: usize| c.get(i).copied().unwrap_or('\0');
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && at(i + 1) == '/' {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && at(i + 1) == '*' {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if ch == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
        } else if ch == '\'' {
            // A char literal ('{', '\n', '\u{7d}'), or a lifetime ('a).
            if at(i + 1) == '\\' {
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if at(i + 2) == '\'' {
                i += 3;
            } else {
                i += 1;
            }
        } else if ch.is_alphanumeric() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            let word: String = c[start..i].iter().collect();
            let hashes = c[i..].iter().take_while(|&&h| h == '#').count();
            if matches!(word.as_str(), "r" | "br" | "cr") && at(i + hashes) == '"' {
                // A raw string: to the quote followed by as many hashes.
                let closes = |k: usize| c[k] == '"' && (1..=hashes).all(|h| at(k + h) == '#');
                i += hashes + 1;
                while i < c.len() && !closes(i) {
                    i += 1;
                }
                i += hashes + 1;
            } else {
                out.push(Tok::Ident(word));
            }
        } else if ch == ':' && at(i + 1) == ':' {
            out.push(Tok::Sep);
            i += 2;
        } else {
            out.push(match ch {
                '{' => Tok::Open,
                '}' => Tok::Close,
                ',' => Tok::Comma,
                _ => Tok::Other,
            });
            i += 1;
        }
    }
    out
}

/// The paths of the use tree at `toks[i..]`, each in full
/// (`a::{b, c::d}` gives `a::b` and `a::c::d`), and the index after it.
/// A path in an expression ends where its segments do (`f(`, `::<T>`).
fn use_tree(toks: &[Tok], mut i: usize) -> (Vec<Vec<String>>, usize) {
    match toks.get(i) {
        Some(Tok::Open) => {
            let mut out = Vec::new();
            i += 1;
            loop {
                match toks.get(i) {
                    None => break,
                    Some(Tok::Close) => {
                        i += 1;
                        break;
                    }
                    Some(Tok::Comma) => i += 1,
                    Some(_) => {
                        let (paths, next) = use_tree(toks, i);
                        out.extend(paths);
                        i = next.max(i + 1);
                    }
                }
            }
            (out, i)
        }
        Some(Tok::Ident(name)) => {
            if toks.get(i + 1) == Some(&Tok::Sep) {
                let (rest, next) = use_tree(toks, i + 2);
                if !rest.is_empty() {
                    let paths = rest
                        .into_iter()
                        .map(|tail| std::iter::once(name.clone()).chain(tail).collect())
                        .collect();
                    return (paths, next);
                }
            }
            (vec![vec![name.clone()]], i + 1)
        }
        _ => (Vec::new(), i),
    }
}

/// Every path of a file's code that starts at `root` (`crate` in the
/// library, `strata` in the Python crate), in full from the root:
/// `root::{a::{b, c}, d}` gives `a::b`, `a::c` and `d`.
///
/// With the file's `module` path (for the library), `super::` chains are
/// resolved against it and the inline modules (`mod tests { ... }`) they
/// stand in, so `super::super::render::Film` in `src/geometry/csg/mesh.rs`
/// is `render::Film`; a chain that stays inside the module gives a path
/// inside it (`geometry::...`).
fn rooted_paths(text: &str, root: &str, module: Option<&[String]>) -> Vec<Vec<String>> {
    let toks = tokens(text);
    let ident = |i: usize| match toks.get(i) {
        Some(Tok::Ident(w)) => Some(w.as_str()),
        _ => None,
    };
    let mut out = Vec::new();
    // The inline modules around the token, each with the brace depth of
    // its body.
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth: usize = 0;
    let mut i = 0;
    while i < toks.len() {
        let after_sep = i > 0 && toks[i - 1] == Tok::Sep;
        let starts = |w: &str| ident(i) == Some(w) && toks.get(i + 1) == Some(&Tok::Sep);
        if starts(root) && !after_sep {
            let (paths, next) = use_tree(&toks, i + 2);
            out.extend(paths);
            i = next.max(i + 1);
            continue;
        }
        if let Some(module) = module.filter(|_| starts("super") && !after_sep) {
            let mut ups = 0;
            while ident(i) == Some("super") && toks.get(i + 1) == Some(&Tok::Sep) {
                ups += 1;
                i += 2;
            }
            let here: Vec<String> = module
                .iter()
                .cloned()
                .chain(inline.iter().map(|(name, _)| name.clone()))
                .collect();
            let (paths, next) = use_tree(&toks, i);
            if ups <= here.len() {
                let base = &here[..here.len() - ups];
                out.extend(paths.into_iter().map(|p| [base, &p].concat()));
            }
            i = next.max(i);
            continue;
        }
        match &toks[i] {
            Tok::Open => depth += 1,
            Tok::Close => {
                if inline.last().is_some_and(|&(_, d)| d == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
            }
            Tok::Ident(w) if w == "mod" => {
                if let (Some(name), Some(Tok::Open)) = (ident(i + 1), toks.get(i + 2)) {
                    inline.push((name.to_string(), depth + 1));
                }
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// The top-level modules a library file's code names: through `crate::`
/// (each name of a nested group), or through `super::` chains that climb
/// to the crate root. `module` is the file's [`module_path`].
fn crate_paths(text: &str, module: &[String]) -> Vec<String> {
    rooted_paths(text, "crate", Some(module))
        .into_iter()
        .filter_map(|p| p.into_iter().next())
        .collect()
}

fn layer_of(module: &str) -> Option<usize> {
    layer_of_in(module, LAYERS)
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
        for target in crate_paths(&text, &module_path(&file)) {
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

fn path(names: &[&str]) -> Vec<String> {
    names.iter().map(|n| n.to_string()).collect()
}

#[test]
fn the_layering_check_sees_imports_of_every_form() {
    let text = "use crate::accel::Bvh8;\nuse crate::{math::Ray, scene};\n// crate::render in a comment\n/* crate::camera */ let s = \"crate::light\";\nlet x = crate::shade::f();";
    let file = path(&["geometry", "csg", "mesh"]);
    assert_eq!(
        crate_paths(text, &file),
        ["accel", "math", "scene", "shade"]
    );
    assert_eq!(module_of(&src().join("geometry/csg/mesh.rs")), "geometry");
    assert_eq!(module_of(&src().join("error.rs")), "error");
}

#[test]
fn a_nested_group_gives_every_name_of_the_outer_one() {
    // Cut at its first `}`, this gave `a` and `c`, and never `d`.
    let text = "use crate::{a::{b, c}, d};\nuse crate::{e::{f::{g, h}, i}, j::k, {l, m}};";
    assert_eq!(
        crate_paths(text, &[]),
        ["a", "a", "d", "e", "e", "e", "j", "l", "m"]
    );
    assert_eq!(
        rooted_paths("use crate::{a::{b, c}, d};", "crate", None),
        [path(&["a", "b"]), path(&["a", "c"]), path(&["d"])]
    );
}

#[test]
fn super_chains_that_reach_the_crate_root_are_imports() {
    assert_eq!(
        module_path(&src().join("geometry/csg/mesh.rs")),
        ["geometry", "csg", "mesh"]
    );
    assert_eq!(
        module_path(&src().join("geometry/csg/mod.rs")),
        ["geometry", "csg"]
    );
    assert_eq!(module_path(&src().join("error.rs")), ["error"]);
    let mesh = path(&["geometry", "csg", "mesh"]);
    // From geometry::csg::mesh, two steps up is geometry and three the root.
    assert_eq!(
        crate_paths("use super::super::render::Film;", &mesh),
        ["geometry"]
    );
    assert_eq!(
        crate_paths("use super::super::super::render::Film;", &mesh),
        ["render"]
    );
    // In mod.rs, `super` counts from the folder's module: geometry::csg.
    let csg = path(&["geometry", "csg"]);
    assert_eq!(
        crate_paths("use super::super::render::Film;", &csg),
        ["render"]
    );
    assert_eq!(
        crate_paths("use super::super::{render::Film, scene};", &csg),
        ["render", "scene"]
    );
    // An inline module is one more step: from geometry::csg::mesh::tests,
    // three steps up is geometry (its own `shade`), four the root.
    let inline = "pub(super) fn f() {}\nmod tests {\n    use super::super::super::shade::X;\n    use super::super::super::super::shade::Y;\n}\nuse super::super::super::render::Z;";
    assert_eq!(crate_paths(inline, &mesh), ["geometry", "shade", "render"]);
    // A brace in a char or a string does not open a module.
    let braces = "const A: char = '{';\nconst B: &str = \"}}\";\nmod tests { use super::super::super::super::shade::Y; }";
    assert_eq!(crate_paths(braces, &mesh), ["shade"]);
}

/// Each module of the layer table of docs/ARCHITECTURE.md (`| 3 | `accel` | ... |`)
/// and its layer number.
fn doc_layers(doc: &str) -> BTreeMap<String, usize> {
    let mut out = BTreeMap::new();
    for line in doc.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 4 || !cells[0].is_empty() {
            continue;
        }
        let name = cells[2].strip_prefix('`').and_then(|n| n.strip_suffix('`'));
        if let (Ok(layer), Some(name)) = (cells[1].parse::<usize>(), name) {
            out.insert(name.to_string(), layer);
        }
    }
    out
}

/// Where the document's layers and `layers` disagree: a module at another
/// number, or in one and not the other.
fn layer_differences(doc: &BTreeMap<String, usize>, layers: &[&[&str]]) -> Vec<String> {
    let mut out = Vec::new();
    for (n, layer) in layers.iter().enumerate() {
        for module in *layer {
            match doc.get(*module) {
                None => out.push(format!("`{module}` (layer {n} in LAYERS) has no row")),
                Some(&d) if d != n => out.push(format!(
                    "`{module}`: layer {d} in the document, {n} in LAYERS"
                )),
                Some(_) => {}
            }
        }
    }
    for (module, d) in doc {
        if layer_of_in(module, layers).is_none() {
            out.push(format!(
                "`{module}` is at layer {d} in the document, in no layer of LAYERS"
            ));
        }
    }
    out
}

fn layer_of_in(module: &str, layers: &[&[&str]]) -> Option<usize> {
    layers.iter().position(|layer| layer.contains(&module))
}

fn architecture_doc() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/ARCHITECTURE.md"))
        .unwrap()
}

#[test]
fn the_documents_layer_numbers_are_those_of_layers() {
    let doc = doc_layers(&architecture_doc());
    let wrong = layer_differences(&doc, LAYERS);
    assert!(
        wrong.is_empty(),
        "docs/ARCHITECTURE.md and LAYERS disagree:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_layer_table_is_read_and_compared_number_by_number() {
    let doc = "| layer | module | owns |\n|---|---|---|\n| 0 | `math` | rays |\n| 1 | `mode` | modes |\n| 1 | `output` | files |\nA line | `x` | of prose.";
    let layers = doc_layers(doc);
    assert_eq!(
        layers.into_iter().collect::<Vec<_>>(),
        [
            ("math".to_string(), 0),
            ("mode".to_string(), 1),
            ("output".to_string(), 1)
        ]
    );
    let layers = doc_layers(doc);
    assert!(layer_differences(&layers, &[&["math"], &["mode", "output"]]).is_empty());
    assert_eq!(
        layer_differences(&layers, &[&["math", "mode"], &["output"]]),
        ["`mode`: layer 1 in the document, 0 in LAYERS"]
    );
    assert_eq!(
        layer_differences(&layers, &[&["math"], &["mode", "output", "raycast"]]),
        ["`raycast` (layer 1 in LAYERS) has no row"]
    );
    assert_eq!(
        layer_differences(&layers, &[&["math"], &["output"]]),
        ["`mode` is at layer 1 in the document, in no layer of LAYERS"]
    );
}

/// What the Python binding may not name: the geometry belongs to the
/// library, which answers mesh queries through its facade (`strata::raycast`,
/// and `render`, `scene`, `error`, `output` for rendering).
const PYTHON_MAY_NOT_NAME: &[&[&str]] =
    &[&["accel"], &["geometry"], &["shape"], &["math", "lanes"]];

/// The `strata::` paths of a Python crate file that name what
/// [`PYTHON_MAY_NOT_NAME`] lists.
fn python_reaches_past_the_facade(text: &str) -> Vec<String> {
    rooted_paths(text, "strata", None)
        .into_iter()
        .filter(|p| {
            PYTHON_MAY_NOT_NAME
                .iter()
                .any(|bad| p.len() >= bad.len() && p[..bad.len()] == bad[..])
        })
        .map(|p| format!("strata::{}", p.join("::")))
        .collect()
}

fn python_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    rust_files(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("python/src"),
        &mut files,
    );
    files.sort();
    files
}

#[test]
fn the_python_check_refuses_the_geometry_and_passes_the_facade() {
    assert_eq!(
        python_reaches_past_the_facade("use strata::geometry::Geometry;"),
        ["strata::geometry::Geometry"]
    );
    assert!(python_reaches_past_the_facade("use strata::raycast::Mesh;").is_empty());
    let text = "use strata::{math::{lanes::LANES, Ray}, render, accel::PrimHit};\nlet v = strata::VERSION;\nlet s = strata::shape::triangle::hit(r);\n// strata::geometry in a comment\nuse crate::geometry::Local;";
    assert_eq!(
        python_reaches_past_the_facade(text),
        [
            "strata::math::lanes::LANES",
            "strata::accel::PrimHit",
            "strata::shape::triangle::hit"
        ]
    );
    // The scan sees the real crate: it names the library somewhere.
    let named: usize = python_files()
        .iter()
        .map(|f| rooted_paths(&std::fs::read_to_string(f).unwrap(), "strata", None).len())
        .sum();
    assert!(named > 0, "no strata:: path found in python/src");
}

#[test]
fn python_uses_the_library_through_its_facade() {
    let mut wrong = Vec::new();
    for file in python_files() {
        let text = std::fs::read_to_string(&file).unwrap();
        for p in python_reaches_past_the_facade(&text) {
            wrong.push(format!("{}: {p}", file.display()));
        }
    }
    assert!(
        wrong.is_empty(),
        "python/src reaches past strata's facade (raycast, render, scene, error, output):\n{}",
        wrong.join("\n")
    );
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

/// What of `code` prints to the terminal: the print macros, the standard
/// streams and indicatif. Code from the first `#[cfg(test)]` on is a test
/// module's (ours come last in their file) and may print.
fn prints(code: &str) -> Vec<&'static str> {
    let code = code.split("#[cfg(test)]").next().unwrap_or("");
    [
        "println!",
        "eprintln!",
        "print!",
        "eprint!",
        "stdout()",
        "stderr()",
        "indicatif",
    ]
    .into_iter()
    .filter(|p| {
        // A whole word: `println!` is not the tail of `eprintln!`.
        code.match_indices(p)
            .any(|(i, _)| !code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_'))
    })
    .collect()
}

#[test]
fn the_print_check_sees_each_way_of_printing_outside_tests() {
    assert_eq!(prints("fn f() { eprintln!(\"x\"); }"), ["eprintln!"]);
    assert_eq!(prints("use indicatif::ProgressBar;"), ["indicatif"]);
    assert_eq!(
        prints("let _ = std::io::stderr().write_all(b);"),
        ["stderr()"]
    );
    assert!(prints("fn f() {}\n#[cfg(test)]\nmod tests { fn g() { println!(); } }").is_empty());
}

#[test]
fn only_the_cli_prints() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let printing: Vec<String> = files
        .iter()
        .filter(|f| module_of(f) != "cli" && module_of(f) != "main")
        .filter_map(|f| {
            let found = prints(&code(&std::fs::read_to_string(f).unwrap()));
            (!found.is_empty()).then(|| format!("{} ({})", f.display(), found.join(", ")))
        })
        .collect();
    assert!(
        printing.is_empty(),
        "only src/cli/ prints: report through render's Observer or return warnings instead: {printing:?}"
    );
}

#[test]
fn no_source_file_passes_800_lines() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    // The Python package's crate too.
    files.extend(python_files());
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
    let doc = architecture_doc();
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
