//! Where each key of a scene file is written, so that every error can name
//! both the key path (`lights[1].radiance`) and its line: serde's errors
//! come with a byte span and no key, the compiler's with a key and no span.

use std::ops::Range;
use toml::de::DeValue;
use toml::Spanned;

/// One key, array element or table of the file.
#[derive(Debug, Clone)]
struct Entry {
    /// `objects[2].sphere.radius`, `lights[0]`, `materials.white`.
    path: String,
    /// Where the key (or, for an array element, the element) is written.
    key: Range<usize>,
    /// Where its value is written.
    value: Range<usize>,
}

/// The key paths of a TOML text with their places.
#[derive(Debug, Clone, Default)]
pub struct SourceMap {
    entries: Vec<Entry>,
    /// Byte offset of the start of each line.
    line_starts: Vec<usize>,
    /// The text was made by strata (the scene of a model file), not
    /// written by the user: it has keys but no lines to point at.
    made_up: bool,
}

impl SourceMap {
    /// The map of `text`; empty if `text` is not valid TOML (its parse
    /// error then carries its own line).
    pub fn new(text: &str) -> Self {
        let mut entries = Vec::new();
        if let Ok(root) = toml::de::DeTable::parse(text) {
            for (key, value) in root.get_ref() {
                walk(key.get_ref().to_string(), key.span(), value, &mut entries);
            }
        }
        let line_starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Self {
            entries,
            line_starts,
            made_up: false,
        }
    }

    /// The same map for text strata made up, which the user never saw:
    /// its keys stay known (to tell a `--set` edit's keys from the
    /// text's), but no error points at one of its lines.
    pub fn made_up(self) -> Self {
        Self {
            made_up: true,
            ..self
        }
    }

    /// The 1-based line of byte `offset`.
    pub fn line_at(&self, offset: usize) -> usize {
        self.line_starts.partition_point(|&start| start <= offset)
    }

    /// The line where `path` is written: the key itself, else its nearest
    /// written ancestor (a default that the file left out is reported at
    /// the table that left it out).
    pub fn line_of(&self, path: &str) -> Option<usize> {
        if self.made_up {
            return None;
        }
        let mut path = path;
        loop {
            if let Some(e) = self.entries.iter().find(|e| e.path == path) {
                return Some(self.line_at(e.key.start));
            }
            path = parent(path)?;
        }
    }

    /// Whether the file writes `path` itself.
    pub fn contains(&self, path: &str) -> bool {
        self.entries.iter().any(|e| e.path == path)
    }

    /// The innermost key whose value contains byte `offset`.
    pub fn path_at(&self, offset: usize) -> Option<&str> {
        self.entries
            .iter()
            .filter(|e| e.value.contains(&offset) || e.key.contains(&offset))
            .min_by_key(|e| e.value.len())
            .map(|e| e.path.as_str())
    }
}

/// `a.b[2]` for `a.b[2].c`, `a.b` for `a.b[2]`, `None` at the top.
fn parent(path: &str) -> Option<&str> {
    let cut = path.rfind(['.', '['])?;
    Some(&path[..cut])
}

fn walk(path: String, key: Range<usize>, value: &Spanned<DeValue<'_>>, out: &mut Vec<Entry>) {
    out.push(Entry {
        path: path.clone(),
        key,
        value: value.span(),
    });
    match value.get_ref() {
        DeValue::Table(table) => {
            for (k, v) in table {
                walk(format!("{path}.{}", k.get_ref()), k.span(), v, out);
            }
        }
        DeValue::Array(array) => {
            for (i, v) in array.iter().enumerate() {
                walk(format!("{path}[{i}]"), v.span(), v, out);
            }
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r#"[render]
width = 10

[[lights]]
type = "point"
position = [0.0, 4.0, 0.0]

[[lights]]
type = "rect"
corner = [0.0, 0.0, 0.0]
radiance = [1.0, 2.0]

[[objects]]
sphere = { center = [0.0, 1.0, 0.0], radius = 1.0 }
group = [ { plane = { normal = [0.0, 1.0, 0.0] } } ]
"#;

    #[test]
    fn key_paths_map_to_the_lines_they_are_written_on() {
        let map = SourceMap::new(TEXT);
        assert_eq!(map.line_of("render.width"), Some(2));
        assert_eq!(map.line_of("lights[1].radiance"), Some(11));
        assert_eq!(map.line_of("lights[0].position"), Some(6));
        assert_eq!(map.line_of("objects[0].sphere.radius"), Some(14));
        assert_eq!(map.line_of("objects[0].group[0].plane.normal"), Some(15));
        // Not written: the nearest written ancestor.
        assert_eq!(map.line_of("lights[1].edge_u"), Some(8));
        assert_eq!(map.line_of("render.spp"), Some(1));
        assert_eq!(map.line_of("camera.fov"), None);
    }

    #[test]
    fn an_offset_maps_to_the_innermost_key_around_it() {
        let map = SourceMap::new(TEXT);
        let at = |needle: &str| TEXT.find(needle).unwrap();
        assert_eq!(map.path_at(at("2.0]")), Some("lights[1].radiance[1]"));
        assert_eq!(
            map.path_at(at("radius = 1.0") + 9),
            Some("objects[0].sphere.radius")
        );
        assert_eq!(map.line_at(at("radiance")), 11);
        assert_eq!(map.line_at(0), 1);
    }

    #[test]
    fn made_up_text_has_keys_but_no_lines() {
        let map = SourceMap::new(TEXT).made_up();
        assert!(map.contains("render.width"));
        assert_eq!(map.line_of("render.width"), None);
        assert_eq!(map.line_of("lights[1].radiance"), None);
    }

    #[test]
    fn invalid_toml_gives_an_empty_map() {
        let map = SourceMap::new("[render\nwidth = 1\n");
        assert_eq!(map.line_of("render.width"), None);
        assert_eq!(map.line_at(9), 2);
    }
}
