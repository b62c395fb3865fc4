//! The one logging macro set: `defmt` on the target (feature `defmt`), nothing elsewhere.

#[cfg(feature = "defmt")]
macro_rules! info { ($($t:tt)*) => { defmt::info!($($t)*) } }
#[cfg(not(feature = "defmt"))]
macro_rules! info {
    ($($t:tt)*) => {{}};
}
#[cfg(feature = "defmt")]
macro_rules! warning { ($($t:tt)*) => { defmt::warn!($($t)*) } }
#[cfg(not(feature = "defmt"))]
macro_rules! warning {
    ($($t:tt)*) => {{}};
}

pub(crate) use {info, warning};
