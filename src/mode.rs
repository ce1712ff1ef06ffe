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

/// Declares a closed enum of named modes. `$what` names the kind of mode
/// in error messages ("unknown sampler 'x' (expected random or stratified)").
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
                Self::from_name(s).ok_or_else(|| {
                    format!(
                        "unknown {} '{s}' (expected {})",
                        $what,
                        $crate::mode::expected(&[$($text),+])
                    )
                })
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
    fn expected_lists_read_as_prose() {
        assert_eq!(super::expected(&["a"]), "a");
        assert_eq!(super::expected(&["a", "b"]), "a or b");
        assert_eq!(super::expected(&["a", "b", "c"]), "a, b or c");
    }
}
