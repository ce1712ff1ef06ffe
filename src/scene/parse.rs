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
            Err(InputError::new(path, key, e.message().to_string()).on_line(line))
        }
    }
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
    fn an_empty_file_is_a_valid_scene_with_defaults() {
        let d = parse_description(Path::new("empty.toml"), "").unwrap();
        let s = crate::scene::RenderSettings::merge(&[&d.render]);
        assert_eq!((s.width, s.height, s.spp), (640, 480, 1));
        assert!(d.objects.is_empty());
    }
}
