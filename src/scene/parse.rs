//! Reading a scene file into a [`SceneDescription`], with errors that name
//! the file and the line: every mistake of the file in one run, in file
//! order.
//!
//! serde stops at its first error, so the file is parsed as TOML once and
//! then read part by part: the `[render]` table, `[camera]`, each material,
//! each light, each object. A part that does not read is reported and left
//! out, and the others are still read; inside a table, a key serde refuses
//! is reported and dropped, and the table read again without it, so that
//! two bad keys of one table are two errors. A TOML syntax error stops the
//! reading (what follows it has no sure meaning), and is the only error.

use super::description::{LightDesc, MaterialDesc, ObjectDesc, SceneDescription};
use super::edit::{self, Edit};
use super::source_map::SourceMap;
use crate::error::{InputError, InputResult};
use serde::de::IntoDeserializer;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// Parse scene text with `--set` edits applied. The text as written is
/// checked first, so its own mistakes are reported at its lines; what is
/// wrong after that comes from an edit, and is reported as that `--set`.
///
/// Without edits, the description may hold [`SceneDescription::mistakes`]:
/// the parts of the file that did not read are left out of it, and the
/// compiler reports those mistakes together with its own, so that one run
/// names every mistake of the file. (Every caller compiles what it gets.)
pub fn parse_edited(path: &Path, text: &str, edits: &[Edit]) -> InputResult<SceneDescription> {
    let as_written = read_leniently(path, text)?;
    if edits.is_empty() {
        return Ok(as_written);
    }
    if let Some(mistakes) = InputError::all(as_written.mistakes) {
        return Err(mistakes);
    }
    let edited = edit::apply(text, edits)?;
    let mut desc = parse_description(path, &edited).map_err(|e| {
        let blamed = e.into_each().into_iter().map(|e| {
            let edit = edits
                .iter()
                .rev()
                .find(|edit| within(&e.location, &edit.path) || within(&edit.path, &e.location))
                .unwrap_or(&edits[edits.len() - 1]);
            InputError::new("<command line>", edit.flag(), e.message)
        });
        InputError::all(blamed.collect()).expect("an error holds one mistake at least")
    })?;
    desc.source = as_written.source;
    desc.edited = edits.iter().map(|e| e.path.clone()).collect();
    Ok(desc)
}

/// Whether key path `inner` is `outer` or lies inside it.
pub fn within(inner: &str, outer: &str) -> bool {
    inner
        .strip_prefix(outer)
        .is_some_and(|rest| rest.is_empty() || rest.starts_with(['.', '[']))
}

/// Parse scene text read from `path`. A malformed value is reported at its
/// line with its key path (`lights[1].radiance`), from the span serde
/// gives; every such mistake of the file is reported, in file order.
pub fn parse_description(path: &Path, text: &str) -> InputResult<SceneDescription> {
    let mut desc = read_leniently(path, text)?;
    match InputError::all(std::mem::take(&mut desc.mistakes)) {
        Some(mistakes) => Err(mistakes),
        None => Ok(desc),
    }
}

/// The top-level keys of a scene file.
const SECTIONS: &[&str] = &["render", "camera", "materials", "lights", "objects"];

/// What of `text` reads, with a mistake for each part that does not
/// ([`SceneDescription::mistakes`], in file order) and the key path of each
/// light, object or camera left out for it ([`SceneDescription::unread`]).
/// Only a TOML syntax error is an `Err`.
pub fn read_leniently(path: &Path, text: &str) -> InputResult<SceneDescription> {
    let source = SourceMap::new(text);
    let root = DeTable::parse(text).map_err(|e| {
        let mut error = serde_error(path, &source, &e);
        // TOML's "duplicate key" names no key: its span is the key.
        if let Some(key) = e.span().and_then(|s| text.get(s)) {
            let key = key.trim();
            if e.message().trim() == "duplicate key" && !key.is_empty() && !key.contains('\n') {
                error.message = format!("duplicate key '{key}': each key is given once a table");
            }
        }
        error
    })?;
    let mut reader = Reader {
        path,
        source: &source,
        mistakes: Mistakes::new(path),
    };
    let mut desc = SceneDescription::default();
    for (key, value) in root.get_ref() {
        let name: &str = key.get_ref();
        match name {
            "render" => {
                // Every key of [render] stands alone: keep those that read.
                if let (Some(render), _) = reader.read(value) {
                    desc.render = render;
                }
            }
            "camera" => match reader.read(value) {
                (Some(camera), true) => desc.camera = Some(camera),
                _ => desc.unread.push("camera".to_string()),
            },
            "materials" => match value.get_ref() {
                DeValue::Table(table) => {
                    for (name, value) in table {
                        // Kept with the keys that read, so that objects
                        // naming it are not blamed for its mistakes.
                        let material = reader.read(value).0.unwrap_or_default();
                        desc.materials.insert(name.get_ref().to_string(), material);
                    }
                }
                _ => reader.refuse::<BTreeMap<String, MaterialDesc>>(value),
            },
            "lights" => match value.get_ref() {
                DeValue::Array(array) => {
                    desc.lights = reader.elements(array.iter(), "lights", &mut desc.unread);
                }
                _ => reader.refuse::<Vec<LightDesc>>(value),
            },
            "objects" => match value.get_ref() {
                DeValue::Array(array) => {
                    desc.objects = reader.elements(array.iter(), "objects", &mut desc.unread);
                }
                _ => reader.refuse::<Vec<ObjectDesc>>(value),
            },
            _ => {
                let names = SECTIONS
                    .iter()
                    .map(|s| format!("`{s}`"))
                    .collect::<Vec<_>>();
                let message = format!(
                    "unknown field `{name}`, expected one of {}",
                    names.join(", ")
                );
                let line = source.line_at(key.span().start);
                reader.mistakes.push(
                    InputError::new(path, name, in_user_words(&message, name)).on_line(Some(line)),
                    None,
                );
            }
        }
    }
    desc.mistakes = reader.mistakes.in_file_order();
    desc.source = source;
    Ok(desc)
}

/// Reads the parts of one scene file, noting their mistakes.
struct Reader<'a> {
    path: &'a Path,
    source: &'a SourceMap,
    mistakes: Mistakes,
}

impl<'i> Reader<'_> {
    /// `T` from `value`, and whether it read whole. A key that serde
    /// refuses is reported and dropped, and the table read again without
    /// it, until the rest reads (then `T` holds the keys that read) or no
    /// key is to blame (then `None`).
    fn read<T: Deserialize<'i>>(&mut self, value: &Spanned<DeValue<'i>>) -> (Option<T>, bool) {
        let mut value = value.clone();
        let mut dropped: Vec<String> = Vec::new();
        loop {
            let e = match T::deserialize(value.clone().into_deserializer()) {
                Ok(t) => return (Some(t), dropped.is_empty()),
                Err(e) => e,
            };
            // A key dropped for its bad value is not missing as well.
            let missing = e.message().strip_prefix("missing field `");
            if missing.is_some_and(|m| dropped.iter().any(|d| m.trim_end_matches('`') == d)) {
                return (None, false);
            }
            self.mistakes
                .push(serde_error(self.path, self.source, &e), None);
            let (span, DeValue::Table(table)) = (value.span(), value.get_ref()) else {
                return (None, false);
            };
            let at = e.span().map_or(usize::MAX, |s| s.start);
            let Some((culprit, _)) = table
                .iter()
                .find(|(k, v)| k.span().contains(&at) || v.span().contains(&at))
            else {
                return (None, false);
            };
            let culprit = culprit.get_ref().to_string();
            let rest: DeTable<'i> = table
                .iter()
                .filter(|(k, _)| *k.get_ref() != culprit)
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect();
            dropped.push(culprit);
            value = Spanned::new(span, DeValue::Table(rest));
        }
    }

    /// The elements of the array `section` (`lights`, `objects`), each read
    /// alone: one that does not read whole is a default placeholder, so
    /// the others keep their indices, and its key path goes to `unread`.
    fn elements<'v, T: Deserialize<'i> + Default>(
        &mut self,
        array: impl Iterator<Item = &'v Spanned<DeValue<'i>>>,
        section: &str,
        unread: &mut Vec<String>,
    ) -> Vec<T>
    where
        'i: 'v,
    {
        array
            .enumerate()
            .map(|(i, value)| {
                let before = self.mistakes.found.len();
                let read = self.read(value);
                // A mistake of the element as a whole (a missing key) is
                // located at its `[[section]]` header, whose path is the
                // section's: name the element.
                for (_, e) in &mut self.mistakes.found[before..] {
                    if e.location == section {
                        e.location = format!("{section}[{i}]");
                    }
                }
                match read {
                    (Some(t), true) => t,
                    _ => {
                        unread.push(format!("{section}[{i}]"));
                        T::default()
                    }
                }
            })
            .collect()
    }

    /// Report why `value` is not a `T` (a section of the wrong type).
    fn refuse<T: Deserialize<'i>>(&mut self, value: &Spanned<DeValue<'i>>) {
        if let Err(e) = T::deserialize(value.clone().into_deserializer()) {
            self.mistakes
                .push(serde_error(self.path, self.source, &e), None);
        }
    }
}

/// A serde or TOML error at its line and key path, in the scene format's words.
fn serde_error(path: &Path, source: &SourceMap, e: &toml::de::Error) -> InputError {
    let (line, key) = match e.span() {
        Some(span) => {
            let at = span.start;
            (Some(source.line_at(at)), source.path_at(at).unwrap_or(""))
        }
        None => (None, ""),
    };
    InputError::new(path, key, in_user_words(e.message(), key)).on_line(line)
}

/// A scene file's mistakes as they are found, to be given in file order:
/// each at its line in the scene file, or, where it names another file
/// (a mesh file's own mistake), at the line of the part that read it;
/// the command line's before the file's.
#[derive(Debug)]
pub struct Mistakes {
    file: String,
    found: Vec<(usize, InputError)>,
}

impl Mistakes {
    /// No mistakes yet in the scene file `path`.
    pub fn new(path: &Path) -> Self {
        Self {
            file: path.display().to_string(),
            found: Vec::new(),
        }
    }

    /// Note `e` (and any it holds); `part_line` is the line of the scene
    /// file's part being read when it was found.
    pub fn push(&mut self, e: InputError, part_line: Option<usize>) {
        for e in e.into_each() {
            let line = if e.file == "<command line>" {
                0
            } else if e.file == self.file && e.line.is_some() {
                e.line.unwrap_or(0)
            } else {
                part_line.unwrap_or(usize::MAX)
            };
            // The same mistake found twice (a mesh file two objects name)
            // is said once.
            if !self.found.iter().any(|(_, seen)| *seen == e) {
                self.found.push((line, e));
            }
        }
    }

    /// Note the error of `result`, if it is one, and give its value.
    pub fn check<T>(&mut self, result: InputResult<T>, part_line: Option<usize>) -> Option<T> {
        result.map_err(|e| self.push(e, part_line)).ok()
    }

    pub fn is_empty(&self) -> bool {
        self.found.is_empty()
    }

    /// The mistakes, in file order (found order among those of one line).
    pub fn in_file_order(mut self) -> Vec<InputError> {
        self.found.sort_by_key(|(line, _)| *line);
        self.found.into_iter().map(|(_, e)| e).collect()
    }
}

/// serde's message about the value at key path `key`, in the words of the
/// scene format: `invalid type: string "16", expected u32` becomes
/// `expected a whole number, found the string "16"`, and an unknown key or
/// value suggests the valid one it is a typo of. Every type and key error
/// of a scene file passes through here, so no field needs its own words.
/// A message it does not know (the scene's own checks) is kept as it is.
pub fn in_user_words(message: &str, key: &str) -> String {
    if let Some(rest) = message.strip_prefix("invalid type: ") {
        if let Some((found, wanted)) = rest.rsplit_once(", expected ") {
            // An integer past 64 bits, which TOML reads as an i128.
            let huge = found
                .strip_prefix("integer `")
                .and_then(|n| n.strip_suffix("` as i128"))
                .and_then(|n| n.parse::<i128>().ok());
            if let (Some(n), Some(range)) = (huge, integer_range(wanted)) {
                return out_of_range(n, range);
            }
            let wanted = wanted_words(wanted, key);
            // Numbers written as a string, comma-separated: `spp = "16"` (a
            // number in quotes is a string in TOML) or `--set
            // camera.position=-1,0,5` (a list without its brackets).
            let numbers = found
                .strip_prefix("string \"")
                .and_then(|s| s.strip_suffix('"'))
                .map(|s| s.split(',').map(str::trim).collect::<Vec<_>>())
                .filter(|parts| parts.iter().all(|x| x.parse::<f64>().is_ok()));
            let hint = match numbers {
                Some(list) if list.len() > 1 && (wanted.contains('[') || wanted == "an array") => {
                    format!(" (write a list in brackets: [{}])", list.join(", "))
                }
                Some(one) if one.len() == 1 && wanted.contains("number") => {
                    " (write it without the quotes)".to_string()
                }
                _ => String::new(),
            };
            return format!("expected {wanted}, found {}{hint}", found_words(found));
        }
    }
    if let Some(rest) = message.strip_prefix("invalid value: ") {
        if let Some((found, wanted)) = rest.rsplit_once(", expected ") {
            let number = found
                .strip_prefix("integer `")
                .and_then(|n| n.strip_suffix('`'))
                .and_then(|n| n.parse::<i128>().ok());
            if let (Some(n), Some(range)) = (number, integer_range(wanted)) {
                return out_of_range(n, range);
            }
            return format!(
                "expected {}, found {}",
                wanted_words(wanted, key),
                found_words(found)
            );
        }
    }
    if let Some(rest) = message.strip_prefix("invalid length ") {
        if let Some((count, wanted)) = rest.split_once(", expected ") {
            return format!(
                "expected {}, found an array of {count}",
                wanted_words(wanted, key)
            );
        }
    }
    if let Some(rest) = message.strip_prefix("unknown field `") {
        if let Some((word, names)) = rest.split_once('`') {
            return unknown("key", word, &quoted_names(names));
        }
    }
    if let Some(rest) = message.strip_prefix("unknown variant `") {
        if let Some((word, names)) = rest.split_once('`') {
            return unknown("value", word, &quoted_names(names));
        }
    }
    if let Some(rest) = message.strip_prefix("missing field `") {
        return format!("missing key '{}'", rest.trim_end_matches('`'));
    }
    message.to_string()
}

/// A whole number `n` outside an integer type's `(min, max)`, said with
/// the bound it crosses.
fn out_of_range(n: i128, (min, max): (i128, i128)) -> String {
    let bound = if n < min && min == 0 {
        "of 0 or more".to_string()
    } else if n < min {
        format!("of at least {min}")
    } else {
        format!("of at most {max}")
    };
    format!("expected a whole number {bound}, found {n}")
}

/// `unknown key 'x'; did you mean 'y'?`, else the valid names.
fn unknown(what: &str, word: &str, names: &[&str]) -> String {
    if names.is_empty() {
        return format!("unknown {what} '{word}' (this table takes no keys)");
    }
    crate::mode::unknown(what, word, names)
}

/// The names in serde's "expected one of `a`, `b`" tail.
fn quoted_names(tail: &str) -> Vec<&str> {
    tail.split('`').skip(1).step_by(2).collect()
}

/// The value serde expected, as the scene format calls it.
fn wanted_words(wanted: &str, key: &str) -> String {
    if integer_range(wanted).is_some() {
        return "a whole number".to_string();
    }
    if wanted.starts_with("struct ") || wanted == "a map" || wanted == "map" {
        return "a table".to_string();
    }
    if wanted == "a sequence" || wanted == "sequence" {
        return match key {
            // `[lights]` where `[[lights]]` was meant.
            "lights" | "objects" => format!("an array of tables, one [[{key}]] each"),
            _ => "an array".to_string(),
        };
    }
    let text = match wanted {
        "f32" | "f64" => "a number",
        "a boolean" | "bool" => "true or false",
        "a string" | "a borrowed string" | "string" => "a string in quotes",
        _ => match wanted.strip_prefix("an array of length ") {
            // The two arrays of arrays, then the arrays of numbers.
            Some(_) if key.ends_with("triangle.v") => "three points [[x, y, z], …]",
            Some(_) if key.ends_with("transform.matrix") => "four rows of four numbers",
            Some("3") => "three numbers [x, y, z]",
            Some("4") if key.ends_with("rotate") => "four numbers [x, y, z, degrees]",
            Some("4") => "four numbers",
            Some(n) => return format!("an array of {n}"),
            None => return wanted.to_string(),
        },
    };
    text.to_string()
}

/// The value serde found, as a user wrote it.
fn found_words(found: &str) -> String {
    let between = |prefix: &str| {
        found
            .strip_prefix(prefix)
            .and_then(|v| v.strip_prefix('`'))
            .and_then(|v| v.strip_suffix('`'))
    };
    if let Some(v) = between("integer ")
        .or_else(|| between("floating point "))
        .or_else(|| between("boolean "))
    {
        return v.to_string();
    }
    if let Some(s) = found.strip_prefix("string ") {
        return format!("the string {s}");
    }
    match found {
        "sequence" => "an array".to_string(),
        "map" => "a table".to_string(),
        _ => found.to_string(),
    }
}

/// The range of an integer type that serde names (`u32`).
fn integer_range(wanted: &str) -> Option<(i128, i128)> {
    Some(match wanted {
        "u8" => (0, u8::MAX.into()),
        "u16" => (0, u16::MAX.into()),
        "u32" => (0, u32::MAX.into()),
        "u64" => (0, u64::MAX.into()),
        "usize" => (0, usize::MAX as i128),
        "i8" => (i8::MIN.into(), i8::MAX.into()),
        "i16" => (i16::MIN.into(), i16::MAX.into()),
        "i32" => (i32::MIN.into(), i32::MAX.into()),
        "i64" | "isize" => (i64::MIN.into(), i64::MAX.into()),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_keys_and_type_errors_name_the_line() {
        let p = Path::new("bad.toml");
        let e = parse_description(p, "[render]\nwidth = 10\nwidht = 20\n").unwrap_err();
        assert_eq!((e.line, e.location.as_str()), (Some(3), "render.widht"));
        assert!(e.message.contains("widht"), "{e}");
        let e = parse_description(p, "[[objects]]\nsphere = { radius = \"big\" }\n").unwrap_err();
        assert_eq!(
            (e.line, e.location.as_str()),
            (Some(2), "objects[0].sphere.radius")
        );
        let e = parse_description(p, "[render\n").unwrap_err();
        assert!(e.to_string().starts_with("bad.toml: line 1:"), "{e}");
    }

    /// What serde and TOML said in Rust's words (an i128, a struct's
    /// name, a sequence), or without the key or the element at fault.
    #[test]
    fn mistakes_name_the_key_and_the_element_in_the_formats_words() {
        let p = Path::new("s.toml");
        let said = |text: &str| parse_description(p, text).unwrap_err().to_string();
        assert_eq!(
            said("[render]\nspp = 99999999999999999999\n"),
            "s.toml: line 2: render.spp: expected a whole number of at most 4294967295, found 99999999999999999999"
        );
        assert_eq!(
            said("render = 5\n"),
            "s.toml: line 1: render: expected a table, found 5"
        );
        assert_eq!(
            said("[lights]\ntype = \"point\"\n"),
            "s.toml: line 1: lights: expected an array of tables, one [[lights]] each, found a table"
        );
        assert_eq!(
            said("[[lights]]\nposition = [0, 1, 0]\n"),
            "s.toml: line 1: lights[0]: missing key 'type'"
        );
        assert_eq!(
            said("[render]\nspp = 4\nspp = 5\n"),
            "s.toml: line 3: duplicate key 'spp': each key is given once a table"
        );
    }

    #[test]
    fn serde_messages_read_in_the_scene_formats_words() {
        let words = |m: &str| in_user_words(m, "render.spp");
        assert_eq!(
            words("invalid type: string \"16\", expected u32"),
            "expected a whole number, found the string \"16\" (write it without the quotes)"
        );
        assert_eq!(
            words("invalid type: string \"many\", expected u32"),
            "expected a whole number, found the string \"many\""
        );
        // A list without its brackets (`--set camera.position=-1,0,5`);
        // where one number is wanted, no list is suggested.
        assert_eq!(
            in_user_words("invalid type: string \"-1,0,5\", expected an array of length 3", "camera.position"),
            "expected three numbers [x, y, z], found the string \"-1,0,5\" (write a list in brackets: [-1, 0, 5])"
        );
        assert_eq!(
            words("invalid type: string \"1,2\", expected u32"),
            "expected a whole number, found the string \"1,2\""
        );
        assert_eq!(
            words("invalid type: floating point `1.5`, expected u32"),
            "expected a whole number, found 1.5"
        );
        assert_eq!(
            words("invalid value: integer `-1`, expected u32"),
            "expected a whole number of 0 or more, found -1"
        );
        assert_eq!(
            words("invalid value: integer `5000000000`, expected u32"),
            "expected a whole number of at most 4294967295, found 5000000000"
        );
        assert_eq!(
            words("invalid type: boolean `true`, expected f32"),
            "expected a number, found true"
        );
        assert_eq!(
            in_user_words("invalid length 2, expected an array of length 3", "x.v"),
            "expected three numbers [x, y, z], found an array of 2"
        );
        assert_eq!(
            in_user_words(
                "invalid length 2, expected an array of length 3",
                "objects[0].triangle.v"
            ),
            "expected three points [[x, y, z], …], found an array of 2"
        );
        assert_eq!(
            words("unknown field `shadow_sample`, expected one of `spp`, `shadow_samples`"),
            "unknown key 'shadow_sample'; did you mean 'shadow_samples'?"
        );
        assert_eq!(
            words("unknown field `colour`, expected `center` or `radius`"),
            "unknown key 'colour' (expected center or radius)"
        );
        assert_eq!(
            words("unknown field `x`, there are no fields"),
            "unknown key 'x' (this table takes no keys)"
        );
        assert_eq!(
            words("unknown variant `unon`, expected one of `union`, `difference`"),
            "unknown value 'unon'; did you mean 'union'?"
        );
        assert_eq!(words("missing field `radius`"), "missing key 'radius'");
        let own = "must be between 0 and 180 degrees, got 300";
        assert_eq!(words(own), own);
    }

    #[test]
    fn every_mistake_of_a_file_is_reported_in_file_order() {
        let text = "[render]\nspp = \"many\"\nwidht = 10\nheight = 20\n\n\
                    [[lights]]\ntype = \"pont\"\nposition = [0, 1, 0]\n\n\
                    [[objects]]\nsphere = { radius = \"big\" }\n\
                    [[objects]]\nsphere = { radius = 1 }\n\
                    [[objects]]\nsphere = { radius = 1 }\nmaterial = 5\n\
                    [camera]\nfov = \"wide\"\n[extra]\n";
        let e = parse_description(Path::new("s.toml"), text).unwrap_err();
        let each = e.clone().into_each();
        let at: Vec<(Option<usize>, &str)> =
            each.iter().map(|e| (e.line, e.location.as_str())).collect();
        assert_eq!(
            at,
            [
                (Some(2), "render.spp"),
                (Some(3), "render.widht"),
                (Some(7), "lights[0].type"),
                (Some(11), "objects[0].sphere.radius"),
                (Some(16), "objects[2].material"),
                (Some(18), "camera.fov"),
                (Some(19), "extra"),
            ]
        );
        // One line each, as the CLI prints them.
        assert_eq!(e.to_string().lines().count(), 7, "{e}");
        assert!(each[6].message.contains("unknown key 'extra'"), "{e}");

        // Read leniently, the parts that read are kept, those that do not
        // are placeholders named in `unread`, and [render] keeps its good keys.
        let desc = read_leniently(Path::new("s.toml"), text).unwrap();
        assert_eq!(desc.mistakes.len(), 7);
        // (The sections in TOML's key order.)
        assert_eq!(
            desc.unread,
            ["camera", "lights[0]", "objects[0]", "objects[2]"]
        );
        assert_eq!((desc.lights.len(), desc.objects.len()), (1, 3));
        assert!(desc.objects[1].sphere.is_some(), "objects[1] reads");
        assert_eq!(desc.render.height, Some(20));
    }

    #[test]
    fn a_key_dropped_for_its_value_is_not_missing_too() {
        let p = Path::new("s.toml");
        let e = parse_description(p, "[[lights]]\ntype = 5\n").unwrap_err();
        assert!(e.more.is_empty(), "{e}");
        assert_eq!(e.location, "lights[0].type");
        // But a key that is missing is.
        let e = parse_description(p, "[[objects]]\nsphere = { center = [0, 0, 0] }\n").unwrap_err();
        assert_eq!(e.message, "missing key 'radius'");
        // A section of the wrong type is one mistake.
        let e = parse_description(p, "lights = 3\nobjects = {}\n").unwrap_err();
        assert_eq!(e.clone().into_each().len(), 2, "{e}");
        // A syntax error stops the reading: it alone is reported.
        let e = parse_description(p, "[render]\nspp = \nwidth = \"x\"\n").unwrap_err();
        assert!(e.more.is_empty() && e.line == Some(2), "{e}");
    }

    #[test]
    fn an_empty_file_is_a_valid_scene_with_defaults() {
        let d = parse_description(Path::new("empty.toml"), "").unwrap();
        let s = crate::scene::RenderSettings::merge(&[&d.render]);
        assert_eq!((s.width, s.height, s.spp), (640, 480, 1));
        assert!(d.objects.is_empty());
    }
}
