//! The interfaces the EXE host keeps registered with the RPC runtime while it serves.
//!
//! COM registers an interface with the RPC runtime when a process first marshals it and unregisters
//! it when the last stub of that interface in the process goes, waiting for the calls on it to end
//! (`RpcServerUnregisterIf(..., WaitForCallsToComplete)`). Wine's runtime can lose that wait: the
//! thread that served a call sends the reply before it counts the call as ended, so a client that
//! releases its object as soon as the reply arrives can make the last stub go while the count still
//! holds the call; if the call's end then falls between the unregistration's look at the count and
//! its creating the event it waits on, nobody sets the event. The unregistration waits for good,
//! holding the lock every marshal of the process takes, and every later activation of the server
//! hangs. (Met in the reconnect test under load: clients that create, call once and release; made
//! to happen in seconds by `tests/oop/interfaces-kept.sh`, which checks this module's remedy.)
//!
//! The remedy: before the first client, the host marshals, table-strong, each interface a server on
//! the library is likely to hand out, from an object of its own (`com::kept`), and releases those
//! marshals after the last client has gone; so the last stub of such an interface never goes while
//! the host serves. Kept: the interfaces opccomn's proxy/stub serves (registered or not, each that
//! has a proxy/stub on the machine), and the system interfaces of connection points and enumerators.

use crate::com::guids::{
    IID_IConnectionPoint, IID_IConnectionPointContainer, IID_IEnumConnectionPoints, IID_IEnumConnections, IID_IEnumGUID,
};
use crate::com::kept::Keeper;
use crate::com::GUID;
use crate::proxy::layouts::{COUNT, PROXY_STUB_INTERFACES};

/// The system interfaces kept besides the proxy/stub's: those of connection points, and the
/// enumerators OPC interfaces hand out (IEnumGUID: IOPCServerList; IEnumString and IEnumUnknown:
/// IOPCServer::CreateGroupEnumerator, IOPCBrowseServerAddressSpace).
const SYSTEM_INTERFACES: [GUID; 7] = [
    IID_IConnectionPointContainer,
    IID_IConnectionPoint,
    IID_IEnumConnections,
    IID_IEnumConnectionPoints,
    IID_IEnumGUID,
    GUID::from_u128(0x00000101_0000_0000_C000_000000000046), // IEnumString
    GUID::from_u128(0x00000100_0000_0000_C000_000000000046), // IEnumUnknown
];

/// Every interface the host keeps.
static KEPT_INTERFACES: [GUID; COUNT + SYSTEM_INTERFACES.len()] = {
    let mut all = [SYSTEM_INTERFACES[0]; COUNT + SYSTEM_INTERFACES.len()];
    let mut i = 0;
    while i < COUNT {
        all[i] = PROXY_STUB_INTERFACES[i].0;
        i += 1;
    }
    while i < all.len() {
        all[i] = SYSTEM_INTERFACES[i - COUNT];
        i += 1;
    }
    all
};

/// The host's keeper.
pub(super) static KEEPER: Keeper = Keeper::new(&KEPT_INTERFACES);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::com::kept::KEEPER_METHODS;

    #[test]
    fn every_interface_of_the_proxy_stub_and_the_system_ones_are_kept() {
        for (iid, ..) in PROXY_STUB_INTERFACES.iter() {
            assert!(KEEPER.iids().contains(iid));
        }
        for iid in SYSTEM_INTERFACES.iter() {
            assert!(KEEPER.iids().contains(iid));
        }
        assert_eq!(KEEPER.iids().len(), COUNT + SYSTEM_INTERFACES.len());
    }

    #[test]
    fn the_keepers_table_is_longer_than_every_kept_interface() {
        for (iid, name, methods, _) in PROXY_STUB_INTERFACES.iter() {
            assert!(
                (*methods as usize) <= KEEPER_METHODS,
                "{name} {iid:?} has {methods} methods"
            );
        }
        // The system interfaces: IConnectionPoint has the most, 8.
        const { assert!(8 <= KEEPER_METHODS) };
    }
}
