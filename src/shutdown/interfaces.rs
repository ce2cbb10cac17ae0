//! The interfaces of the shutdown capability in their exact COM layout: IOPCShutdown (specification
//! section 4.2) and the standard connectable-object interfaces it is reached through (section 4.1).
//!
//! The four standard interfaces and CONNECTDATA carry `#[cfg(not(system_com_headers))]`: C programs
//! on Windows get them from <ocidl.h>, everywhere else from this library's header.

use crate::com::ffi::{Crossed, Hr};
use core::ffi::c_void;

use crate::com::{IUnknown, DWORD, IID, LPCWSTR, REFIID, ULONG};

/// The methods of IOPCShutdown, in the order of the specification's IDL.
#[repr(C)]
#[allow(non_snake_case)]
pub struct IOPCShutdownVtbl {
    pub QueryInterface:
        unsafe extern "system" fn(This: *mut IOPCShutdown, riid: REFIID, ppvObject: *mut *mut c_void) -> Hr,
    pub AddRef: unsafe extern "system" fn(This: *mut IOPCShutdown) -> Crossed<ULONG>,
    pub Release: unsafe extern "system" fn(This: *mut IOPCShutdown) -> Crossed<ULONG>,
    pub ShutdownRequest: unsafe extern "system" fn(This: *mut IOPCShutdown, szReason: LPCWSTR) -> Hr,
}

/// IOPCShutdown: implemented by a client, called by a server that is about to shut down.
#[repr(C)]
#[allow(non_snake_case)]
pub struct IOPCShutdown {
    pub lpVtbl: *const IOPCShutdownVtbl,
}

/// One connection of a connection point: the sink and the cookie Advise returned for it.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
#[derive(Clone, Copy)]
pub struct CONNECTDATA {
    /// The connected sink (AddRef'ed for whoever received it from IEnumConnections::Next).
    pub pUnk: *mut IUnknown,
    /// The cookie IConnectionPoint::Advise returned for the sink.
    pub dwCookie: DWORD,
}

/// The methods of IConnectionPointContainer.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IConnectionPointContainerVtbl {
    pub QueryInterface: unsafe extern "system" fn(
        This: *mut IConnectionPointContainer,
        riid: REFIID,
        ppvObject: *mut *mut c_void,
    ) -> Hr,
    pub AddRef: unsafe extern "system" fn(This: *mut IConnectionPointContainer) -> Crossed<ULONG>,
    pub Release: unsafe extern "system" fn(This: *mut IConnectionPointContainer) -> Crossed<ULONG>,
    pub EnumConnectionPoints:
        unsafe extern "system" fn(This: *mut IConnectionPointContainer, ppEnum: *mut *mut IEnumConnectionPoints) -> Hr,
    pub FindConnectionPoint: unsafe extern "system" fn(
        This: *mut IConnectionPointContainer,
        riid: REFIID,
        ppCP: *mut *mut IConnectionPoint,
    ) -> Hr,
}

/// IConnectionPointContainer: the object that has connection points.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IConnectionPointContainer {
    pub lpVtbl: *const IConnectionPointContainerVtbl,
}

/// The methods of IEnumConnectionPoints.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IEnumConnectionPointsVtbl {
    pub QueryInterface:
        unsafe extern "system" fn(This: *mut IEnumConnectionPoints, riid: REFIID, ppvObject: *mut *mut c_void) -> Hr,
    pub AddRef: unsafe extern "system" fn(This: *mut IEnumConnectionPoints) -> Crossed<ULONG>,
    pub Release: unsafe extern "system" fn(This: *mut IEnumConnectionPoints) -> Crossed<ULONG>,
    pub Next: unsafe extern "system" fn(
        This: *mut IEnumConnectionPoints,
        cConnections: ULONG,
        ppCP: *mut *mut IConnectionPoint,
        pcFetched: *mut ULONG,
    ) -> Hr,
    pub Skip: unsafe extern "system" fn(This: *mut IEnumConnectionPoints, cConnections: ULONG) -> Hr,
    pub Reset: unsafe extern "system" fn(This: *mut IEnumConnectionPoints) -> Hr,
    pub Clone:
        unsafe extern "system" fn(This: *mut IEnumConnectionPoints, ppEnum: *mut *mut IEnumConnectionPoints) -> Hr,
}

/// IEnumConnectionPoints: enumerates the connection points of a container.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IEnumConnectionPoints {
    pub lpVtbl: *const IEnumConnectionPointsVtbl,
}

/// The methods of IConnectionPoint.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IConnectionPointVtbl {
    pub QueryInterface:
        unsafe extern "system" fn(This: *mut IConnectionPoint, riid: REFIID, ppvObject: *mut *mut c_void) -> Hr,
    pub AddRef: unsafe extern "system" fn(This: *mut IConnectionPoint) -> Crossed<ULONG>,
    pub Release: unsafe extern "system" fn(This: *mut IConnectionPoint) -> Crossed<ULONG>,
    pub GetConnectionInterface: unsafe extern "system" fn(This: *mut IConnectionPoint, pIID: *mut IID) -> Hr,
    pub GetConnectionPointContainer:
        unsafe extern "system" fn(This: *mut IConnectionPoint, ppCPC: *mut *mut IConnectionPointContainer) -> Hr,
    pub Advise:
        unsafe extern "system" fn(This: *mut IConnectionPoint, pUnkSink: *mut IUnknown, pdwCookie: *mut DWORD) -> Hr,
    pub Unadvise: unsafe extern "system" fn(This: *mut IConnectionPoint, dwCookie: DWORD) -> Hr,
    pub EnumConnections:
        unsafe extern "system" fn(This: *mut IConnectionPoint, ppEnum: *mut *mut IEnumConnections) -> Hr,
}

/// IConnectionPoint: one outgoing interface of a container, to which sinks are advised.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IConnectionPoint {
    pub lpVtbl: *const IConnectionPointVtbl,
}

/// The methods of IEnumConnections.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IEnumConnectionsVtbl {
    pub QueryInterface:
        unsafe extern "system" fn(This: *mut IEnumConnections, riid: REFIID, ppvObject: *mut *mut c_void) -> Hr,
    pub AddRef: unsafe extern "system" fn(This: *mut IEnumConnections) -> Crossed<ULONG>,
    pub Release: unsafe extern "system" fn(This: *mut IEnumConnections) -> Crossed<ULONG>,
    pub Next: unsafe extern "system" fn(
        This: *mut IEnumConnections,
        cConnections: ULONG,
        rgcd: *mut CONNECTDATA,
        pcFetched: *mut ULONG,
    ) -> Hr,
    pub Skip: unsafe extern "system" fn(This: *mut IEnumConnections, cConnections: ULONG) -> Hr,
    pub Reset: unsafe extern "system" fn(This: *mut IEnumConnections) -> Hr,
    pub Clone: unsafe extern "system" fn(This: *mut IEnumConnections, ppEnum: *mut *mut IEnumConnections) -> Hr,
}

/// IEnumConnections: enumerates the connections of a connection point.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IEnumConnections {
    pub lpVtbl: *const IEnumConnectionsVtbl,
}
