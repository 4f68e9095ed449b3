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

/// The names of a field-less enum, written once: `ALL` (every value, in the order of the
/// names), `name()`, `Display` (the name) and `FromStr` (by [`parse_name`], with the
/// aliases of each value; an unknown text gives the message `unknown` builds from it).
macro_rules! names_as_text {
    (
        $t:ident,
        names: [$($v:ident => $name:literal),+ $(,)?],
        aliases: [$($av:ident => [$($alias:literal),+ $(,)?]),* $(,)?],
        unknown: $unknown:expr $(,)?
    ) => {
        impl $t {
            /// Every value, in the order of the names.
            pub const ALL: [Self; [$($name),+].len()] = [$(Self::$v),+];

            #[doc = concat!("The name users type (", $("`", $name, "` ",)+ ").")]
            pub fn name(self) -> &'static str {
                match self {
                    $(Self::$v => $name,)+
                }
            }
        }

        impl std::fmt::Display for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl std::str::FromStr for $t {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, Self::Err> {
                const ALIASES: &[(&str, $t)] = &[$($(($alias, $t::$av),)+)*];
                let unknown: fn(&str) -> String = $unknown;
                $crate::io::names::parse_name(s, &Self::ALL, Self::name, ALIASES)
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

    /// The enums written with [`names_as_text!`] keep their text forms: each name reads
    /// back and is what `Display` writes, the aliases read as before, and an unknown name
    /// gives the message it gave.
    #[test]
    fn the_named_enums_keep_their_text_forms() {
        use crate::correspondence::{DescriptorKind, ZoomoutDirection};
        use crate::geodesic::Convention;
        use crate::operators::Laplacian;
        fn round_trip<T>(all: &[T], name: fn(T) -> &'static str)
        where
            T: Copy + PartialEq + std::fmt::Debug + std::fmt::Display + std::str::FromStr,
            T::Err: std::fmt::Debug,
        {
            for &v in all {
                assert_eq!(v.to_string(), name(v));
                assert_eq!(name(v).parse::<T>().unwrap(), v);
                assert_eq!(
                    format!(" {} ", name(v).to_uppercase())
                        .parse::<T>()
                        .unwrap(),
                    v
                );
            }
        }
        fn reads_as<T>(spellings: &[(T, &str)])
        where
            T: Copy + PartialEq + std::fmt::Debug + std::str::FromStr,
            T::Err: std::fmt::Debug,
        {
            for &(v, texts) in spellings {
                for text in texts.split_whitespace() {
                    assert_eq!(text.parse::<T>().unwrap(), v, "{text}");
                }
            }
        }
        round_trip(&Laplacian::ALL, Laplacian::name);
        round_trip(&DescriptorKind::ALL, DescriptorKind::name);
        round_trip(&Convention::ALL, Convention::name);
        round_trip(&ZoomoutDirection::ALL, ZoomoutDirection::name);
        let names: Vec<&str> = Laplacian::ALL.iter().map(|l| l.name()).collect();
        assert_eq!(
            names,
            [
                "cot",
                "voronoi-cot",
                "fem",
                "mixed-voronoi",
                "uniform",
                "robust"
            ]
        );
        // Each value's other spellings, space-separated.
        reads_as(&[
            (
                Laplacian::VoronoiCot,
                "voronoi Voronoi_Cot barycentric lumped",
            ),
            (Laplacian::Fem, "linear-fem linear_fem wfem"),
            (Laplacian::MixedVoronoi, "mixed meyer"),
            (Laplacian::Uniform, "graph combinatorial"),
            (Laplacian::Robust, "tufted intrinsic-delaunay nonmanifold"),
        ]);
        reads_as(&[
            (Convention::Crane, "average"),
            (Convention::Potpourri3d, "geometry-central neumann"),
        ]);
        let refusals = [
            "Nope".parse::<Laplacian>().unwrap_err(),
            " Gauss".parse::<DescriptorKind>().unwrap_err(),
            "exact".parse::<Convention>().unwrap_err(),
            " Sideways ".parse::<ZoomoutDirection>().unwrap_err(),
        ];
        assert_eq!(
            refusals,
            [
                "unknown Laplacian 'Nope': expected one of cot, voronoi-cot, fem, mixed-voronoi, uniform, robust",
                "unknown descriptor ' Gauss': expected wks or hks",
                "unknown heat-method convention 'exact': expected crane or potpourri3d",
                "unknown ZoomOut direction 'sideways': use forward, reverse or both",
            ]
        );
    }
}
