//! The interfaces of the shutdown capability in their exact COM layout: IOPCShutdown (specification
//! section 4.2) and the standard connectable-object interfaces it is reached through (section 4.1).
//!
//! The four standard interfaces and CONNECTDATA carry `#[cfg(not(system_com_headers))]`: C programs
//! on Windows get them from <ocidl.h>, everywhere else from this library's header.

use core::ffi::c_void;

use crate::com::{IUnknown, DWORD, HRESULT, IID, LPCWSTR, REFIID, ULONG};

/// The methods of IOPCShutdown, in the order of the specification's IDL.
#[repr(C)]
#[allow(non_snake_case)]
pub struct IOPCShutdownVtbl {
    pub QueryInterface:
        unsafe extern "system" fn(This: *mut IOPCShutdown, riid: REFIID, ppvObject: *mut *mut c_void) -> HRESULT,
    pub AddRef: unsafe extern "system" fn(This: *mut IOPCShutdown) -> ULONG,
    pub Release: unsafe extern "system" fn(This: *mut IOPCShutdown) -> ULONG,
    pub ShutdownRequest: unsafe extern "system" fn(This: *mut IOPCShutdown, szReason: LPCWSTR) -> HRESULT,
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
    pub pUnk: *mut IUnknown,
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
    ) -> HRESULT,
    pub AddRef: unsafe extern "system" fn(This: *mut IConnectionPointContainer) -> ULONG,
    pub Release: unsafe extern "system" fn(This: *mut IConnectionPointContainer) -> ULONG,
    pub EnumConnectionPoints: unsafe extern "system" fn(
        This: *mut IConnectionPointContainer,
        ppEnum: *mut *mut IEnumConnectionPoints,
    ) -> HRESULT,
    pub FindConnectionPoint: unsafe extern "system" fn(
        This: *mut IConnectionPointContainer,
        riid: REFIID,
        ppCP: *mut *mut IConnectionPoint,
    ) -> HRESULT,
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
    pub QueryInterface: unsafe extern "system" fn(
        This: *mut IEnumConnectionPoints,
        riid: REFIID,
        ppvObject: *mut *mut c_void,
    ) -> HRESULT,
    pub AddRef: unsafe extern "system" fn(This: *mut IEnumConnectionPoints) -> ULONG,
    pub Release: unsafe extern "system" fn(This: *mut IEnumConnectionPoints) -> ULONG,
    pub Next: unsafe extern "system" fn(
        This: *mut IEnumConnectionPoints,
        cConnections: ULONG,
        ppCP: *mut *mut IConnectionPoint,
        pcFetched: *mut ULONG,
    ) -> HRESULT,
    pub Skip: unsafe extern "system" fn(This: *mut IEnumConnectionPoints, cConnections: ULONG) -> HRESULT,
    pub Reset: unsafe extern "system" fn(This: *mut IEnumConnectionPoints) -> HRESULT,
    pub Clone:
        unsafe extern "system" fn(This: *mut IEnumConnectionPoints, ppEnum: *mut *mut IEnumConnectionPoints) -> HRESULT,
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
        unsafe extern "system" fn(This: *mut IConnectionPoint, riid: REFIID, ppvObject: *mut *mut c_void) -> HRESULT,
    pub AddRef: unsafe extern "system" fn(This: *mut IConnectionPoint) -> ULONG,
    pub Release: unsafe extern "system" fn(This: *mut IConnectionPoint) -> ULONG,
    pub GetConnectionInterface: unsafe extern "system" fn(This: *mut IConnectionPoint, pIID: *mut IID) -> HRESULT,
    pub GetConnectionPointContainer:
        unsafe extern "system" fn(This: *mut IConnectionPoint, ppCPC: *mut *mut IConnectionPointContainer) -> HRESULT,
    pub Advise: unsafe extern "system" fn(
        This: *mut IConnectionPoint,
        pUnkSink: *mut IUnknown,
        pdwCookie: *mut DWORD,
    ) -> HRESULT,
    pub Unadvise: unsafe extern "system" fn(This: *mut IConnectionPoint, dwCookie: DWORD) -> HRESULT,
    pub EnumConnections:
        unsafe extern "system" fn(This: *mut IConnectionPoint, ppEnum: *mut *mut IEnumConnections) -> HRESULT,
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
        unsafe extern "system" fn(This: *mut IEnumConnections, riid: REFIID, ppvObject: *mut *mut c_void) -> HRESULT,
    pub AddRef: unsafe extern "system" fn(This: *mut IEnumConnections) -> ULONG,
    pub Release: unsafe extern "system" fn(This: *mut IEnumConnections) -> ULONG,
    pub Next: unsafe extern "system" fn(
        This: *mut IEnumConnections,
        cConnections: ULONG,
        rgcd: *mut CONNECTDATA,
        pcFetched: *mut ULONG,
    ) -> HRESULT,
    pub Skip: unsafe extern "system" fn(This: *mut IEnumConnections, cConnections: ULONG) -> HRESULT,
    pub Reset: unsafe extern "system" fn(This: *mut IEnumConnections) -> HRESULT,
    pub Clone: unsafe extern "system" fn(This: *mut IEnumConnections, ppEnum: *mut *mut IEnumConnections) -> HRESULT,
}

/// IEnumConnections: enumerates the connections of a connection point.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IEnumConnections {
    pub lpVtbl: *const IEnumConnectionsVtbl,
}
