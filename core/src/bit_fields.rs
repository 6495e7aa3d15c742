//! `bit_fields!`: the bit-field value type of a register, said once here and named per register
//! by the generated code (svd2rust's split: the generic part in the library, per register only
//! its masks). A generated module writes one invocation per bit-field register:
//!
//! ```
//! drivemap_core::bit_fields! {
//!     /// Bit fields of `Command`.
//!     pub struct CommandBits(mask 0x00F3, register "command");
//!     /// bit 0: Run.
//!     flag run, set_run, with_run = 0x0001;
//!     /// bit 1: Fault (read only: no setters).
//!     flag fault = 0x0002;
//!     /// bits 4..=7: Step.
//!     number step, set_step, with_step = 0x00F0 >> 4, max 15;
//! }
//! let mut c = CommandBits::new().with_run(true);
//! c.set_step(9).unwrap();
//! assert_eq!(c.raw(), 0x0091);
//! assert!(c.run() && !c.fault() && c.step() == 9);
//! assert!(c.set_step(16).is_err());
//! assert_eq!(format!("{c:?}"), "CommandBits { run: true, fault: false, step: 9 }");
//! ```
//!
//! A field is `flag` (one bit, `bool`), `number` (several bits, `u16`) or `code` (several bits
//! whose codes an enumeration lists: `code name: Type, … = mask >> lsb, max m;`); with setter
//! names it is writable (`set_*` in place, `with_*` by value), without them read only. The type
//! keeps reserved bits (outside `mask`) 0 and implements `Code`, `Bits` and a `Debug` listing
//! every field.

/// The bit-field type of a register; see [the module](mod@crate::bit_fields).
#[macro_export]
macro_rules! bit_fields {
    (
        $(#[$attr:meta])*
        pub struct $t:ident(mask $mask:literal, register $reg:literal);
        $($fields:tt)*
    ) => {
        $(#[$attr])*
        #[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
        pub struct $t(u16);

        impl $t {
            /// Bits that carry a field.
            pub const MASK: u16 = $mask;

            /// All fields 0.
            #[inline]
            pub const fn new() -> Self {
                Self(0)
            }

            /// The raw word (reserved bits 0).
            #[inline]
            pub const fn raw(&self) -> u16 {
                self.0
            }

            $crate::__bit_field_methods!($reg; $($fields)*);
        }

        impl $crate::register::Code for $t {
            #[inline]
            fn code(&self) -> u16 {
                self.0
            }
            #[inline]
            fn from_code(code: u16) -> Self {
                Self(code & Self::MASK)
            }
            #[inline]
            fn is_known(&self) -> bool {
                true
            }
        }

        impl $crate::register::Bits for $t {
            const MASK: u16 = $mask;
        }

        impl ::core::fmt::Debug for $t {
            fn fmt(&self, f: &mut ::core::fmt::Formatter<'_>) -> ::core::fmt::Result {
                let mut d = f.debug_struct(stringify!($t));
                $crate::__bit_field_debug!(self, d; $($fields)*);
                d.finish()
            }
        }
    };
}

/// The accessors of [`bit_fields!`]' fields, one field at a time.
#[doc(hidden)]
#[macro_export]
macro_rules! __bit_field_methods {
    ($reg:literal;) => {};
    ($reg:literal; $(#[$a:meta])* flag $get:ident = $m:literal; $($rest:tt)*) => {
        $(#[$a])*
        #[inline]
        pub const fn $get(&self) -> bool {
            self.0 & $m != 0
        }
        $crate::__bit_field_methods!($reg; $($rest)*);
    };
    ($reg:literal; $(#[$a:meta])* flag $get:ident, $set:ident, $with:ident = $m:literal; $($rest:tt)*) => {
        $crate::__bit_field_methods!($reg; $(#[$a])* flag $get = $m;);
        #[doc = concat!(" Sets `", stringify!($get), "`.")]
        #[inline]
        pub fn $set(&mut self, on: bool) -> &mut Self {
            if on {
                self.0 |= $m
            } else {
                self.0 &= !$m
            }
            self
        }
        #[doc = concat!(" This value with `", stringify!($get), "` set to `on`.")]
        #[inline]
        pub const fn $with(self, on: bool) -> Self {
            Self(if on { self.0 | $m } else { self.0 & !$m })
        }
        $crate::__bit_field_methods!($reg; $($rest)*);
    };
    ($reg:literal; $(#[$a:meta])* number $get:ident = $m:literal >> $lo:literal; $($rest:tt)*) => {
        $(#[$a])*
        #[inline]
        pub const fn $get(&self) -> u16 {
            (self.0 & $m) >> $lo
        }
        $crate::__bit_field_methods!($reg; $($rest)*);
    };
    (
        $reg:literal;
        $(#[$a:meta])* number $get:ident, $set:ident, $with:ident = $m:literal >> $lo:literal, max $max:literal;
        $($rest:tt)*
    ) => {
        $crate::__bit_field_methods!($reg; $(#[$a])* number $get = $m >> $lo;);
        #[doc = concat!(" Sets `", stringify!($get), "`; a value wider than the field is refused.")]
        #[inline]
        pub fn $set(&mut self, value: u16) -> Result<&mut Self, $crate::scale::ValueError> {
            if value > $max {
                return Err($crate::scale::ValueError::OutOfRange {
                    register: $reg,
                    value: value as f64,
                    min: 0.0,
                    max: $max as f64,
                    unit: "",
                });
            }
            self.0 = (self.0 & !$m) | (value << $lo);
            Ok(self)
        }
        #[doc = concat!(
            " This value with `", stringify!($get),
            "` set to `value`; a value wider than the field is refused."
        )]
        #[inline]
        pub fn $with(mut self, value: u16) -> Result<Self, $crate::scale::ValueError> {
            self.$set(value)?;
            Ok(self)
        }
        $crate::__bit_field_methods!($reg; $($rest)*);
    };
    ($reg:literal; $(#[$a:meta])* code $get:ident: $ety:ty = $m:literal >> $lo:literal; $($rest:tt)*) => {
        $(#[$a])*
        #[inline]
        pub fn $get(&self) -> $ety {
            <$ety as $crate::register::Code>::from_code((self.0 & $m) >> $lo)
        }
        $crate::__bit_field_methods!($reg; $($rest)*);
    };
    (
        $reg:literal;
        $(#[$a:meta])* code $get:ident: $ety:ty, $set:ident, $with:ident = $m:literal >> $lo:literal, max $max:literal;
        $($rest:tt)*
    ) => {
        $crate::__bit_field_methods!($reg; $(#[$a])* code $get: $ety = $m >> $lo;);
        #[doc = concat!(" Sets `", stringify!($get), "`; an unknown or too wide code is refused.")]
        #[inline]
        pub fn $set(&mut self, value: $ety) -> Result<&mut Self, $crate::scale::ValueError> {
            let code = $crate::register::Code::code(&value);
            if !$crate::register::Code::is_known(&value) || code > $max {
                return Err($crate::scale::ValueError::UnknownCode { register: $reg, code });
            }
            self.0 = (self.0 & !$m) | (code << $lo);
            Ok(self)
        }
        #[doc = concat!(
            " This value with `", stringify!($get),
            "` set to `value`; an unknown or too wide code is refused."
        )]
        #[inline]
        pub fn $with(mut self, value: $ety) -> Result<Self, $crate::scale::ValueError> {
            self.$set(value)?;
            Ok(self)
        }
        $crate::__bit_field_methods!($reg; $($rest)*);
    };
}

/// The `Debug` fields of [`bit_fields!`]: every field by its getter, in order.
#[doc(hidden)]
#[macro_export]
macro_rules! __bit_field_debug {
    ($s:ident, $d:ident;) => {};
    (
        $s:ident, $d:ident;
        $(#[$a:meta])* $kind:ident $get:ident $(: $ety:ty)? $(, $set:ident, $with:ident)?
            = $m:literal $(>> $lo:literal)? $(, max $max:literal)?;
        $($rest:tt)*
    ) => {
        $d.field(stringify!($get), &$s.$get());
        $crate::__bit_field_debug!($s, $d; $($rest)*);
    };
}
