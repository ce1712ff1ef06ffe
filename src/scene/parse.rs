//! Reading a scene file into a [`SceneDescription`], with errors that name
//! the file and the line.

use super::description::SceneDescription;
use super::edit::{self, Edit};
use super::source_map::SourceMap;
use crate::error::{InputError, InputResult};
use std::path::Path;

/// Parse scene text with `--set` edits applied. The text as written is
/// checked first, so its own mistakes are reported at its lines; what is
/// wrong after that comes from an edit, and is reported as that `--set`.
pub fn parse_edited(path: &Path, text: &str, edits: &[Edit]) -> InputResult<SceneDescription> {
    let as_written = parse_description(path, text)?;
    if edits.is_empty() {
        return Ok(as_written);
    }
    let edited = edit::apply(text, edits)?;
    let mut desc = parse_description(path, &edited).map_err(|e| {
        let edit = edits
            .iter()
            .rev()
            .find(|edit| within(&e.location, &edit.path) || within(&edit.path, &e.location))
            .unwrap_or(&edits[edits.len() - 1]);
        InputError::new("<command line>", edit.flag(), e.message)
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
/// line with its key path (`lights[1].radiance`), from the span serde gives.
pub fn parse_description(path: &Path, text: &str) -> InputResult<SceneDescription> {
    let source = SourceMap::new(text);
    match toml::from_str::<SceneDescription>(text) {
        Ok(mut desc) => {
            desc.source = source;
            Ok(desc)
        }
        Err(e) => {
            let (line, key) = match e.span() {
                Some(span) => {
                    let at = span.start.min(text.len());
                    (Some(source.line_at(at)), source.path_at(at).unwrap_or(""))
                }
                None => (None, ""),
            };
            Err(InputError::new(path, key, in_user_words(e.message(), key)).on_line(line))
        }
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
            let wanted = wanted_words(wanted, key);
            // `spp = "16"`: a number in quotes is a string in TOML.
            let quoted_number = found
                .strip_prefix("string \"")
                .and_then(|s| s.strip_suffix('"'))
                .is_some_and(|s| s.trim().parse::<f64>().is_ok());
            let hint = if quoted_number && wanted.contains("number") {
                " (write it without the quotes)"
            } else {
                ""
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
            if let (Some(n), Some((min, max))) = (number, integer_range(wanted)) {
                let bound = if n < min && min == 0 {
                    "of 0 or more".to_string()
                } else if n < min {
                    format!("of at least {min}")
                } else {
                    format!("of at most {max}")
                };
                return format!("expected a whole number {bound}, found {n}");
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
    fn an_empty_file_is_a_valid_scene_with_defaults() {
        let d = parse_description(Path::new("empty.toml"), "").unwrap();
        let s = crate::scene::RenderSettings::merge(&[&d.render]);
        assert_eq!((s.width, s.height, s.spp), (640, 480, 1));
        assert!(d.objects.is_empty());
    }
}
