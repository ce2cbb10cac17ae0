//! opccomn: the OPC Common Definitions and Interfaces (OPC Common 1.0 and 1.10) as a library with a
//! C ABI, so OPC servers and clients written in C or C++ can link one tested implementation of
//! IOPCCommon and the error texts instead of writing their own.
//!
//! Layout, by specification chapter:
//! - `com`: the COM core (types, IUnknown, reference counting, aggregation, the snapshot enumerator,
//!   allocator, the FFI boundary)
//! - `locale`: locale identifiers and how they resolve, shared by `common` and `errors`
//! - `common`: IOPCCommon (chapter 5)
//! - `errors`: the error text catalog behind GetErrorString (chapter 5.1.4)
//! - `shutdown`: the IOPCShutdown connection point for servers and a shutdown sink for clients (chapter 4)
//! - `registry`: the registry abstraction and the registration helpers (chapter 6)
//! - `serverlist`: the server browser OPCServerList (chapter 7)
//! - `server`: a server's COM plumbing (class objects, the server count, the `Dll*` module functions
//!   over a class table, the EXE host), which servers built on the library use
//! - `module`: opccomn's own class table (OPCServerList) and its `Dll*` entry points, over `server`'s
//!   module functions
//! - `security`: DCOM process security and proxy blankets, hardened for KB5004442
//! - `proxy`: opccomn.dll as the proxy/stub of the five OPC Common interfaces, and its registration
//!
//! The C API is declared in `include/opccomn/opccomn.h`, generated from these sources (cbindgen) and the IDL in `idl/` by tools/gen-header.

#![allow(non_snake_case)] // COM and OPC names are kept as the specification spells them

pub mod com;
pub mod common;
pub mod errors;
pub mod locale;
pub mod pattern;
pub mod proxy;
pub mod registry;
pub mod security;
pub mod server;
pub mod serverlist;
// After `serverlist`: the header declares the modules' functions in this order.
pub mod module;
pub mod shutdown;

#[cfg(test)]
mod stress_tests;
#[cfg(test)]
mod struct_size_table;

/// How many COM objects created by the library are still alive (IOPCCommon sessions, shutdown
/// connection points, enumerators, ...). Meant for leak checks in tests.
///
/// # Returns
/// The number of the library's objects not yet freed, in the whole process.
#[no_mangle]
pub extern "C" fn OpcObjectCount() -> com::ffi::Crossed<u32> {
    com::ffi::guard!(0, { com::object::live_objects() as u32 })
}
