//! Reading a scene file into a [`SceneDescription`], with errors that name
//! the file and the line.

use super::description::SceneDescription;
use crate::error::{InputError, InputResult};
use std::path::Path;

pub fn read_description(path: &Path) -> InputResult<SceneDescription> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| InputError::file(path, format!("cannot read: {e}")))?;
    parse_description(path, &text)
}

pub fn parse_description(path: &Path, text: &str) -> InputResult<SceneDescription> {
    toml::from_str::<SceneDescription>(text).map_err(|e| {
        let location = e
            .span()
            .map(|span| {
                format!(
                    "line {}",
                    text[..span.start.min(text.len())].matches('\n').count() + 1
                )
            })
            .unwrap_or_default();
        InputError::new(path, location, e.message().to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_keys_and_type_errors_name_the_line() {
        let p = Path::new("bad.toml");
        let e = parse_description(p, "[render]\nwidth = 10\nwidht = 20\n").unwrap_err();
        assert_eq!(e.location, "line 3");
        assert!(e.message.contains("widht"), "{e}");
        let e = parse_description(p, "[[objects]]\nsphere = { radius = \"big\" }\n").unwrap_err();
        assert_eq!(e.location, "line 2");
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
