//! `--set KEY=VALUE`: change any value of a scene file from the command
//! line by its dotted key path (`render.spp=64`, `camera.fov=30`,
//! `materials.white.diffuse=[0.5,0.5,0.5]`, `lights[0].radiance=[1,1,1]`),
//! exactly as editing the file would.
//!
//! The value is TOML (a bare word that is not TOML, such as `random`, is
//! taken as a string); no value at all (`--set lights[0].radiance=`)
//! removes the key, or the array entry, so that a value that excludes
//! another can replace it. The edited document is then read like any
//! scene file, so it is validated the same way. A path may name a key the
//! file leaves out (tables are created as needed), but not an array
//! element the file does not have, and a key removed must be there (a
//! typo removes nothing silently); a key the scene format does not know is
//! refused by the same check as an unknown key in the file.

use crate::error::InputError;
use toml::{Table, Value};

const COMMAND_LINE: &str = "<command line>";

/// One `--set`: a key path and the value to put there, or `None` to
/// remove the key.
#[derive(Debug, Clone, PartialEq)]
pub struct Edit {
    pub path: String,
    pub value: Option<Value>,
}

impl std::str::FromStr for Edit {
    type Err = String;
    fn from_str(text: &str) -> Result<Self, String> {
        let (path, value) = text
            .split_once('=')
            .ok_or_else(|| format!("'{text}' is not KEY=VALUE"))?;
        let path = path.trim().to_string();
        steps(&path)?;
        let value = value.trim();
        if value.is_empty() {
            return Ok(Self { path, value: None });
        }
        let value = match format!("v = {value}").parse::<Table>() {
            Ok(mut t) => t.remove("v").expect("parsed as v"),
            Err(_) => Value::String(value.to_string()),
        };
        Ok(Self {
            path,
            value: Some(value),
        })
    }
}

impl Edit {
    /// How the command line gave it, for messages.
    pub fn flag(&self) -> String {
        format!("--set {}", self.path)
    }

    /// The edit as the user wrote it: `--set KEY=VALUE`, or `--set KEY=`
    /// for a removal.
    pub fn written(&self) -> String {
        match &self.value {
            Some(value) => format!("--set {}={value}", self.path),
            None => format!("--set {}=", self.path),
        }
    }
}

/// One step of a key path: a table key or an array index.
#[derive(Debug, Clone, PartialEq)]
enum Step {
    Key(String),
    Index(usize),
}

/// `lights[0].radiance` as [Key(lights), Index(0), Key(radiance)].
fn steps(path: &str) -> Result<Vec<Step>, String> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (key, mut rest) = part.split_at(part.find('[').unwrap_or(part.len()));
        if key.is_empty()
            || !key
                .chars()
                .all(|c| c.is_alphanumeric() || c == '_' || c == '-')
        {
            return Err(format!(
                "'{path}' is not a key path like lights[0].radiance"
            ));
        }
        out.push(Step::Key(key.to_string()));
        while let Some(inner) = rest.strip_prefix('[') {
            let end = inner
                .find(']')
                .ok_or_else(|| format!("'{path}': unclosed ["))?;
            let index = inner[..end]
                .parse()
                .map_err(|_| format!("'{path}': '{}' is not an index", &inner[..end]))?;
            out.push(Step::Index(index));
            rest = &inner[end + 1..];
        }
        if !rest.is_empty() {
            return Err(format!(
                "'{path}' is not a key path like lights[0].radiance"
            ));
        }
    }
    Ok(out)
}

/// The scene text with every edit applied, in order. The result is TOML
/// text again (comments and layout are not kept: it is only read).
pub fn apply(text: &str, edits: &[Edit]) -> Result<String, InputError> {
    let mut doc: Table = text
        .parse()
        .map_err(|e: toml::de::Error| InputError::new(COMMAND_LINE, "--set", e.message()))?;
    for edit in edits {
        let err = |message: String| InputError::new(COMMAND_LINE, edit.flag(), message);
        let steps = steps(&edit.path).map_err(err)?;
        put(&mut doc, "", &steps, edit.value.clone()).map_err(err)?;
    }
    toml::to_string(&doc).map_err(|e| InputError::new(COMMAND_LINE, "--set", e.to_string()))
}

/// Put `value` at `steps` below `table` (which is at key path `at`),
/// creating missing tables; `None` removes what is there.
fn put(table: &mut Table, at: &str, steps: &[Step], value: Option<Value>) -> Result<(), String> {
    let Some((Step::Key(key), rest)) = steps.split_first() else {
        unreachable!("a path starts with a key");
    };
    let path = if at.is_empty() {
        key.clone()
    } else {
        format!("{at}.{key}")
    };
    if rest.is_empty() {
        match value {
            Some(value) => {
                table.insert(key.clone(), value);
            }
            None => {
                if table.remove(key).is_none() {
                    return Err(no_key_to_remove(at, key, table));
                }
            }
        }
        return Ok(());
    }
    if value.is_none() && !table.contains_key(key) {
        return Err(no_key_to_remove(at, key, table));
    }
    let slot = table.entry(key.clone()).or_insert_with(|| match rest[0] {
        Step::Key(_) => Value::Table(Table::new()),
        Step::Index(_) => Value::Array(Vec::new()),
    });
    put_in(slot, &path, rest, value)
}

/// "lights[0] has no key 'radiace' to remove (it has radiance, type)".
fn no_key_to_remove(at: &str, key: &str, table: &Table) -> String {
    let whose = if at.is_empty() { "the scene" } else { at };
    let keys: Vec<&str> = table.keys().map(String::as_str).collect();
    let has = if keys.is_empty() {
        "none".to_string()
    } else {
        keys.join(", ")
    };
    format!("{whose} has no key '{key}' to remove (it has {has})")
}

/// Put `value` at `steps` below `slot`, the value at key path `path`.
fn put_in(
    slot: &mut Value,
    path: &str,
    steps: &[Step],
    value: Option<Value>,
) -> Result<(), String> {
    match (&steps[0], slot) {
        (Step::Key(_), Value::Table(t)) => put(t, path, steps, value),
        (Step::Index(i), Value::Array(items)) => {
            let count = items.len();
            let item = items.get_mut(*i).ok_or_else(|| {
                let entries = if count == 1 { "entry" } else { "entries" };
                format!("{path} has {count} {entries}, so {path}[{i}] does not exist")
            })?;
            if steps.len() == 1 {
                match value {
                    Some(value) => *item = value,
                    None => {
                        items.remove(*i);
                    }
                }
                return Ok(());
            }
            put_in(item, &format!("{path}[{i}]"), &steps[1..], value)
        }
        (Step::Key(_), _) => Err(format!("{path} is not a table")),
        (Step::Index(_), _) => Err(format!("{path} is not an array")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edit(text: &str) -> Edit {
        text.parse().unwrap()
    }

    #[test]
    fn values_parse_as_toml_and_bare_words_as_strings() {
        assert_eq!(edit("render.spp=64").value, Some(Value::Integer(64)));
        assert_eq!(edit("camera.fov = 30.5").value, Some(Value::Float(30.5)));
        assert_eq!(
            edit("render.sampler=random").value,
            Some(Value::String("random".into()))
        );
        assert_eq!(
            edit("render.sampler=\"random\"").value,
            Some(Value::String("random".into()))
        );
        let v = edit("lights[0].radiance=[1,1,1]").value.unwrap();
        assert_eq!(v.as_array().map(Vec::len), Some(3));
        // No value removes the key; an empty string is written "".
        assert_eq!(edit("lights[0].radiance=").value, None);
        assert_eq!(edit("lights[0].radiance = ").value, None);
        assert_eq!(
            edit("camera.name=\"\"").value,
            Some(Value::String("".into()))
        );
        assert!("render.spp".parse::<Edit>().is_err());
        assert!("lights[x].radiance=1".parse::<Edit>().is_err());
        assert!("lights[0.radiance=1".parse::<Edit>().is_err());
    }

    #[test]
    fn edits_replace_values_create_tables_and_refuse_missing_elements() {
        let text = "[render]\nspp = 4\n[[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\n";
        let out = apply(
            text,
            &[
                edit("render.spp=64"),
                edit("camera.fov=30"),
                edit("lights[0].position=[1.0, 2.0, 3.0]"),
            ],
        )
        .unwrap();
        let t: Table = out.parse().unwrap();
        assert_eq!(t["render"]["spp"], Value::Integer(64));
        assert_eq!(t["camera"]["fov"], Value::Integer(30));
        assert_eq!(t["lights"][0]["position"][2], Value::Float(3.0));
        assert_eq!(t["lights"][0]["type"], Value::String("point".into()));
        let e = apply(text, &[edit("lights[3].radiance=[1,1,1]")]).unwrap_err();
        assert_eq!(e.location, "--set lights[3].radiance");
        assert!(
            e.message.contains("lights has 1 entry, so lights[3]"),
            "{e}"
        );
        let e = apply(text, &[edit("render.spp.x=1")]).unwrap_err();
        assert!(e.message.contains("render.spp is not a table"), "{e}");
    }

    #[test]
    fn an_empty_value_removes_a_key_or_an_entry_that_is_there() {
        let text = "[[lights]]\ntype = \"environment\"\nradiance = [1.0, 1.0, 1.0]\n[[lights]]\ntype = \"point\"\n";
        // A value that excludes another replaces it: map for radiance.
        let out = apply(
            text,
            &[
                edit("lights[0].map=\"sky.hdr\""),
                edit("lights[0].radiance="),
            ],
        )
        .unwrap();
        let t: Table = out.parse().unwrap();
        assert_eq!(t["lights"][0]["map"], Value::String("sky.hdr".into()));
        assert!(t["lights"][0].get("radiance").is_none(), "{out}");
        // An array entry goes, and the later ones move up.
        let t: Table = apply(text, &[edit("lights[0]=")]).unwrap().parse().unwrap();
        assert_eq!(t["lights"].as_array().unwrap().len(), 1);
        assert_eq!(t["lights"][0]["type"], Value::String("point".into()));
        // What is not there cannot be removed: a typo is not silent.
        let e = apply(text, &[edit("lights[0].radiace=")]).unwrap_err();
        assert_eq!(e.location, "--set lights[0].radiace");
        assert!(
            e.message
                .contains("lights[0] has no key 'radiace' to remove (it has radiance, type)"),
            "{e}"
        );
        let e = apply(text, &[edit("camera.fov=")]).unwrap_err();
        assert!(e.message.contains("the scene has no key 'camera'"), "{e}");
        let e = apply(text, &[edit("lights[2]=")]).unwrap_err();
        assert!(e.message.contains("lights has 2 entries"), "{e}");
    }
}
