//! The names users type for the library's small enums (a Laplacian, a descriptor, a
//! heat-method convention, a ZoomOut direction): one rule to read them and one way to
//! write them.

/// The value of `all` whose `name` is `s`, or the value of the first of `aliases` spelled
/// `s`. `s` is read trimmed, in any case, with `_` taken for `-`.
pub(crate) fn parse_name<T: Copy>(
    s: &str,
    all: &[T],
    name: impl Fn(T) -> &'static str,
    aliases: &[(&str, T)],
) -> Option<T> {
    let key = s.trim().to_ascii_lowercase().replace('_', "-");
    all.iter().copied().find(|&v| name(v) == key).or_else(|| {
        aliases
            .iter()
            .find(|(alias, _)| *alias == key)
            .map(|&(_, v)| v)
    })
}

/// `Display` (the value's `name()`) and `FromStr` (by [`parse_name`] over the type's
/// `ALL`, the aliases given; the error built from the text given) of a named enum.
macro_rules! names_as_text {
    ($t:ty, aliases: $aliases:expr, unknown: $unknown:expr) => {
        impl std::fmt::Display for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl std::str::FromStr for $t {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, Self::Err> {
                let unknown: fn(&str) -> String = $unknown;
                $crate::io::names::parse_name(s, &<$t>::ALL, <$t>::name, $aliases)
                    .ok_or_else(|| unknown(s))
            }
        }
    };
}
pub(crate) use names_as_text;

#[cfg(test)]
mod tests {
    use super::parse_name;

    #[derive(Debug, Clone, Copy, PartialEq)]
    enum Colour {
        Red,
        DarkBlue,
    }

    fn name(c: Colour) -> &'static str {
        match c {
            Colour::Red => "red",
            Colour::DarkBlue => "dark-blue",
        }
    }

    #[test]
    fn names_are_read_trimmed_in_any_case_with_underscores_and_aliases() {
        let all = [Colour::Red, Colour::DarkBlue];
        let aliases = [("navy", Colour::DarkBlue), ("red", Colour::DarkBlue)];
        let read = |s: &str| parse_name(s, &all, name, &aliases);
        assert_eq!(
            read(" RED "),
            Some(Colour::Red),
            "a name wins over an alias"
        );
        assert_eq!(read("Dark_Blue"), Some(Colour::DarkBlue));
        assert_eq!(read("navy"), Some(Colour::DarkBlue));
        assert_eq!(read("green"), None);
        assert_eq!(read(""), None);
    }
}
