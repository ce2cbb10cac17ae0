//! The interfaces of the shutdown capability: IOPCShutdown (specification section 4.2) and the standard
//! connectable-object interfaces it is reached through (section 4.1), generated from the IDL
//! (`src/com/interfaces.rs`).

pub use crate::com::interfaces::{
    IConnectionPoint, IConnectionPointContainer, IConnectionPointContainerVtbl, IConnectionPointVtbl,
    IEnumConnectionPoints, IEnumConnectionPointsVtbl, IEnumConnections, IEnumConnectionsVtbl, IOPCShutdown,
    IOPCShutdownVtbl,
};
pub use crate::com::CONNECTDATA;
