//! The macro that declares the tracker's parameters once, grouped by concept, and derives from that one
//! declaration both the nested structs the tracker reads and the flat key table that a TOML `[tracker.parameters]`
//! table or a `track --params` file writes (its keys keep their names; a key's group is not part of it).

/// Declares `$top` with one field per group (a struct of that group's parameters, each with its default) and one
/// per sub-table, and `$flat`: every group's parameters as one flat serde/schemars struct with the same doc
/// comments, followed by the sub-tables. `$top` (de)serialises and describes itself through `$flat`, so unknown
/// keys, wrong types and their line numbers are reported exactly as the flat struct's derive reports them.
macro_rules! grouped_parameters {
    (
        $(#[$top_meta:meta])*
        pub struct $top:ident;
        $(#[$flat_meta:meta])*
        pub struct $flat:ident;
        groups {
            $(
                $(#[$group_meta:meta])*
                $group:ident: $group_ty:ident {
                    $(
                        $(#[$field_meta:meta])*
                        $field:ident: $field_ty:ty = $default:expr,
                    )*
                }
            )*
        }
        tables {
            $(
                $(#[$table_meta:meta])*
                $table:ident: $table_ty:ty,
            )*
        }
    ) => {
        $(
            $(#[$group_meta])*
            #[derive(Debug, Clone, PartialEq)]
            pub struct $group_ty {
                $(
                    $(#[$field_meta])*
                    pub $field: $field_ty,
                )*
            }

            impl Default for $group_ty {
                fn default() -> Self {
                    Self { $($field: $default,)* }
                }
            }
        )*

        $(#[$top_meta])*
        #[derive(Debug, Clone, PartialEq, Default)]
        pub struct $top {
            $(
                $(#[$group_meta])*
                pub $group: $group_ty,
            )*
            $(
                $(#[$table_meta])*
                pub $table: $table_ty,
            )*
        }

        $(#[$flat_meta])*
        #[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
        #[serde(deny_unknown_fields, default)]
        pub struct $flat {
            $($(
                $(#[$field_meta])*
                pub $field: $field_ty,
            )*)*
            $(
                $(#[$table_meta])*
                pub $table: $table_ty,
            )*
        }

        impl Default for $flat {
            fn default() -> Self {
                Self::from($top::default())
            }
        }

        impl From<$top> for $flat {
            fn from(nested: $top) -> Self {
                Self {
                    $($($field: nested.$group.$field,)*)*
                    $($table: nested.$table,)*
                }
            }
        }

        impl From<$flat> for $top {
            fn from(flat: $flat) -> Self {
                Self {
                    $($group: $group_ty { $($field: flat.$field,)* },)*
                    $($table: flat.$table,)*
                }
            }
        }

        impl serde::Serialize for $top {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                $flat::from(self.clone()).serialize(serializer)
            }
        }

        impl<'de> serde::Deserialize<'de> for $top {
            fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                $flat::deserialize(deserializer).map(Self::from)
            }
        }

        impl schemars::JsonSchema for $top {
            fn schema_name() -> std::borrow::Cow<'static, str> {
                <$flat as schemars::JsonSchema>::schema_name()
            }

            fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
                <$flat as schemars::JsonSchema>::json_schema(generator)
            }
        }
    };
}
