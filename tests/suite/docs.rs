//! The user documentation cannot fall behind the code unnoticed:
//!
//! - every long flag that `strata --help` or `strata COMMAND --help` lists
//!   appears in docs/cli.md, and every subcommand has a section there;
//! - every relative link in README.md and docs/*.md points at a file that
//!   exists, and a `#fragment` into a Markdown file names one of its headings;
//! - every TOML example in the scene format reference (and the README and
//!   the CLI reference) is a scene strata accepts, and every example marked
//!   as an error is refused with the message the documentation shows;
//! - the README stays short, the scene it asks a new user to type in
//!   renders something lit, and it counts the scenes `scenes/` holds;
//! - every mesh format strata reads is documented, and the refusals the
//!   scene format shows are what strata says.

use crate::common::process::{repo, run, strata_command, strata_ok};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `strata ARGS --help`, which must succeed.
fn help(args: &[&str]) -> String {
    run(
        strata_command(repo()).args(args).arg("--help"),
        "strata --help",
    )
}

fn is_flag_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '-' || c == '_'
}

/// Every `--long-flag` written anywhere in `text`.
fn long_flags(text: &str) -> BTreeSet<String> {
    let mut flags = BTreeSet::new();
    let mut rest = text;
    while let Some(i) = rest.find("--") {
        let before = rest[..i].chars().next_back();
        let after = &rest[i + 2..];
        let len = after
            .find(|c: char| !is_flag_char(c))
            .unwrap_or(after.len());
        let name = &after[..len];
        if !before.is_some_and(is_flag_char) && name.starts_with(|c: char| c.is_ascii_lowercase()) {
            flags.insert(format!("--{}", name.trim_end_matches('-')));
        }
        rest = &after[len..];
    }
    flags
}

/// The subcommands `strata --help` lists (its "Commands:" section).
fn subcommands(top: &str) -> Vec<String> {
    let section = top
        .split("Commands:")
        .nth(1)
        .expect("strata --help has a Commands section");
    section
        .lines()
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|name| *name != "help")
        .map(str::to_string)
        .collect()
}

#[test]
fn every_flag_of_every_subcommand_is_in_the_cli_reference() {
    let doc = read(&repo().join("docs/cli.md"));
    let documented = long_flags(&doc);
    let top = help(&[]);
    let commands = subcommands(&top);
    for expected in [
        "render", "merge", "converge", "scaling", "bench", "rays", "trace",
    ] {
        assert!(
            commands.iter().any(|c| c == expected),
            "strata --help does not list {expected}: {commands:?}"
        );
    }
    let mut missing = Vec::new();
    for flag in long_flags(&top) {
        if !documented.contains(&flag) {
            missing.push(format!("strata {flag}"));
        }
    }
    for command in &commands {
        if !doc.contains(&format!("## `strata {command}")) {
            missing.push(format!("a `## `strata {command}`` section"));
        }
        for flag in long_flags(&help(&[command])) {
            if !documented.contains(&flag) {
                missing.push(format!("strata {command} {flag}"));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "docs/cli.md does not document: {}",
        missing.join(", ")
    );
}

/// The text of `markdown` outside fenced code blocks and inline code spans.
fn prose(markdown: &str) -> String {
    let mut out = String::new();
    let mut fenced = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            out.push('\n');
            continue;
        }
        if !fenced {
            // Drop inline code: every other backtick-delimited span.
            let mut code = false;
            for (i, part) in line.split('`').enumerate() {
                if i > 0 {
                    code = !code;
                }
                if !code {
                    out.push_str(part);
                }
            }
        }
        out.push('\n');
    }
    out
}

/// The targets of the inline links and images `[text](target)` and the
/// reference definitions `[label]: target` in `markdown`.
fn link_targets(markdown: &str) -> Vec<String> {
    let text = prose(markdown);
    let mut targets = Vec::new();
    let mut rest = text.as_str();
    while let Some(i) = rest.find("](") {
        let after = &rest[i + 2..];
        let end = after.find(')').unwrap_or(after.len());
        let target = after[..end].split_whitespace().next().unwrap_or("");
        targets.push(target.trim_matches(['<', '>']).to_string());
        rest = &after[end..];
    }
    for line in text.lines() {
        let line = line.trim_start();
        if let Some(close) = line.strip_prefix('[').and_then(|l| l.find("]:")) {
            let target = line[close + 3..].split_whitespace().next().unwrap_or("");
            targets.push(target.to_string());
        }
    }
    targets
}

/// GitHub's anchor for a heading: lower case, punctuation other than `-`
/// and `_` dropped, spaces to hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|&c| c.is_alphanumeric() || c == ' ' || c == '-' || c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a Markdown file's headings (repeats get -1, -2, …).
fn anchors(markdown: &str) -> BTreeSet<String> {
    let mut seen = std::collections::HashMap::<String, usize>::new();
    let mut out = BTreeSet::new();
    let mut fenced = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        }
        if fenced || !line.starts_with('#') {
            continue;
        }
        let heading = line.trim_start_matches('#');
        if !heading.starts_with(' ') {
            continue;
        }
        let base = slug(&heading.replace('`', ""));
        let n = seen.entry(base.clone()).or_insert(0);
        out.insert(if *n == 0 {
            base.clone()
        } else {
            format!("{base}-{n}")
        });
        *n += 1;
    }
    out
}

fn markdown_files() -> Vec<PathBuf> {
    let mut files = vec![repo().join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(repo().join("docs"))
        .expect("docs/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

/// Documents that other work is still writing. A link to one of them is
/// skipped only while the file does not exist; once it does, its links and
/// headings are checked like any other's. Remove an entry when its file lands.
const PENDING_DOCS: &[&str] = &["docs/embree.md", "docs/mitsuba.md"];

#[test]
fn every_relative_link_in_the_docs_points_at_a_file_that_exists() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for file in markdown_files() {
        let text = read(&file);
        let name = file.strip_prefix(repo()).unwrap().display().to_string();
        for target in link_targets(&text) {
            if target.is_empty() || target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let (path, fragment) = match target.split_once('#') {
                Some((p, f)) => (p, Some(f)),
                None => (target.as_str(), None),
            };
            let resolved = if path.is_empty() {
                file.clone()
            } else {
                file.parent().unwrap().join(path)
            };
            if !resolved.exists() && PENDING_DOCS.iter().any(|p| repo().join(p) == resolved) {
                continue;
            }
            if !resolved.exists() {
                broken.push(format!("{name}: {target} (no such file)"));
                continue;
            }
            if let Some(fragment) = fragment {
                if resolved.extension().is_some_and(|e| e == "md")
                    && !anchors(&read(&resolved)).contains(fragment)
                {
                    broken.push(format!("{name}: {target} (no such heading)"));
                }
            }
        }
    }
    assert!(checked > 0, "no relative links found at all");
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

/// The documents whose TOML examples are scene files (or parts of one that
/// stand alone as a scene: everything in a scene file has a default).
const SCENE_EXAMPLES: &[&str] = &["README.md", "docs/scene-format.md", "docs/cli.md"];

/// How an example that strata must refuse is marked: its first line is
/// `# error: TEXT`, and the error strata prints must contain TEXT.
const ERROR_MARK: &str = "# error: ";

/// The fenced ```toml blocks of `markdown`, as (line of the fence, text).
fn toml_blocks(markdown: &str) -> Vec<(usize, String)> {
    let mut blocks = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in markdown.lines().enumerate() {
        let fence = line.trim_start().strip_prefix("```");
        match (&mut current, fence) {
            (None, Some(info)) if info.trim() == "toml" => current = Some((i + 1, String::new())),
            (Some(_), Some(_)) => blocks.extend(current.take()),
            (Some((_, text)), None) => {
                text.push_str(line);
                text.push('\n');
            }
            (None, _) => {}
        }
    }
    blocks
}

/// Compile a documented scene as strata does before rendering (parse,
/// validate every key and number, load the meshes, build the BVH), as if
/// saved in the repository's root: mesh paths are relative to it.
fn compile_example(text: &str) -> Result<(), String> {
    let path = repo().join("example.toml");
    crate::common::checked::scene_from_str(text, &path, &strata::scene::RenderOverrides::default())
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// The number a word or digits name ("twelve", "12"), up to twenty.
fn number(word: &str) -> Option<usize> {
    const WORDS: [&str; 21] = [
        "zero",
        "one",
        "two",
        "three",
        "four",
        "five",
        "six",
        "seven",
        "eight",
        "nine",
        "ten",
        "eleven",
        "twelve",
        "thirteen",
        "fourteen",
        "fifteen",
        "sixteen",
        "seventeen",
        "eighteen",
        "nineteen",
        "twenty",
    ];
    word.parse()
        .ok()
        .or_else(|| WORDS.iter().position(|w| w.eq_ignore_ascii_case(word)))
}

/// The README says how many scenes `scenes/` holds: the number of its
/// `.toml` files (it said nine when there were twelve).
#[test]
fn the_readme_counts_the_scenes_there_are() {
    let readme = read(&repo().join("README.md"));
    let said = readme
        .split("`scenes/` has ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .expect("the README says how many scenes `scenes/` has");
    let there = std::fs::read_dir(repo().join("scenes"))
        .unwrap()
        .filter(|e| {
            let path = e.as_ref().unwrap().path();
            path.is_file() && path.extension().is_some_and(|x| x == "toml")
        })
        .count();
    assert_eq!(
        number(said),
        Some(there),
        "README: `scenes/` has {said} ..."
    );
}

/// Every mesh format strata reads is in the scene format's table of mesh
/// files and in the README.
#[test]
fn every_mesh_format_strata_reads_is_documented() {
    let format = read(&repo().join("docs/scene-format.md"));
    let table = format
        .split("## Mesh files")
        .nth(1)
        .and_then(|rest| rest.split("\n### ").next())
        .expect("a Mesh files section");
    let readme = read(&repo().join("README.md"));
    for extension in strata::scene::loaders::SUPPORTED_EXTENSIONS {
        let named = format!("`.{extension}`");
        assert!(
            table.contains(&named),
            "scene-format.md's mesh table lacks {named}"
        );
        assert!(
            readme.contains(&format!(".{extension}")),
            "README.md lacks .{extension}"
        );
    }
}

/// The refusals the scene format shows are, word for word, what strata
/// says of such files (it once listed fewer glTF extensions than strata
/// reads, and called a file requiring one of them refused).
#[test]
fn the_refusals_the_docs_show_are_what_strata_says() {
    use strata::scene::loaders::{load_mesh_file, read_scene_file};
    let format = read(&repo().join("docs/scene-format.md"));
    let dir = crate::common::temp_dir("docs-refusals");
    let cases: [(&str, &[u8], bool); 4] = [
        ("truck.gltf", br#"{"asset":{"version":"1.0"}}"#, true),
        (
            "engine.gltf",
            br#"{"asset":{"version":"2.0"},"extensionsUsed":["KHR_draco_mesh_compression"],"extensionsRequired":["KHR_draco_mesh_compression"]}"#,
            true,
        ),
        ("box.fbx", b"Kaydara FBX Binary  \x00\x1a\x00", false),
        ("box.obj", b"glTF\x02\x00\x00\x00\x0c\x00\x00\x00", true),
    ];
    for (name, bytes, mesh) in cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let mut e = if mesh {
            load_mesh_file(&path).map(|_| ()).unwrap_err()
        } else {
            read_scene_file(&path).map(|_| ()).unwrap_err()
        };
        e.file = name.to_string();
        let line = format!("error: {e}");
        assert!(
            format.lines().any(|l| l == line),
            "scene-format.md does not show what strata says:\n{line}"
        );
    }
}

#[test]
fn the_readme_fits_in_a_sitting() {
    let lines = read(&repo().join("README.md")).lines().count();
    assert!(lines <= 300, "README.md has {lines} lines");
}

#[test]
fn the_first_scene_in_the_readme_renders_a_lit_image() {
    let readme = read(&repo().join("README.md"));
    let section = readme
        .split("## Your first scene")
        .nth(1)
        .expect("a 'Your first scene' section");
    let (_, block) = toml_blocks(section)
        .into_iter()
        .next()
        .expect("a toml block in 'Your first scene'");
    // The README says to save it in the repository's root, so its mesh path
    // resolves from there.
    let small = block
        .replace("width = 640", "width = 32")
        .replace("height = 480", "height = 24")
        .replace("spp = 16 ", "spp = 1 ");
    let scene = crate::common::scene_at(&small, &repo().join("first.toml"));
    let rgb = crate::common::render_rgb(&scene, 2);
    let lit = rgb.iter().filter(|p| p.max_element() > 0.01).count();
    assert!(
        lit > rgb.len() / 4,
        "only {lit} of {} pixels lit",
        rgb.len()
    );
}

#[test]
fn every_scene_example_in_the_docs_is_a_scene_strata_accepts() {
    let mut failures = Vec::new();
    let mut scenes = 0;
    let mut errors = 0;
    for name in SCENE_EXAMPLES {
        let text = read(&repo().join(name));
        for (line, block) in toml_blocks(&text) {
            let at = format!("{name}:{line}");
            match block
                .lines()
                .next()
                .and_then(|l| l.strip_prefix(ERROR_MARK))
            {
                Some(expected) => {
                    errors += 1;
                    match compile_example(&block) {
                        Ok(()) => failures.push(format!("{at}: accepted, but marked as an error")),
                        Err(e) if !e.contains(expected.trim()) => failures.push(format!(
                            "{at}: the error is\n    {e}\n  not one containing\n    {expected}"
                        )),
                        Err(_) => {}
                    }
                }
                None => {
                    scenes += 1;
                    if let Err(e) = compile_example(&block) {
                        failures.push(format!("{at}: {e}"));
                    }
                }
            }
        }
    }
    assert!(scenes >= 10, "only {scenes} scene examples found");
    assert!(errors >= 1, "no error examples found");
    assert!(
        failures.is_empty(),
        "TOML examples that do not do what the docs say:\n{}",
        failures.join("\n")
    );
}

#[test]
fn the_checkers_find_what_they_look_for() {
    assert_eq!(
        long_flags(
            "  -o, --output <OUTPUT>\n      --max-spp <N>  (see --reference-spp)\n a--b ---"
        ),
        ["--max-spp", "--output", "--reference-spp"]
            .map(String::from)
            .into()
    );
    let md = "See [the format](scene-format.md#render) and ![chart](c.svg).\n\
              `[not](code.md)`\n```\n[not](fenced.md)\n```\n[ref]: other.md\n";
    assert_eq!(
        link_targets(md),
        ["scene-format.md#render", "c.svg", "other.md"]
    );
    let heads = anchors("# Scene files\n## `[render]`\n## Units and limits\n## Units and limits\n");
    for a in [
        "scene-files",
        "render",
        "units-and-limits",
        "units-and-limits-1",
    ] {
        assert!(heads.contains(a), "{a} in {heads:?}");
    }
    let blocks = toml_blocks("a\n```toml\n[render]\nspp = 4\n```\n```sh\nx\n```\n```toml\n```\n");
    assert_eq!(
        blocks,
        [(2, "[render]\nspp = 4\n".to_string()), (9, String::new())]
    );
    assert!(compile_example("[render]\nspp = 4\n").is_ok());
    let typo = compile_example("[render]\nssp = 4\n").unwrap_err();
    assert!(
        typo.contains("line 2: render.ssp: unknown key 'ssp'"),
        "{typo}"
    );
}

/// The `strata` command lines in the shell blocks of `markdown`: the line
/// number and the words after `strata`, one entry per command (a line
/// may hold several, joined by `;`, `&&`, `|` or a loop's `do`).
fn strata_commands(markdown: &str) -> Vec<(usize, Vec<String>)> {
    let mut out = Vec::new();
    let mut block: Option<bool> = None;
    let mut joined = String::new();
    for (i, line) in markdown.lines().enumerate() {
        let t = line.trim_start();
        if let Some(tag) = t.strip_prefix("```") {
            block = match block {
                Some(_) => None,
                None => Some(matches!(tag.trim(), "sh" | "bash" | "shell")),
            };
            continue;
        }
        if block != Some(true) {
            continue;
        }
        // A comment starts at a `#` that begins a word.
        let code = match t.find(" #") {
            Some(k) => &t[..k],
            None if t.starts_with('#') => "",
            None => t,
        };
        joined.push_str(code.trim_end_matches('\\'));
        joined.push(' ');
        if code.trim_end().ends_with('\\') {
            continue;
        }
        let text = std::mem::take(&mut joined);
        for part in text.split([';', '|', '&']) {
            let words: Vec<String> = part
                .split_whitespace()
                .map(|w| w.trim_matches(|c| c == '\'' || c == '"').to_string())
                .skip_while(|w| {
                    w.contains('=') || ["do", "then", "time", "/usr/bin/time"].contains(&w.as_str())
                })
                .collect();
            if words.first().map(String::as_str) == Some("strata") {
                out.push((i + 1, words[1..].to_vec()));
            }
        }
    }
    out
}

/// Whether `input` is `output`, or one of the files a loop writes to
/// `output` with one `$variable` in its name (`part_$k.strata`).
fn names_the_same(output: &str, input: &str) -> bool {
    match output.split_once('$') {
        None => output == input,
        Some((before, rest)) => {
            let after = rest.trim_start_matches(|c: char| c.is_ascii_alphanumeric() || c == '_');
            input.len() > before.len() + after.len()
                && input.starts_with(before)
                && input.ends_with(after)
        }
    }
}

/// Flags whose value is a file strata writes: a later command may read it.
const WRITES: [&str; 10] = [
    "-o",
    "--output",
    "--csv",
    "--chart",
    "--stats",
    "--timeline",
    "--checkpoint",
    "--rays",
    "--hits",
    "--save-scene",
];

/// Every `strata` command in the README's and the docs' shell blocks names
/// a subcommand that exists, flags that it takes, and input files that are
/// in the repository (or in assets/, which tools/fetch-assets fills, or
/// written by an earlier command on the same page), so that a reader can
/// run it as written from the repository's root. A command too long for
/// the test suite (a 4096-spp render, a benchmark) is checked this far and
/// no further.
#[test]
fn every_strata_command_in_the_docs_is_one_strata_takes() {
    let commands = subcommands(&help(&[]));
    let mut flags_of: std::collections::HashMap<String, BTreeSet<String>> = Default::default();
    let mut problems = Vec::new();
    for path in markdown_files() {
        let text = read(&path);
        let name = path
            .strip_prefix(repo())
            .unwrap_or(&path)
            .display()
            .to_string();
        let mut written: BTreeSet<String> = BTreeSet::new();
        for (line, words) in strata_commands(&text) {
            let at = format!("{name}:{line}: strata {}", words.join(" "));
            let sub = words.first().filter(|w| !w.starts_with('-')).cloned();
            let key = sub.clone().unwrap_or_default();
            if let Some(s) = &sub {
                if !commands.contains(s) {
                    problems.push(format!("{at}: no subcommand {s}"));
                    continue;
                }
            }
            let known = flags_of.entry(key.clone()).or_insert_with(|| {
                let args: Vec<&str> = sub.iter().map(String::as_str).collect();
                long_flags(&help(&args))
            });
            known.insert("--help".into());
            known.insert("--version".into());
            for (k, w) in words.iter().enumerate() {
                if w.starts_with("--") {
                    let flag = w.split('=').next().unwrap_or(w);
                    if !known.contains(flag) {
                        problems.push(format!("{at}: {key} takes no {flag}"));
                    }
                }
                let previous = k.checked_sub(1).map(|p| words[p].as_str());
                if previous.is_some_and(|p| WRITES.contains(&p)) {
                    written.insert(w.clone());
                    continue;
                }
                let input = [".toml", ".obj", ".ply", ".glb", ".gltf", ".strata", ".bin"]
                    .iter()
                    .any(|e| w.ends_with(e))
                    && !w.starts_with('-')
                    && !w.contains(['$', '*', '{', '<']);
                if input
                    && !repo().join(w).exists()
                    && !w.starts_with("assets/")
                    && !written.iter().any(|o| names_the_same(o, w))
                {
                    problems.push(format!("{at}: {w} is not in the repository and no earlier command on the page writes it"));
                }
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_command_reader_finds_commands_in_loops_chains_and_continuations() {
    let md = "```sh\nfor k in 0 1; do strata render a.toml --slice $k/2 -o p_$k.strata; done\n\
              strata merge p_*.strata -o x.png && strata render \\\n  --spp 4 b.toml # c\n```\n\
              ```toml\nstrata = 1\n```\n";
    assert!(names_the_same("p_$k.strata", "p_3.strata"));
    assert!(!names_the_same("p_$k.strata", "q_3.strata") && !names_the_same("a.toml", "b.toml"));
    let found = strata_commands(md);
    let words: Vec<String> = found.iter().map(|(_, w)| w.join(" ")).collect();
    assert_eq!(
        words,
        [
            "render a.toml --slice $k/2 -o p_$k.strata",
            "merge p_*.strata -o x.png",
            "render --spp 4 b.toml"
        ]
    );
}

/// The summary line with its figures and output path taken out: what a
/// render always prints, whatever its numbers.
fn summary_shape(line: &str) -> String {
    let line = line.split(" -> ").next().unwrap_or(line);
    let mut shape = String::new();
    for c in line.chars() {
        if c.is_ascii_digit() || c == '.' {
            if !shape.ends_with('#') {
                shape.push('#');
            }
        } else {
            shape.push(c);
        }
    }
    shape
}

/// The summary line the README and the CLI reference show after `cargo
/// run --release` is the one strata prints for the seed scene, figures
/// aside.
#[test]
fn the_summary_line_the_docs_show_is_the_one_strata_prints() {
    let dir = crate::common::temp_dir("docs-summary");
    let out = dir.join("render.png");
    let printed = strata_ok(
        repo(),
        &[
            "render",
            "scenes/seed.toml",
            "--width",
            "64",
            "--height",
            "48",
            "--threads",
            "2",
            "-o",
            out.to_str().unwrap(),
        ],
    );
    let printed = printed
        .lines()
        .find(|l| l.contains(" spp: "))
        .unwrap_or_else(|| panic!("no summary line in {printed:?}"));
    // Where the process cannot read its peak memory (no `/proc`), strata
    // leaves the peak out; the rest must still match.
    let known_peak = printed.contains(", peak +");
    let shape = |line: &str| {
        let shape = summary_shape(line);
        if known_peak {
            shape
        } else {
            shape.replace(", peak +# MB", "")
        }
    };
    for doc in ["README.md", "docs/cli.md"] {
        let text = read(&repo().join(doc));
        let shown = text
            .lines()
            .find(|l| l.starts_with("640x480 1 spp: "))
            .unwrap_or_else(|| panic!("{doc} shows no summary line"));
        assert_eq!(
            shape(shown),
            shape(printed),
            "{doc} shows\n{shown}\nstrata prints\n{printed}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
