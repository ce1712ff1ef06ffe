//! Render settings are declared once, in `RenderOverrides`: the scene
//! file's `[render]` keys (serde) and the command line's flags (clap) are
//! its fields, and `strata_rt.render`'s keywords, in its pyo3 signature
//! (python/src/render.rs) and in both `@overload`s of its stub
//! (python/strata_rt/_native.pyi), must name exactly those fields, each
//! defaulting to None, plus the front-end settings of [`FRONT_END`], which
//! must be flags of `strata render`. Adding a field to `RenderOverrides`
//! without its keyword, or a keyword the stub does not have, fails here;
//! python/tests/test_stub.py holds the stub to the compiled module.

use clap::{Args, Command};
use std::collections::BTreeSet;
use std::path::PathBuf;
use strata::scene::RenderOverrides;

/// Keywords of `render` that are not render settings, each with the
/// `strata render` flag it is: what to render (`set`) and how (threads,
/// passes, packets, schedule, BVH effort, the window, the AOVs), which
/// change the time or the output, never a pixel's value; and which of a
/// model file's cameras to render from.
const FRONT_END: [(&str, &str); 9] = [
    ("set", "--set"),
    ("camera", "--camera"),
    ("threads", "--threads"),
    ("passes", "--passes"),
    ("packets", "--packets"),
    ("schedule", "--schedule"),
    ("bvh_quality", "--bvh-quality"),
    ("crop", "--crop"),
    // Python's plural: `aovs=True` asks for all of them.
    ("aovs", "--aov"),
];

fn repo_file(path: &str) -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `RenderOverrides`' fields as clap names its flags' ids (the field names).
fn clap_fields() -> Vec<String> {
    RenderOverrides::augment_args(Command::new("strata"))
        .get_arguments()
        .map(|a| a.get_id().to_string())
        .collect()
}

/// `RenderOverrides`' fields as serde knows them: the keys its
/// `deny_unknown_fields` error lists for a `[render]` key that is none.
fn serde_fields() -> Vec<String> {
    let err = toml::from_str::<RenderOverrides>("not_a_setting = 1")
        .expect_err("an unknown key is refused")
        .to_string();
    let (_, expected) = err
        .split_once("expected one of")
        .unwrap_or_else(|| panic!("serde's message lists no keys: {err}"));
    expected
        .split(',')
        .map(|k| k.trim().trim_matches('`').to_string())
        .filter(|k| !k.is_empty())
        .collect()
}

/// One parameter: its name and its default as written (`None`, `...`).
#[derive(Debug, PartialEq)]
struct Param {
    name: String,
    default: Option<String>,
}

/// The parameters of `text`, the inside of a parameter list, split at
/// the commas outside brackets, with `*` kept as a parameter of its own.
fn params(text: &str) -> Vec<Param> {
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0i32, 0);
    for (i, c) in text.char_indices() {
        match c {
            '(' | '[' | '{' => depth += 1,
            ')' | ']' | '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&text[start..]);
    parts
        .into_iter()
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .map(|p| {
            let (head, default) = match p.split_once('=') {
                Some((h, d)) => (h, Some(d.trim().to_string())),
                None => (p, None),
            };
            // A stub's annotation, `name: Optional[int]`, is not the name.
            let name = head.split(':').next().unwrap_or(head).trim().to_string();
            Param { name, default }
        })
        .collect()
}

/// The text between the bracket that opens at `open` in `text` and the one that closes it.
fn bracketed(text: &str, open: usize) -> &str {
    let mut depth = 0;
    for (i, c) in text[open..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    return &text[open + 1..open + i];
                }
            }
            _ => {}
        }
    }
    panic!("unclosed bracket at byte {open}");
}

/// The pyo3 signature of the `#[pyfunction]` `render`.
fn pyo3_signature() -> Vec<Param> {
    let source = repo_file("python/src/render.rs");
    let at = source
        .find("#[pyo3(signature = (")
        .expect("render's #[pyo3(signature = (...))]");
    let after = &source[at..];
    let function = after.find("fn ").expect("a function after the signature");
    assert!(
        after[function + 3..].starts_with("render("),
        "the first pyo3 signature of python/src/render.rs is render's"
    );
    let open = at + "#[pyo3(signature = ".len();
    params(bracketed(&source, open))
}

/// The parameters of every `def render(` of the stub.
fn stub_overloads() -> Vec<Vec<Param>> {
    let stub = repo_file("python/strata_rt/_native.pyi");
    stub.match_indices("def render(")
        .map(|(at, m)| params(bracketed(&stub, at + m.len() - 1)))
        .collect()
}

/// The keyword-only parameters: those after `*`.
fn keywords(params: &[Param]) -> &[Param] {
    let star = params
        .iter()
        .position(|p| p.name == "*")
        .expect("render's settings are keyword-only (after *)");
    &params[star + 1..]
}

#[test]
fn clap_and_serde_name_the_same_settings() {
    let clap = clap_fields();
    assert!(clap.len() >= 11, "{clap:?}");
    assert_eq!(clap, serde_fields());
}

#[test]
fn render_keywords_are_the_settings_and_the_front_end_ones() {
    let settings = clap_fields();
    let front_end: Vec<&str> = FRONT_END.iter().map(|(k, _)| *k).collect();
    let signature = pyo3_signature();
    let overloads = stub_overloads();
    assert_eq!(overloads.len(), 2, "the stub has two @overloads of render");
    for (what, params) in std::iter::once(("the pyo3 signature", &signature))
        .chain(overloads.iter().map(|o| ("a stub overload", o)))
    {
        assert_eq!(params[0].name, "scene", "{what}: {params:?}");
        let keywords = keywords(params);
        let names: BTreeSet<&str> = keywords.iter().map(|p| p.name.as_str()).collect();
        let wanted: BTreeSet<&str> = settings
            .iter()
            .map(String::as_str)
            .chain(front_end.iter().copied())
            .collect();
        assert_eq!(names.len(), keywords.len(), "{what} repeats a keyword");
        let missing: Vec<_> = wanted.difference(&names).collect();
        let extra: Vec<_> = names.difference(&wanted).collect();
        assert!(
            missing.is_empty() && extra.is_empty(),
            "{what} of render: missing {missing:?}, not a setting {extra:?}"
        );
        for p in keywords {
            // The second overload is the one for `aovs` given (`...`).
            let may_be_required = what != "the pyo3 signature" && p.name == "aovs";
            let default = p.default.as_deref();
            assert!(
                default == Some("None") || (may_be_required && default == Some("...")),
                "{what}: {} defaults to {default:?}, not None",
                p.name
            );
        }
    }
    // The same order everywhere, so that the stub reads as the signature.
    let order = |params: &[Param]| -> Vec<String> {
        keywords(params).iter().map(|p| p.name.clone()).collect()
    };
    for overload in &overloads {
        assert_eq!(order(overload), order(&signature));
    }
}

#[test]
fn the_front_end_keywords_are_flags_of_strata_render() {
    let help = std::process::Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["render", "--help"])
        .output()
        .expect("run strata render --help");
    let help = String::from_utf8_lossy(&help.stdout);
    for flag in FRONT_END.iter().map(|(_, f)| f.to_string()).chain(
        clap_fields()
            .iter()
            .map(|f| format!("--{}", f.replace('_', "-"))),
    ) {
        assert!(
            help.contains(&format!("{flag} ")) || help.contains(&format!("{flag}\n")),
            "strata render has no {flag}:\n{help}"
        );
    }
}

#[test]
fn the_parameter_reader_splits_at_top_level_commas() {
    let p = params("scene, *, a: Union[Tuple[int, int], str, None] = None, b=...,");
    let names: Vec<&str> = p.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["scene", "*", "a", "b"]);
    assert_eq!(p[2].default.as_deref(), Some("None"));
    assert_eq!(p[3].default.as_deref(), Some("..."));
    assert_eq!(p[0].default, None);
}
