//! Settings that take one of a few named values (a measurement frame, a fold grouping, a table
//! semantics): each such enum lists its values with their names and a line of help ([`choices!`]), so
//! that every front end offers, parses and prints the same words — the command line's `--help` and
//! parser, Python's keyword arguments — and none keeps a list of its own.

use std::fmt;

/// A name that is not one of a setting's values.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownChoice {
    /// What the setting is ("measurement frame").
    pub what: &'static str,
    /// The name given.
    pub given: String,
    /// The names it takes.
    pub known: Vec<&'static str>,
}

impl fmt::Display for UnknownChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "unknown {} `{}` (use {})", self.what, self.given, self.known.join(", "))
    }
}

impl std::error::Error for UnknownChoice {}

/// Gives an enum its named values: `CHOICES` (name, help, value), `name()`, `FromStr` (the name, any
/// case) and `Display` (the name).
///
/// ```
/// #[derive(Clone, Copy, Debug, PartialEq)]
/// enum Frame { Base, Tracker }
/// thermokin_chain::choices!(Frame, "measurement frame", [
///     ("base", "the robot's base frame", Frame::Base),
///     ("tracker", "a laser tracker's frame", Frame::Tracker),
/// ]);
/// assert_eq!("Tracker".parse::<Frame>(), Ok(Frame::Tracker));
/// assert_eq!(Frame::Base.to_string(), "base");
/// assert_eq!("nope".parse::<Frame>().unwrap_err().to_string(), "unknown measurement frame `nope` (use base, tracker)");
/// ```
#[macro_export]
macro_rules! choices {
    ($ty:ty, $what:literal, [$(($name:literal, $help:literal, $value:expr)),+ $(,)?]) => {
        impl $ty {
            /// Every value with its name and a line of help, as front ends offer them.
            pub const CHOICES: &'static [(&'static str, &'static str, $ty)] = &[$(($name, $help, $value)),+];

            /// The value's name.
            pub fn name(&self) -> &'static str {
                Self::CHOICES.iter().find(|(_, _, v)| v == self).map_or("?", |(n, _, _)| *n)
            }
        }

        impl ::std::str::FromStr for $ty {
            type Err = $crate::UnknownChoice;
            fn from_str(s: &str) -> Result<Self, Self::Err> {
                Self::CHOICES.iter().find(|(n, _, _)| n.eq_ignore_ascii_case(s.trim())).map(|(_, _, v)| *v).ok_or_else(
                    || $crate::UnknownChoice {
                        what: $what,
                        given: s.to_string(),
                        known: Self::CHOICES.iter().map(|(n, _, _)| *n).collect(),
                    },
                )
            }
        }

        impl ::std::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}
