//! What of an MTL library strata reads past, said rather than dropped:
//! one warning per kind of statement (`map_Bump`, `norm`, `Tf`, ...) or
//! `map_Kd` option (`-s`, `-o`, ...) and library, at the line of its first
//! use, counting the others, so that a library of a hundred materials with
//! bump maps gives one line, not a hundred.

use crate::error::InputError;
use std::path::{Path, PathBuf};

/// Why strata reads past statement `keyword`, or `None` for the
/// statements it reads (and `Ka`, the ambient colour, which has no part in
/// light that is computed rather than assumed, and `#` comments).
pub(super) fn why_statement_is_ignored(keyword: &str) -> Option<&'static str> {
    Some(match keyword {
        "newmtl" | "Kd" | "Ks" | "Ke" | "Ns" | "Ni" | "d" | "Tr" | "illum" | "map_Kd" | "Ka"
        | "map_Bump" | "map_bump" | "bump" | "norm" | "map_Norm" | "" => return None,
        _ if keyword.starts_with('#') => return None,
        "disp" | "map_disp" => "strata has no displacement mapping",
        "Tf" => "strata's glass has no colour filter (only d or Tr)",
        "Pr" | "Pm" | "Ps" | "Pc" | "Pcr" | "aniso" | "anisor" | "sharpness" => {
            "strata maps only Kd, Ks, Ke, Ns, Ni, d, Tr and illum to its material"
        }
        _ if keyword.starts_with("map_") || matches!(keyword, "decal" | "refl") => {
            "only map_Kd textures are read"
        }
        _ => "it is not an MTL statement strata reads",
    })
}

/// How many values a `map_Kd` option takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Values {
    /// Exactly this many words.
    Words(usize),
    /// One to three numbers (`-o`, `-s`, `-t`: u [v [w]]).
    UpToThreeNumbers,
}

/// The values of `map_Kd` option `option` (other than `-clamp`, which is
/// read) and why strata reads past it. An option strata does not know
/// takes no values.
pub(super) fn map_kd_option(option: &str) -> (Values, &'static str) {
    match option {
        "-o" | "-s" | "-t" => (
            Values::UpToThreeNumbers,
            "the texture is looked up where the file's texture coordinates say, unmoved and unscaled",
        ),
        "-mm" => (Values::Words(2), "the image's values are used as they are"),
        "-blendu" | "-blendv" | "-cc" | "-boost" | "-texres" | "-imfchan" | "-bm" | "-type" => {
            (Values::Words(1), "the image is used as it is")
        }
        _ => (Values::Words(0), "it is not a map_Kd option strata knows"),
    }
}

/// One kind of thing read past, where first and how often since.
struct Seen {
    what: String,
    why: &'static str,
    line: usize,
    more: usize,
}

/// What one library's reading passed over, to be said as warnings.
pub(super) struct Ignored {
    path: PathBuf,
    seen: Vec<Seen>,
}

impl Ignored {
    pub(super) fn new(path: &Path) -> Self {
        Self {
            path: path.to_path_buf(),
            seen: Vec::new(),
        }
    }

    /// `what` (a statement, or `map_Kd option -s`) is ignored on `line`.
    pub(super) fn note(&mut self, what: &str, why: &'static str, line: usize) {
        match self.seen.iter_mut().find(|s| s.what == what) {
            Some(seen) => seen.more += 1,
            None => self.seen.push(Seen {
                what: what.to_string(),
                why,
                line,
                more: 0,
            }),
        }
    }

    /// One warning per kind, in the order first seen.
    pub(super) fn warn(self, warnings: &mut Vec<InputError>) {
        for s in self.seen {
            let more = match s.more {
                0 => String::new(),
                1 => " (and on 1 more line)".to_string(),
                n => format!(" (and on {n} more lines)"),
            };
            warnings.push(InputError::new(
                &self.path,
                format!("line {}", s.line),
                format!("{} is ignored{more}: {}", s.what, s.why),
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_warning_per_kind_at_its_first_line() {
        let mut ignored = Ignored::new(Path::new("m.mtl"));
        ignored.note("map_Bump", "why", 4);
        ignored.note("norm", "why", 5);
        ignored.note("map_Bump", "why", 9);
        ignored.note("map_Bump", "why", 12);
        let mut warnings = Vec::new();
        ignored.warn(&mut warnings);
        let said: Vec<String> = warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(
            said,
            [
                "m.mtl: line 4: map_Bump is ignored (and on 2 more lines): why",
                "m.mtl: line 5: norm is ignored: why",
            ]
        );
    }

    #[test]
    fn what_is_read_is_not_ignored() {
        for keyword in [
            "newmtl", "Kd", "map_Kd", "Ka", "illum", "", "#comment", "map_Bump", "bump", "norm",
        ] {
            assert_eq!(why_statement_is_ignored(keyword), None, "{keyword}");
        }
        for keyword in ["map_Ks", "Tf", "Pr", "refl", "Kz"] {
            assert!(why_statement_is_ignored(keyword).is_some(), "{keyword}");
        }
    }
}
