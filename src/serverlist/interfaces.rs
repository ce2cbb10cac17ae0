//! The enumerator interface EnumClassesOfCategories returns: IOPCEnumGUID (OPC Common 1.10), which has
//! the layout of the system's IEnumGUID; the library's enumerator (`com::enumerator`) answers
//! QueryInterface for both. Generated from the IDL (`src/com/interfaces.rs`).

pub use crate::com::interfaces::{IEnumGUID, IEnumGUIDVtbl, IOPCEnumGUID, IOPCEnumGUIDVtbl};
