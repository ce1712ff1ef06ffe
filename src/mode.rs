//! Closed enums of named modes (`sampler = "stratified"`, `--packets off`):
//! one declaration gives the enum its name table, and from that its
//! parsing and printing everywhere a user meets it, so the scene file, the
//! command line (with `--help` listing the values), the stats JSON and the
//! error messages always agree.
//!
//! ```ignore
//! mode_enum! {
//!     /// Whether traversal prefetches.
//!     #[derive(Default)]
//!     pub enum Prefetch("prefetch mode") {
//!         #[default]
//!         Auto = "auto",
//!         On = "on",
//!         Off = "off",
//!     }
//! }
//! ```
//!
//! A variant may accept aliases after its name (`SolidAngle = "solid_angle"
//! | "solid-angle"`); it always prints as the name.

/// "a", "a or b", "a, b or c": the names a mode accepts, for messages.
pub fn expected(names: &[&str]) -> String {
    match names {
        [] => String::new(),
        [one] => (*one).to_string(),
        [rest @ .., last] => format!("{} or {last}", rest.join(", ")),
    }
}

/// The one name in `names` that `word` is most likely a typo of, if any:
/// the unique nearest within an edit distance of a third of `word`'s
/// length (at least 1, at most 2), or else the one name that `word` begins
/// (`persp` for `perspective`). Case is ignored. Used for "did you mean"
/// in messages about unknown keys and values.
pub fn nearest<'a>(word: &str, names: &[&'a str]) -> Option<&'a str> {
    let word = word.to_lowercase();
    let limit = (word.chars().count() / 3).clamp(1, 2);
    let mut best: Option<(usize, &'a str)> = None;
    let mut tied = false;
    for &name in names {
        let d = edit_distance(&word, &name.to_lowercase());
        match best {
            Some((b, _)) if d > b => {}
            Some((b, _)) if d == b => tied = true,
            _ => (best, tied) = (Some((d, name)), false),
        }
    }
    if let (Some((d, name)), false) = (best, tied) {
        if d <= limit {
            return Some(name);
        }
    }
    let mut prefixed = names
        .iter()
        .filter(|name| word.chars().count() >= 3 && name.to_lowercase().starts_with(&word));
    match (prefixed.next(), prefixed.next()) {
        (Some(name), None) => Some(name),
        _ => None,
    }
}

/// Edits (insert, delete, substitute, swap two neighbours) that turn `a`
/// into `b`: the optimal string alignment distance, over characters.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    // Rows i−2, i−1 and i of the table d[i][j] = distance(a[..i], b[..j]).
    let mut before: Vec<usize> = vec![0; b.len() + 1];
    let mut last: Vec<usize> = (0..=b.len()).collect();
    for i in 1..=a.len() {
        let mut row = vec![i; b.len() + 1];
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            row[j] = (last[j] + 1).min(row[j - 1] + 1).min(last[j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                row[j] = row[j].min(before[j - 2] + 1);
            }
        }
        before = std::mem::replace(&mut last, row);
    }
    last[b.len()]
}

/// "unknown sampler 'x'; did you mean 'y'?" when one name is close, else
/// "unknown sampler 'x' (expected a, b or c)".
pub fn unknown(what: &str, word: &str, names: &[&str]) -> String {
    match nearest(word, names) {
        Some(name) => format!("unknown {what} '{word}'; did you mean '{name}'?"),
        None => format!("unknown {what} '{word}' (expected {})", expected(names)),
    }
}

/// Declares a closed enum of named modes. `$what` names the kind of mode
/// in error messages ("unknown sampler 'x' (expected random or stratified)",
/// or "unknown sampler 'stratifed'; did you mean 'stratified'?").
/// Implements `ALL`, `name()`, `Display`, `FromStr`, serde's `Serialize` and
/// `Deserialize` by name, and clap's `ValueEnum`.
macro_rules! mode_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident($what:literal) {
            $(
                $(#[$variant_meta:meta])*
                $variant:ident = $text:literal $(| $alias:literal)*
            ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        $vis enum $name {
            $($(#[$variant_meta])* $variant,)+
        }

        impl $name {
            /// Every mode, in declaration order.
            pub const ALL: [Self; [$(stringify!($variant)),+].len()] = [$(Self::$variant),+];

            /// The name a scene file or the command line uses.
            pub fn name(self) -> &'static str {
                match self {
                    $(Self::$variant => $text,)+
                }
            }

            fn from_name(name: &str) -> Option<Self> {
                match name {
                    $($text $(| $alias)* => Some(Self::$variant),)+
                    _ => None,
                }
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl std::str::FromStr for $name {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, String> {
                Self::from_name(s)
                    .ok_or_else(|| $crate::mode::unknown($what, s, &[$($text),+]))
            }
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(self.name())
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let text = <std::borrow::Cow<'de, str> as serde::Deserialize>::deserialize(d)?;
                text.parse().map_err(serde::de::Error::custom)
            }
        }

        impl clap::ValueEnum for $name {
            fn value_variants<'a>() -> &'a [Self] {
                &Self::ALL
            }

            fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
                let value = clap::builder::PossibleValue::new(self.name());
                Some(match self {
                    $(Self::$variant => value $(.alias($alias))*,)+
                })
            }
        }
    };
}

pub(crate) use mode_enum;

#[cfg(test)]
mod tests {
    mode_enum! {
        /// A mode for the tests.
        #[derive(Default)]
        pub enum Flavour("flavour") {
            Plain = "plain",
            #[default]
            SolidAngle = "solid_angle" | "solid-angle",
            Last = "last",
        }
    }

    #[test]
    fn names_parse_print_and_list_in_one_order() {
        for f in Flavour::ALL {
            assert_eq!(f.name().parse::<Flavour>(), Ok(f));
            assert_eq!(f.to_string(), f.name());
        }
        assert_eq!("solid-angle".parse(), Ok(Flavour::SolidAngle));
        assert_eq!(Flavour::default(), Flavour::SolidAngle);
        assert_eq!(
            "sour".parse::<Flavour>(),
            Err("unknown flavour 'sour' (expected plain, solid_angle or last)".to_string())
        );
    }

    #[test]
    fn serde_and_clap_use_the_same_names() {
        #[derive(Debug, serde::Deserialize, serde::Serialize)]
        struct Table {
            flavour: Flavour,
        }
        let t: Table = toml::from_str("flavour = \"solid-angle\"").unwrap();
        assert_eq!(t.flavour, Flavour::SolidAngle);
        assert_eq!(
            toml::to_string(&t).unwrap().trim(),
            "flavour = \"solid_angle\""
        );
        let e = toml::from_str::<Table>("flavour = \"sour\"").unwrap_err();
        assert!(
            e.to_string()
                .contains("expected plain, solid_angle or last"),
            "{e}"
        );

        use clap::ValueEnum;
        assert_eq!(Flavour::from_str("last", false), Ok(Flavour::Last));
        assert_eq!(
            Flavour::from_str("solid-angle", false),
            Ok(Flavour::SolidAngle)
        );
        assert!(Flavour::from_str("sour", false).is_err());
    }

    #[test]
    fn typos_suggest_the_one_nearest_name() {
        use super::{edit_distance, nearest};
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("fvo", "fov"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        let names = ["width", "height", "spp", "shadow_samples", "seed"];
        assert_eq!(nearest("shadow_sample", &names), Some("shadow_samples"));
        assert_eq!(nearest("widht", &names), Some("width"));
        assert_eq!(nearest("ssp", &names), Some("spp"));
        assert_eq!(nearest("Height", &names), Some("height"));
        assert_eq!(nearest("shadow", &names), Some("shadow_samples"));
        assert_eq!(nearest("colour", &names), None);
        // Two names equally near: no guess.
        assert_eq!(nearest("sped", &["seed", "spud"]), None);
        assert_eq!(
            "stratifed".parse::<Flavour>().unwrap_err(),
            "unknown flavour 'stratifed' (expected plain, solid_angle or last)"
        );
        assert_eq!(
            "solid-angel".parse::<Flavour>().unwrap_err(),
            "unknown flavour 'solid-angel'; did you mean 'solid_angle'?"
        );
    }

    #[test]
    fn expected_lists_read_as_prose() {
        assert_eq!(super::expected(&["a"]), "a");
        assert_eq!(super::expected(&["a", "b"]), "a or b");
        assert_eq!(super::expected(&["a", "b", "c"]), "a, b or c");
    }
}
