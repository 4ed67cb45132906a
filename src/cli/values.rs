//! Value parsers that tell shell completion what to offer: the words a
//! value takes (`--view front|side|...`, `--units m|cm|...`), while parsing
//! accepts what the type's `FromStr` does (a units value may also be a
//! number of metres per unit, which completion cannot list).

use clap::builder::{PossibleValue, TypedValueParser};
use std::marker::PhantomData;

/// Parses `T` from text and suggests `words` for completion and `--help`.
#[derive(Clone)]
pub struct Suggest<T> {
    words: &'static [&'static str],
    parsed: PhantomData<fn() -> T>,
}

/// A parser of `T` suggesting `words`.
pub fn suggest<T>(words: &'static [&'static str]) -> Suggest<T> {
    Suggest {
        words,
        parsed: PhantomData,
    }
}

impl<T> TypedValueParser for Suggest<T>
where
    T: std::str::FromStr + Clone + Send + Sync + 'static,
    T::Err: std::fmt::Display,
{
    type Value = T;

    fn parse_ref(
        &self,
        command: &clap::Command,
        argument: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<T, clap::Error> {
        let text = clap::builder::StringValueParser::new().parse_ref(command, argument, value)?;
        text.parse::<T>().map_err(|e| {
            let argument = argument.map_or_else(|| "the value".to_string(), |a| a.to_string());
            clap::Error::raw(
                clap::error::ErrorKind::InvalidValue,
                format!("invalid value '{text}' for '{argument}': {e}\n"),
            )
            .with_cmd(command)
        })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(self.words.iter().map(|w| PossibleValue::new(*w))))
    }
}

/// Units words (`groom::Units` also takes metres per unit).
pub const UNITS: &[&str] = &["m", "cm", "mm", "in"];
/// Up axes.
pub const UP: &[&str] = &["y", "z"];
/// Preview views.
pub const VIEWS: &[&str] = &["front", "side", "top", "persp"];
