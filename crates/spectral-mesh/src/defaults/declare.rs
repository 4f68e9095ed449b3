//! The macro that declares a parameter struct with its defaults (a file of its own: the
//! parameter structs it declares are read by `defaults/mod.rs`, which it must not import).

/// Declares a parameter struct with each field's default written beside it
/// (`pub k: usize = 60,`) and the `Default` that builds them: the field list is written
/// once instead of again in a `Default` impl. Attributes of the struct and of its fields
/// (documentation, derives, serde) pass through.
macro_rules! with_defaults {
    (
        $(#[$attr:meta])*
        $vis:vis struct $name:ident {
            $($(#[$field_attr:meta])* $field_vis:vis $field:ident: $ty:ty = $default:expr,)*
        }
    ) => {
        $(#[$attr])*
        $vis struct $name {
            $($(#[$field_attr])* $field_vis $field: $ty,)*
        }

        impl Default for $name {
            fn default() -> Self {
                Self {
                    $($field: $default,)*
                }
            }
        }
    };
}
pub(crate) use with_defaults;
