//! Number checks shared by every part of the compiler: each value of a
//! scene file is checked where it is read, and a bad one is an error that
//! names its key path (`objects[2].sphere.radius`).

use super::mesh::{MeshOrigin, OutOfReach};
use super::Compiler;
use crate::error::{InputError, InputResult};
use crate::scene::description::V3;
use crate::scene::parse::within;
use crate::scene::settings::past_float32;
use glam::Vec3;

/// `v` as a scene file writes it, `[x, y, z]`, for an error message.
pub(super) fn written(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

/// `Ok` where every one of a table's checks passed, else every error
/// among them (each a check's `err()`): the checks all run, so that
/// one run names each mistake of the table (in the file's order where
/// they are reported).
pub(super) fn all_passed<'e>(
    checks: impl IntoIterator<Item = Option<&'e InputError>>,
) -> InputResult<()> {
    match InputError::all(checks.into_iter().flatten().cloned().collect()) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

impl Compiler<'_> {
    /// Refuse the keys of the table at `key` that its type does not take:
    /// `given` lists each optional key and whether the file gives it,
    /// `takes` the ones that `what` ("a point light") uses. A key that would
    /// silently do nothing is as much a mistake as an unknown one.
    pub(super) fn only(
        &self,
        key: &str,
        what: &str,
        given: &[(&str, bool)],
        takes: &[&str],
    ) -> InputResult<()> {
        match given
            .iter()
            .find(|(name, set)| *set && !takes.contains(name))
        {
            Some((name, _)) => Err(self.err(
                &format!("{key}.{name}"),
                format!(
                    "does not apply to {what}, which takes {}",
                    crate::mode::expected(takes).replace(" or ", " and ")
                ),
            )),
            None => Ok(()),
        }
    }

    /// The value of a key that `what` must have.
    pub(super) fn need<T: Copy>(
        &self,
        value: Option<T>,
        key: &str,
        name: &str,
        what: &str,
    ) -> InputResult<T> {
        value.ok_or_else(|| self.err(key, format!("{what} needs `{name}`")))
    }

    /// The error for a triangle out of reach, at its object's key, with
    /// the mesh file and mesh it is in; a model file rendered as it comes
    /// (no scene file of keys) names its own mesh.
    pub(super) fn out_of_reach(&self, bad: &OutOfReach) -> InputError {
        self.out_of_reach_at(&self.mesh_origins[bad.index], bad)
    }

    /// [`Compiler::out_of_reach`] for a mesh placed first at `origin` (a
    /// prototype's: its trees are built apart from the scene's).
    pub(super) fn out_of_reach_at(&self, origin: &MeshOrigin, bad: &OutOfReach) -> InputError {
        match &origin.file {
            Some((path, _, name)) if *path == self.file => {
                InputError::new(path, name.clone(), bad.message())
            }
            Some((_, written, name)) => {
                let mesh = match name.is_empty() {
                    true => String::new(),
                    false => format!(", mesh \"{name}\""),
                };
                let message = format!("{written}{mesh}: {}", bad.message());
                self.err(&origin.key, message)
            }
            None => self.err(&origin.key, bad.message()),
        }
    }

    /// An error at `key` of the scene file, on the line where the key (or
    /// the nearest table around it) is written.
    pub(super) fn err(&self, key: &str, message: impl Into<String>) -> InputError {
        // The command line's fault: inside an edited value, or at a table
        // the edit gave a key the file did not have.
        let by_edit = |path: &&String| {
            within(key, path) || (within(path, key) && !self.source.contains(path))
        };
        match self.edited.iter().find(by_edit) {
            // The key inside the edited value is named where it is not
            // the edited key itself (`--set camera.fov: must be …`, not
            // `--set camera.fov: camera.fov: must be …`).
            Some(path) if path == key => {
                InputError::new("<command line>", format!("--set {path}"), message)
            }
            Some(path) => InputError::new(
                "<command line>",
                format!("--set {path}"),
                format!("{key}: {}", message.into()),
            ),
            None => InputError::new(&self.file, key, message).on_line(self.source.line_of(key)),
        }
    }

    /// An error at `key` that the values of `others` share the blame for
    /// (`camera.look_at` equal to `camera.position`): where the command
    /// line edited one of them and not `key`, the edit is named, with
    /// `key` after it, rather than the file's line of a value the user
    /// did not change.
    pub(super) fn err_among(
        &self,
        key: &str,
        others: &[&str],
        message: impl Into<String>,
    ) -> InputError {
        match others.iter().find(|&&k| self.edit_gives(k)) {
            Some(&other) if !self.edit_gives(key) => {
                let mut e = self.err(other, message);
                e.message = format!("{key}: {}", e.message);
                e
            }
            _ => self.err(key, message),
        }
    }

    /// Whether the scene gives `key` itself (in its file or by an edit),
    /// rather than leaving it to its default.
    pub(super) fn gives(&self, key: &str) -> bool {
        self.source.contains(key) || self.edit_gives(key)
    }

    /// Whether a `--set` edit gives `key` (the key itself, or a table
    /// around it).
    fn edit_gives(&self, key: &str) -> bool {
        self.edited.iter().any(|path| within(key, path))
    }

    pub(super) fn v3(&self, v: V3, key: &str) -> InputResult<Vec3> {
        let v = Vec3::from(v);
        if v.is_finite() {
            Ok(v)
        } else {
            let note = past_float32(v.abs().max_element());
            Err(self.err(key, format!("must be finite, got {}{note}", written(v))))
        }
    }

    pub(super) fn finite(&self, x: f32, key: &str) -> InputResult<f32> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(key, format!("must be finite, got {x}{}", past_float32(x))))
        }
    }

    pub(super) fn positive(&self, x: f32, key: &str) -> InputResult<f32> {
        if x.is_finite() && x > 0.0 {
            Ok(x)
        } else {
            let note = past_float32(x);
            Err(self.err(
                key,
                format!("must be a positive finite number, got {x}{note}"),
            ))
        }
    }

    pub(super) fn non_negative(&self, x: f32, key: &str) -> InputResult<f32> {
        if x.is_finite() && x >= 0.0 {
            Ok(x)
        } else {
            let note = past_float32(x);
            Err(self.err(key, format!("must be a finite number ≥ 0, got {x}{note}")))
        }
    }

    pub(super) fn colour(&self, v: V3, key: &str) -> InputResult<Vec3> {
        let c = self.v3(v, key)?;
        if c.min_element() < 0.0 {
            return Err(self.err(key, format!("must not be negative, got {}", written(c))));
        }
        Ok(c)
    }

    pub(super) fn direction(&self, v: V3, key: &str) -> InputResult<Vec3> {
        let d = self.v3(v, key)?;
        d.try_normalize()
            .ok_or_else(|| self.err(key, "must be a non-zero vector"))
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::rejected;

    #[test]
    fn each_kind_of_number_is_checked_and_named_by_its_key() {
        for (text, key, needle) in [
            (
                "[[objects]]\nsphere = { radius = 0.0 }",
                "objects[0].sphere.radius",
                "positive",
            ),
            (
                "[[objects]]\nsphere = { radius = -1.0 }",
                "objects[0].sphere.radius",
                "positive",
            ),
            (
                "[[objects]]\nsphere = { radius = nan }",
                "objects[0].sphere.radius",
                "positive",
            ),
            (
                "[[objects]]\nsphere = { radius = inf }",
                "objects[0].sphere.radius",
                "positive",
            ),
            (
                "[[objects]]\nsphere = { radius = 1e39 }",
                "objects[0].sphere.radius",
                "got inf (inf, or a number written past ±3.4e38, float32's largest)",
            ),
            (
                "[camera]\nposition = [0, 1, 1e300]",
                "camera.position",
                "(inf, or a number written past ±3.4e38, float32's largest)",
            ),
            (
                "[materials.m]\nshininess = -1.0",
                "materials.m.shininess",
                "≥ 0",
            ),
            (
                "[materials.m]\ndiffuse = [0.5, -0.1, 0.5]",
                "materials.m.diffuse",
                "negative",
            ),
            (
                "[materials.m]\nemission = [0.5, inf, 0.5]",
                "materials.m.emission",
                "finite",
            ),
            (
                "[[objects]]\nplane = { normal = [0.0, 0.0, 0.0] }",
                "objects[0].plane.normal",
                "non-zero",
            ),
            (
                "[[objects]]\nsphere = { center = [0.0, nan, 0.0], radius = 1.0 }",
                "objects[0].sphere.center",
                "finite",
            ),
        ] {
            let e = rejected(text);
            assert_eq!(e.location, key, "{text}");
            assert!(e.message.contains(needle), "{text}: {e}");
        }
    }

    /// A bad vector is quoted as the file writes it, on the line that
    /// holds it, whichever check refused it.
    #[test]
    fn a_bad_vector_is_quoted_as_written_on_its_line() {
        for (text, line, quoted) in [
            (
                "[render]\nwidth = 4\n[[lights]]\ntype = \"point\"\nposition = [nan, 0.0, 0.0]",
                5,
                "[NaN, 0, 0]",
            ),
            (
                "\n[materials.m]\ndiffuse = [0.5, -0.1, 0.5]",
                3,
                "[0.5, -0.1, 0.5]",
            ),
            (
                "[[objects]]\nsphere = { radius = 1.0 }\ntransform = { scale = [1.0, 0.0, 2.0] }",
                3,
                "[1, 0, 2]",
            ),
            (
                "[materials.m]\nbase_color = [1.5, 0.5, 0.5]",
                2,
                "[1.5, 0.5, 0.5]",
            ),
        ] {
            let e = rejected(text);
            assert_eq!(e.line, Some(line), "{text}: {e}");
            assert!(e.message.ends_with(quoted), "{text}: {e}");
            assert!(!e.message.contains("Vec3"), "{text}: {e}");
        }
    }
}
