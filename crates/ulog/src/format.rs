//! ULog message formats declared from Rust types.
//!
//! A ULog data message is the packed little-endian concatenation of its
//! fields in declaration order (no implicit alignment). Every top-level
//! format starts with `uint64_t timestamp` (µs). The [`ulog_message!`] macro
//! declares a plain Rust struct and its [`Record`] implementation: the
//! field list (name, ULog type, array length), the encoded size and the
//! allocation-free encoder and decoder.
//!
//! Padding: when a record's size is not a multiple of 8 bytes, its format
//! string ends with a `uint8_t[n] _padding0` field that rounds it up, as
//! PX4's generated formats do. By the specification a trailing padding field
//! is not logged (data messages are `n` bytes shorter); it only matters when
//! the type is nested in another one. Readers skip fields named `_padding…`.
//!
//! [`ulog_message!`]: crate::ulog_message

use std::fmt::Write as _;

/// The ULog base types (all little-endian).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum UlogType {
    /// `int8_t`
    Int8,
    /// `uint8_t`
    UInt8,
    /// `int16_t`
    Int16,
    /// `uint16_t`
    UInt16,
    /// `int32_t`
    Int32,
    /// `uint32_t`
    UInt32,
    /// `int64_t`
    Int64,
    /// `uint64_t`
    UInt64,
    /// `float` (IEEE 754 binary32)
    Float,
    /// `double` (IEEE 754 binary64)
    Double,
    /// `bool` (one byte, 0 or 1)
    Bool,
    /// `char` (one byte)
    Char,
}

impl UlogType {
    /// Every base type.
    pub const ALL: [UlogType; 12] = [
        UlogType::Int8,
        UlogType::UInt8,
        UlogType::Int16,
        UlogType::UInt16,
        UlogType::Int32,
        UlogType::UInt32,
        UlogType::Int64,
        UlogType::UInt64,
        UlogType::Float,
        UlogType::Double,
        UlogType::Bool,
        UlogType::Char,
    ];

    /// The C name used in format strings (`uint64_t`, `float`, …).
    pub const fn name(self) -> &'static str {
        match self {
            UlogType::Int8 => "int8_t",
            UlogType::UInt8 => "uint8_t",
            UlogType::Int16 => "int16_t",
            UlogType::UInt16 => "uint16_t",
            UlogType::Int32 => "int32_t",
            UlogType::UInt32 => "uint32_t",
            UlogType::Int64 => "int64_t",
            UlogType::UInt64 => "uint64_t",
            UlogType::Float => "float",
            UlogType::Double => "double",
            UlogType::Bool => "bool",
            UlogType::Char => "char",
        }
    }

    /// Size in bytes.
    pub const fn size(self) -> usize {
        match self {
            UlogType::Int8 | UlogType::UInt8 | UlogType::Bool | UlogType::Char => 1,
            UlogType::Int16 | UlogType::UInt16 => 2,
            UlogType::Int32 | UlogType::UInt32 | UlogType::Float => 4,
            UlogType::Int64 | UlogType::UInt64 | UlogType::Double => 8,
        }
    }

    /// The base type of a C name, if it is one.
    pub fn from_name(name: &str) -> Option<UlogType> {
        UlogType::ALL.into_iter().find(|t| t.name() == name)
    }
}

/// A Rust value that is one ULog field: a base type or a fixed-size array
/// of one.
pub trait UlogValue: Copy + Default {
    /// The base type.
    const TYPE: UlogType;
    /// `Some(n)` for an array of `n`, `None` for a scalar.
    const ARRAY_LEN: Option<usize>;
    /// Encoded size in bytes.
    const SIZE: usize;
    /// Write the value into `out[..Self::SIZE]` (little-endian); nothing is
    /// written when `out` is shorter.
    fn put(&self, out: &mut [u8]);
    /// Read the value from `bytes[..Self::SIZE]`; the default value when
    /// `bytes` is shorter.
    fn get(bytes: &[u8]) -> Self;
}

macro_rules! scalar_value {
    ($($t:ty => $ulog:ident),* $(,)?) => {$(
        impl UlogValue for $t {
            const TYPE: UlogType = UlogType::$ulog;
            const ARRAY_LEN: Option<usize> = None;
            const SIZE: usize = std::mem::size_of::<$t>();
            fn put(&self, out: &mut [u8]) {
                if let Some(o) = out.get_mut(..Self::SIZE) {
                    o.copy_from_slice(&self.to_le_bytes());
                }
            }
            fn get(bytes: &[u8]) -> Self {
                let mut b = [0u8; std::mem::size_of::<$t>()];
                if let Some(s) = bytes.get(..Self::SIZE) {
                    b.copy_from_slice(s);
                }
                <$t>::from_le_bytes(b)
            }
        }
    )*};
}

scalar_value!(
    i8 => Int8, u8 => UInt8, i16 => Int16, u16 => UInt16, i32 => Int32, u32 => UInt32,
    i64 => Int64, u64 => UInt64, f32 => Float, f64 => Double,
);

impl UlogValue for bool {
    const TYPE: UlogType = UlogType::Bool;
    const ARRAY_LEN: Option<usize> = None;
    const SIZE: usize = 1;
    fn put(&self, out: &mut [u8]) {
        if let Some(o) = out.first_mut() {
            *o = u8::from(*self);
        }
    }
    fn get(bytes: &[u8]) -> Self {
        bytes.first().is_some_and(|b| *b != 0)
    }
}

/// Marker for the scalar values (arrays of arrays are not ULog types).
pub trait UlogScalar: UlogValue {}
impl UlogScalar for i8 {}
impl UlogScalar for u8 {}
impl UlogScalar for i16 {}
impl UlogScalar for u16 {}
impl UlogScalar for i32 {}
impl UlogScalar for u32 {}
impl UlogScalar for i64 {}
impl UlogScalar for u64 {}
impl UlogScalar for f32 {}
impl UlogScalar for f64 {}
impl UlogScalar for bool {}

impl<T: UlogScalar, const N: usize> UlogValue for [T; N]
where
    [T; N]: Default,
{
    const TYPE: UlogType = T::TYPE;
    const ARRAY_LEN: Option<usize> = Some(N);
    const SIZE: usize = T::SIZE * N;
    fn put(&self, out: &mut [u8]) {
        if out.len() < Self::SIZE {
            return;
        }
        for (v, chunk) in self.iter().zip(out.chunks_exact_mut(T::SIZE)) {
            v.put(chunk);
        }
    }
    fn get(bytes: &[u8]) -> Self {
        let mut a = <[T; N]>::default();
        if bytes.len() < Self::SIZE {
            return a;
        }
        for (v, chunk) in a.iter_mut().zip(bytes.chunks_exact(T::SIZE)) {
            *v = T::get(chunk);
        }
        a
    }
}

/// One field of a declared format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldDef {
    /// Field name (`timestamp`, `command`, …).
    pub name: &'static str,
    /// Base type.
    pub ty: UlogType,
    /// Array length, `None` for a scalar.
    pub array_len: Option<usize>,
}

impl FieldDef {
    /// The field of a Rust value type.
    pub const fn of<T: UlogValue>(name: &'static str) -> FieldDef {
        FieldDef {
            name,
            ty: T::TYPE,
            array_len: T::ARRAY_LEN,
        }
    }

    /// Encoded size in bytes.
    pub const fn size(&self) -> usize {
        match self.array_len {
            Some(n) => self.ty.size() * n,
            None => self.ty.size(),
        }
    }
}

/// A message format declared in Rust: a ULog topic with a fixed layout.
/// Implemented by [`ulog_message!`](crate::ulog_message); the first field is
/// always `uint64_t timestamp` (µs).
pub trait Record: Sized {
    /// The ULog message (topic) name, `[a-z0-9_]`.
    const NAME: &'static str;
    /// The fields in order, `timestamp` first.
    const FIELDS: &'static [FieldDef];
    /// Encoded (logged) size in bytes: the sum of the fields' sizes.
    const SIZE: usize;
    /// The record's timestamp (µs).
    fn timestamp_us(&self) -> u64;
    /// Encode the record into `out[..Self::SIZE]`. Returns the number of
    /// bytes written, or `None` when `out` is too short. Never allocates.
    fn encode(&self, out: &mut [u8]) -> Option<usize>;
    /// Decode a record from the first `Self::SIZE` bytes of `bytes`, `None`
    /// when too short.
    fn decode(bytes: &[u8]) -> Option<Self>;
}

/// Bytes of trailing padding that round a record of `size` bytes up to a
/// multiple of 8 (declared in the format, not logged).
pub const fn trailing_padding(size: usize) -> usize {
    (8 - size % 8) % 8
}

/// The ULog format string of a record type:
/// `name:uint64_t timestamp;double[4] command;…;uint8_t[n] _padding0;`.
pub fn format_string<R: Record>() -> String {
    format_string_of(R::NAME, R::FIELDS)
}

/// The ULog format string of a message name and its fields, with the
/// trailing padding to a multiple of 8 bytes.
pub fn format_string_of(name: &str, fields: &[FieldDef]) -> String {
    let mut s = String::with_capacity(32 + 24 * fields.len());
    s.push_str(name);
    s.push(':');
    let mut size = 0;
    for f in fields {
        // Writing into a String cannot fail.
        let _ = match f.array_len {
            Some(n) => write!(s, "{}[{}] {};", f.ty.name(), n, f.name),
            None => write!(s, "{} {};", f.ty.name(), f.name),
        };
        size += f.size();
    }
    let pad = trailing_padding(size);
    if pad > 0 {
        let _ = write!(s, "uint8_t[{pad}] _padding0;");
    }
    s
}

/// Declare a ULog record type: a struct whose first field is
/// `timestamp: u64` (µs) and whose other fields are [`UlogValue`]s (numbers,
/// `bool`, fixed-size arrays of them). Generates the struct (with `Debug,
/// Clone, Copy, PartialEq, Default`) and its [`Record`] implementation.
///
/// ```
/// helicon_ulog::ulog_message! {
///     /// A test topic.
///     pub struct Example: "example" {
///         /// Time (µs).
///         timestamp: u64,
///         /// A vector.
///         v: [f32; 3],
///         /// A flag.
///         ok: bool,
///     }
/// }
/// use helicon_ulog::Record;
/// assert_eq!(Example::SIZE, 8 + 12 + 1);
/// assert_eq!(
///     helicon_ulog::format::format_string::<Example>(),
///     "example:uint64_t timestamp;float[3] v;bool ok;uint8_t[3] _padding0;"
/// );
/// ```
#[macro_export]
macro_rules! ulog_message {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident : $topic:literal {
            $(#[$tsmeta:meta])*
            timestamp: u64
            $(, $(#[$fmeta:meta])* $field:ident : $fty:ty )* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        $vis struct $name {
            $(#[$tsmeta])*
            pub timestamp: u64,
            $( $(#[$fmeta])* pub $field: $fty, )*
        }

        impl $crate::format::Record for $name {
            const NAME: &'static str = $topic;
            const FIELDS: &'static [$crate::format::FieldDef] = &[
                $crate::format::FieldDef::of::<u64>("timestamp"),
                $( $crate::format::FieldDef::of::<$fty>(stringify!($field)), )*
            ];
            const SIZE: usize = 8 $( + <$fty as $crate::format::UlogValue>::SIZE )*;

            fn timestamp_us(&self) -> u64 {
                self.timestamp
            }

            fn encode(&self, out: &mut [u8]) -> Option<usize> {
                use $crate::format::UlogValue as _;
                let out = out.get_mut(..<Self as $crate::format::Record>::SIZE)?;
                self.timestamp.put(&mut out[..8]);
                #[allow(unused_mut)]
                let mut at = 8;
                $(
                    let n = <$fty as $crate::format::UlogValue>::SIZE;
                    self.$field.put(&mut out[at..at + n]);
                    at += n;
                )*
                Some(at)
            }

            #[allow(unused_assignments)] // the last field's offset advance
            fn decode(bytes: &[u8]) -> Option<Self> {
                let bytes = bytes.get(..<Self as $crate::format::Record>::SIZE)?;
                let timestamp = <u64 as $crate::format::UlogValue>::get(&bytes[..8]);
                #[allow(unused_mut, unused_variables)]
                let mut at = 8;
                $(
                    let n = <$fty as $crate::format::UlogValue>::SIZE;
                    let $field = <$fty as $crate::format::UlogValue>::get(&bytes[at..at + n]);
                    at += n;
                )*
                Some($name { timestamp $(, $field)* })
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn type_names_round_trip() {
        for t in UlogType::ALL {
            assert_eq!(UlogType::from_name(t.name()), Some(t));
        }
        assert_eq!(UlogType::from_name("float32"), None);
    }

    #[test]
    fn short_buffers_neither_panic_nor_write() {
        let mut out = [7u8; 3];
        1.5f64.put(&mut out);
        [1u16, 2, 3].put(&mut out);
        true.put(&mut []);
        assert_eq!(out, [7, 7, 7]);
        assert_eq!(f64::get(&[1, 2]), 0.0);
        assert!(!bool::get(&[]));
        assert_eq!(<[u32; 2]>::get(&[1, 0, 0, 0, 9]), [0, 0]);
        assert_eq!(<[u32; 2]>::get(&[1, 0, 0, 0, 2, 0, 0, 0]), [1, 2]);
        assert_eq!(2.5f32.to_le_bytes(), {
            let mut b = [0; 4];
            2.5f32.put(&mut b);
            b
        });
    }

    #[test]
    fn padding_rounds_to_eight() {
        assert_eq!(trailing_padding(8), 0);
        assert_eq!(trailing_padding(9), 7);
        assert_eq!(trailing_padding(15), 1);
    }
}
