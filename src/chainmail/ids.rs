//! Typed indices: an id is only meaningful for the lattice that issued it.

use serde::{Deserialize, Serialize};

macro_rules! typed_id {
    ($(#[$doc:meta])* $name:ident($inner:ty)) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize)]
        pub struct $name(pub $inner);

        impl $name {
            /// The id as an index into the per-item arrays.
            #[inline]
            pub fn index(self) -> usize {
                self.0 as usize
            }
        }
    };
}

typed_id!(
    /// An element (a point of the lattice).
    ElementId(u32)
);
typed_id!(
    /// A link between two elements.
    LinkId(u32)
);
typed_id!(
    /// A material in a body's material table.
    MaterialId(u16)
);
