//! Serde through the text form, for types with `Display` and `FromStr`.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Deserializer, Serializer};

use crate::spectral::filters::Filter;

/// Serde through the text form, for types with `Display` and `FromStr`.
pub(super) fn text_ser<T: fmt::Display, S: Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(v)
}

pub(super) fn text_de<'de, T, D>(d: D) -> Result<T, D::Error>
where
    T: FromStr,
    T::Err: fmt::Display,
    D: Deserializer<'de>,
{
    let s = String::deserialize(d)?;
    s.parse().map_err(serde::de::Error::custom)
}

/// Serde of a [`Filter`] as its text (`"biharmonic"`, `"diffusion:t=0.5"`, ...).
pub mod filter_text {
    use super::*;

    /// Writes the filter's text form.
    pub fn serialize<S: Serializer>(f: &Filter, s: S) -> Result<S::Ok, S::Error> {
        text_ser(f, s)
    }

    /// Parses the filter's text form.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Filter, D::Error> {
        text_de(d)
    }
}
