//! Pairs of colliders, kept from run to run: the [`PairTable`] and the [`Collisions`] system
//! parameter that reads it.
mod collisions;
mod table;

pub use collisions::{Collisions, PairView};
pub use table::PairTable;
pub(crate) use table::{PairEnds, PairSlot, Record};
