//! A configuration's contents as bytes, for a CRC that tells two builds'
//! configurations apart (`exogait_device::DeviceConfig::fingerprint`):
//! every field in declaration order, floats by their bits, integers
//! little-endian as 64 bits, `bool` as one byte, strings as their length
//! and bytes, `Option` as a tag and its value. The same on every target,
//! and without `core::fmt` (whose float formatting would put panic paths
//! into the firmware that prints it).
//!
//! Structs implement it with [`impl_fingerprint!`](crate::impl_fingerprint),
//! which destructures the whole struct: a field added and not fed is a
//! compile error.

/// Feeds a value's contents to `h`.
pub trait Fingerprint {
    /// Feeds `self` to `h` (see the module docs for the encoding).
    fn feed<H: FnMut(&[u8])>(&self, h: &mut H);
}

macro_rules! integers {
    ($($t:ty),*) => {$(
        impl Fingerprint for $t {
            fn feed<H: FnMut(&[u8])>(&self, h: &mut H) {
                h(&(*self as u64).to_le_bytes());
            }
        }
    )*};
}

integers!(u8, u16, u32, u64, usize, i8, i16, i32, i64);

impl Fingerprint for f32 {
    fn feed<H: FnMut(&[u8])>(&self, h: &mut H) {
        h(&self.to_bits().to_le_bytes());
    }
}

impl Fingerprint for f64 {
    fn feed<H: FnMut(&[u8])>(&self, h: &mut H) {
        h(&self.to_bits().to_le_bytes());
    }
}

impl Fingerprint for bool {
    fn feed<H: FnMut(&[u8])>(&self, h: &mut H) {
        h(&[u8::from(*self)]);
    }
}

impl Fingerprint for &str {
    fn feed<H: FnMut(&[u8])>(&self, h: &mut H) {
        self.len().feed(h);
        h(self.as_bytes());
    }
}

impl<T: Fingerprint, const N: usize> Fingerprint for [T; N] {
    fn feed<H: FnMut(&[u8])>(&self, h: &mut H) {
        for x in self {
            x.feed(h);
        }
    }
}

impl<T: Fingerprint> Fingerprint for Option<T> {
    fn feed<H: FnMut(&[u8])>(&self, h: &mut H) {
        match self {
            None => h(&[0]),
            Some(x) => {
                h(&[1]);
                x.feed(h);
            }
        }
    }
}

/// Implements [`Fingerprint`] for a struct by feeding the fields listed, in
/// that order; the list must name every field (the struct is destructured).
///
/// ```ignore
/// impl_fingerprint!(AngleRange { min_rad, max_rad });
/// impl_fingerprint!([T: Fingerprint] Link<T> { length_m, com_m, mass_kg, inertia_kgm2 });
/// ```
#[macro_export]
macro_rules! impl_fingerprint {
    ([$($generics:tt)*] $ty:ty { $($field:ident),* $(,)? }) => {
        impl<$($generics)*> $crate::fingerprint::Fingerprint for $ty {
            fn feed<H: FnMut(&[u8])>(&self, h: &mut H) {
                let Self { $($field),* } = self;
                $( $crate::fingerprint::Fingerprint::feed($field, h); )*
            }
        }
    };
    ($ty:ty { $($field:ident),* $(,)? }) => {
        $crate::impl_fingerprint!([] $ty { $($field),* });
    };
}

/// Implements [`Fingerprint`] for a field-less `Copy` enum by its
/// discriminant.
#[macro_export]
macro_rules! impl_fingerprint_enum {
    ($($ty:ty),* $(,)?) => {$(
        impl $crate::fingerprint::Fingerprint for $ty {
            fn feed<H: FnMut(&[u8])>(&self, h: &mut H) {
                $crate::fingerprint::Fingerprint::feed(&(*self as u8), h);
            }
        }
    )*};
}

use crate::anthropometry::{ExoSegment, ExoSegments};
use crate::model::{JointLimits, Link};

crate::impl_fingerprint!([T: Fingerprint] ExoSegment<T> { mass_kg, com_m, inertia_kgm2 });
crate::impl_fingerprint!([T: Fingerprint] ExoSegments<T> { torso, thigh, shank });

crate::impl_fingerprint!([T: Fingerprint] Link<T> { length_m, com_m, mass_kg, inertia_kgm2 });
crate::impl_fingerprint!([T: Fingerprint] JointLimits<T> {
    hip_flexion_rad,
    hip_extension_rad,
    knee_flexion_rad,
    knee_extension_rad,
    ankle_dorsiflexion_rad,
    ankle_plantarflexion_rad,
});
// `BodyModel`'s private fields: in `model`.
