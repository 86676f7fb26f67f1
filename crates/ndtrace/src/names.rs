//! The names a description accepts, read from serde itself: the variants of an enum exactly as
//! its `Deserialize` knows them (renamed, e.g. `"first_hit"`), so that the lists users are
//! shown — the command line's choices, the bindings' constants — cannot drift from the schema.

use serde::de::{self, DeserializeOwned, Deserializer, Visitor};
use std::fmt;

/// The names of the variants `T`'s `Deserialize` accepts, in declaration order: for
/// [`CompositeMode`](crate::composite::CompositeMode) `["volume", "mip", "first_hit",
/// "slices"]`. Empty for a type that is not an enum.
pub fn variants<T: DeserializeOwned>() -> &'static [&'static str] {
    let mut names: &'static [&'static str] = &[];
    // The derived impl hands its variant list to `deserialize_enum`; the capture keeps it and
    // stops there, so the error is expected.
    let _ = T::deserialize(Capture(&mut names));
    names
}

/// A deserializer that records the variant list it is asked for and fails on everything.
struct Capture<'a>(&'a mut &'static [&'static str]);

/// The error a [`Capture`] stops with.
#[derive(Debug)]
struct Stop;

impl fmt::Display for Stop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("names captured")
    }
}

impl std::error::Error for Stop {}

impl de::Error for Stop {
    fn custom<T: fmt::Display>(_: T) -> Self {
        Stop
    }
}

impl<'de> Deserializer<'de> for Capture<'_> {
    type Error = Stop;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Stop> {
        Err(Stop)
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        variants: &'static [&'static str],
        _: V,
    ) -> Result<V::Value, Stop> {
        *self.0 = variants;
        Err(Stop)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map struct identifier
        ignored_any
    }
}

#[cfg(test)]
mod tests;
