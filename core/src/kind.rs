//! [`ConversionKind`]: the kinds of [`Conversion`] as a plain list, for the tools that must
//! show every kind (the facts view of `drivemap-map`, and `tests/tests/cross_crate/scale_kinds.rs`, which
//! fails when a printer leaves a kind out).
//!
//! The enum and [`ConversionKind::ALL`] are written by one macro from one list, so `ALL` cannot
//! miss a kind; [`ConversionKind::of`] matches [`Conversion`] exhaustively, so a new
//! `Conversion` variant does not compile until it has a kind here.

use crate::plan::Conversion;

macro_rules! kinds {
    ($($(#[$doc:meta])* $kind:ident => $name:literal,)*) => {
        /// The kind of a register's [`Conversion`], without its data.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum ConversionKind {
            $($(#[$doc])* $kind,)*
        }

        impl ConversionKind {
            /// Every kind, in declaration order.
            pub const ALL: &'static [ConversionKind] = &[$(ConversionKind::$kind,)*];

            /// The name of its [`Conversion`] variant (`Decimal`), as generated code prints it.
            pub const fn variant(self) -> &'static str {
                match self {
                    $(ConversionKind::$kind => stringify!($kind),)*
                }
            }

            /// The kind's name in the facts view (`decimal`).
            pub const fn name(self) -> &'static str {
                match self {
                    $(ConversionKind::$kind => $name,)*
                }
            }
        }
    };
}

kinds! {
    /// [`Conversion::Word`]: a plain word.
    Word => "word",
    /// [`Conversion::Decimal`]: raw × a decimal factor.
    Decimal => "decimal",
    /// [`Conversion::Relative`]: `full_scale` raw = 100 % of a reference.
    Relative => "relative",
    /// [`Conversion::Ratio`]: `counts` raw = `equals`, exactly ("60.0 Hz = 3600").
    Ratio => "ratio",
    /// [`Conversion::Selected`]: the scale a parameter's code chooses.
    Selected => "selected",
    /// [`Conversion::Enum`]: codes with meanings.
    Enum => "enum",
    /// [`Conversion::Bits`]: bit fields.
    Bits => "bits",
    /// [`Conversion::Text`]: text, two characters per register.
    Text => "text",
}

impl ConversionKind {
    /// The kind of a conversion.
    pub const fn of(c: &Conversion) -> ConversionKind {
        match c {
            Conversion::Word { .. } => ConversionKind::Word,
            Conversion::Decimal { .. } => ConversionKind::Decimal,
            Conversion::Relative { .. } => ConversionKind::Relative,
            Conversion::Ratio { .. } => ConversionKind::Ratio,
            Conversion::Selected { .. } => ConversionKind::Selected,
            Conversion::Enum { .. } => ConversionKind::Enum,
            Conversion::Bits { .. } => ConversionKind::Bits,
            Conversion::Text { .. } => ConversionKind::Text,
        }
    }

    /// Whether the kind scales a word to an engineering value (a *scale kind*: decimal,
    /// relative, ratio, selected), as opposed to a plain word, codes or bits.
    pub const fn is_scale(self) -> bool {
        match self {
            ConversionKind::Decimal
            | ConversionKind::Relative
            | ConversionKind::Ratio
            | ConversionKind::Selected => true,
            ConversionKind::Word
            | ConversionKind::Enum
            | ConversionKind::Bits
            | ConversionKind::Text => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ConversionKind;

    #[test]
    fn every_kind_is_listed_once_with_its_own_name() {
        for (i, k) in ConversionKind::ALL.iter().enumerate() {
            assert!(
                ConversionKind::ALL[i + 1..]
                    .iter()
                    .all(|o| o != k && o.name() != k.name()),
                "{k:?} twice"
            );
        }
    }
}
