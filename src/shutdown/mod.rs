//! Shutdown of OPC servers (specification chapter 4), both sides.
//!
//! - Server side ([`server`]): `OpcShutdownCreate` makes an aggregatable object with
//!   IConnectionPointContainer and one connection point for IOPCShutdown; `OpcShutdownNotify` calls
//!   ShutdownRequest on every advised sink.
//! - Client side ([`client`]): `OpcShutdownSinkCreate` makes an IOPCShutdown sink that calls a C
//!   callback; `OpcShutdownAdvise` / `OpcShutdownUnadvise` connect it to a server.
//!
//! The rules this module keeps, which existing implementations often break: cookies are non-zero
//! counters, never pointers; an unknown cookie is CONNECT_E_NOCONNECTION; a sink without
//! IOPCShutdown is CONNECT_E_CANNOTCONNECT; another IID is CONNECT_E_NOCONNECTION; EnumConnections
//! works; and ShutdownRequest is never called while a lock is held.

#[cfg(windows)]
mod agile;
mod apartment;
pub mod bounded;
pub mod client;
pub mod interfaces;
pub mod server;

#[cfg(test)]
mod tests;

use core::ffi::c_void;
use core::ptr;

use crate::com::ffi::{self, Hr};
use crate::com::object::ComObject;
use crate::com::{IUnknown, E_INVALIDARG, LPCWSTR, REFIID, S_FALSE, S_OK, ULONG};
use bounded::{read_notify_options, OpcShutdownNotifyOptions};
use client::NUL_STRING;
use server::{read_options, with_object, OpcShutdown, OpcShutdownOptions};

/// Creates a shutdown object with the default options (at most one advised sink): the
/// IConnectionPointContainer of an OPC server, with one connection point for IOPCShutdown.
///
/// To aggregate the object into a server object, pass the server's controlling IUnknown as `outer`
/// and IID_IUnknown as `riid`: the result is the inner, non-delegating IUnknown, which the server
/// keeps, releases when it is destroyed, and forwards QueryInterface(IID_IConnectionPointContainer)
/// to. A server object that cannot aggregate (windows-rs objects, for one) and forwards instead names
/// itself as the container with `OpcShutdownCreateEx` (`OpcShutdownOptions::container`).
///
/// # Parameters
/// - `outer`: the controlling IUnknown of the server object that aggregates the shutdown object, or
///   NULL.
/// - `riid`: the interface wanted: IID_IConnectionPointContainer or IID_IUnknown, only IID_IUnknown
///   with an `outer`.
/// - `ppv` (out): receives the interface, or NULL on failure.
///
/// # Returns
/// S_OK; E_POINTER for a NULL `ppv` or `riid`; CLASS_E_NOAGGREGATION for an `outer` with a `riid`
/// other than IID_IUnknown; E_NOINTERFACE.
///
/// # Safety
/// `outer` must be NULL or a valid IUnknown that outlives the object; `riid` NULL or readable; `ppv`
/// NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcShutdownCreate(outer: *mut IUnknown, riid: REFIID, ppv: *mut *mut c_void) -> Hr {
    ffi::boundary!(Com, [ppv], {
        // SAFETY: forwarded from the caller's contract.
        Ok(unsafe { OpcShutdownCreateEx(ptr::null(), outer, riid, ppv) }.get())
    })
}

/// As `OpcShutdownCreate`, with options.
///
/// # Parameters
/// - `options`: the settings (OpcShutdownOptions), or NULL for the defaults.
/// - `outer`: as for `OpcShutdownCreate`.
/// - `riid`: as for `OpcShutdownCreate`.
/// - `ppv` (out): receives the interface, or NULL on failure.
///
/// # Returns
/// What `OpcShutdownCreate` returns, and E_INVALIDARG for a `struct_size` that is not the size of some
/// version of `OpcShutdownOptions` (4, 8, or `sizeof` as of this version: 16 on 64-bit, 12 on
/// 32-bit), and for a `container` together with an `outer` object.
///
/// # Safety
/// `options` must be NULL or point at `options->struct_size` readable bytes, and its `container`
/// NULL or a valid IUnknown that outlives every reference to the connection point (they count on
/// it); otherwise as for `OpcShutdownCreate`.
#[no_mangle]
pub unsafe extern "C" fn OpcShutdownCreateEx(
    options: *const OpcShutdownOptions,
    outer: *mut IUnknown,
    riid: REFIID,
    ppv: *mut *mut c_void,
) -> Hr {
    ffi::boundary!(Com, [ppv], {
        // SAFETY: forwarded from the caller's contract.
        Ok(unsafe {
            ComObject::<OpcShutdown>::create(outer, riid, ppv, |binder| {
                let settings = read_options(options)?;
                if !outer.is_null() && !settings.container.is_null() {
                    // An aggregated object's container is its outer object.
                    return Err(E_INVALIDARG);
                }
                Ok(OpcShutdown::build(binder, settings))
            })
        })
    })
}

/// Asks every client advised on a shutdown object to disconnect: calls IOPCShutdown::ShutdownRequest
/// on each advised sink.
///
/// The sinks are taken from a snapshot made under the object's lock and called without holding it, one after the other
/// on the calling thread, so a sink may Unadvise, release the server or call back in from inside
/// ShutdownRequest. A sink unadvised from inside the notification (by itself or an earlier sink) is
/// not called any more. A sink that fails (returns a failure code, or cannot be reached from this thread) does
/// not stop the others. On Windows, call it from a thread that has initialised COM: sinks are
/// fetched from the Global Interface Table for the calling apartment.
///
/// This call waits for every sink, however long it takes: a client that hangs in ShutdownRequest
/// holds it (and the sinks after it) for as long as it hangs. A server that must not wait without
/// bound uses `OpcShutdownNotifyBounded`.
///
/// # Parameters
/// - `shutdown`: any interface of a shutdown object: the IConnectionPointContainer, the inner IUnknown
///   from `OpcShutdownCreate`, or the server object that aggregates it or forwards to it (the server's
///   IConnectionPointContainer hands out the shutdown object's connection point).
/// - `reason`: why the server shuts down, passed to every sink; NULL passes a NUL string.
///
/// # Returns
/// S_OK when every advised sink accepted the request (also when none is advised), S_FALSE when at
/// least one failed; E_INVALIDARG when `shutdown` is NULL or not a shutdown object of this library.
/// Use `OpcShutdownNotifyEx` for the counts.
///
/// # Safety
/// `shutdown` must be NULL or a valid COM interface pointer; `reason` NULL or a NUL-terminated
/// UTF-16 string.
#[no_mangle]
pub unsafe extern "C" fn OpcShutdownNotify(shutdown: *mut IUnknown, reason: LPCWSTR) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: forwarded from the caller's contract.
        Ok(unsafe { OpcShutdownNotifyEx(shutdown, reason, ptr::null_mut(), ptr::null_mut()) }.get())
    })
}

/// As `OpcShutdownNotify`, and reports how many sinks accepted the request and how many failed. The
/// counts are set (to 0 on failure) before anything else happens.
///
/// # Parameters
/// - `shutdown`: as for `OpcShutdownNotify`.
/// - `reason`: as for `OpcShutdownNotify`.
/// - `notified` (out): receives how many sinks accepted the request; may be NULL.
/// - `failed` (out): receives how many refused it or could not be reached; may be NULL.
///
/// # Returns
/// As `OpcShutdownNotify`.
///
/// # Safety
/// As for `OpcShutdownNotify`; `notified` and `failed` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcShutdownNotifyEx(
    shutdown: *mut IUnknown,
    reason: LPCWSTR,
    notified: *mut ULONG,
    failed: *mut ULONG,
) -> Hr {
    ffi::boundary!(Opc, [notified, failed], {
        // SAFETY: the caller's contract: both counts NULL or writable (either may be NULL).
        let (notified, failed) = unsafe { (ffi::out_opt(notified), ffi::out_opt(failed)) };
        let reason = if reason.is_null() { NUL_STRING.as_ptr() } else { reason };
        // SAFETY: `shutdown` is valid per the contract; `reason` is a NUL-terminated string.
        let done = unsafe { with_object(shutdown, |obj| obj.notify(reason)) }?;
        if let Some(notified) = notified {
            notified.write(done.notified);
        }
        if let Some(failed) = failed {
            failed.write(done.failed);
        }
        Ok(if done.failed == 0 { S_OK } else { S_FALSE })
    })
}

/// Asks every client advised on a shutdown object to disconnect, as `OpcShutdownNotify`, but waits for
/// them only until a deadline: the advised sinks are called at the same time on worker threads, so a
/// slow or hung client delays nobody else, and the call returns when every sink has answered or
/// passed its deadline.
///
/// The counts (all set, to 0 on failure, before anything else happens) say what became of every sink
/// advised when the call started. A timed-out call may still return later on its worker thread; the worker holds its
/// own reference to the sink and its own copy of `reason`, so the caller may release the server and
/// free `reason` as soon as this returns. While such a worker runs, `OpcDllCanUnloadNow` says
/// S_FALSE.
///
/// Threads: the workers are one pool for the whole process, shared by every notification of every
/// shutdown object, of at most OPC_SHUTDOWN_MAX_NOTIFY_THREADS threads, whatever the clients do; a
/// worker ends when no call is waiting. A sink is never called again while its earlier call has not
/// returned, so a hung client holds one thread however often the server notifies. Every other sink
/// is called, also when hung clients hold every worker: a call waiting while every worker is inside a
/// call, when all those calls are past their deadlines (OPC_SHUTDOWN_MAX_NOTIFY_THREADS clients hung
/// at once) or its own deadline has passed, or when no worker thread can be created, is made by the
/// calling thread itself, one after the other. Only then can this call last longer than its
/// deadline: it waits for each call it makes itself, so a client that hangs there holds it.
///
/// A sink unadvised before its call starts is not called and not counted (a sink unadvised by another
/// sink during the notification may already have been called: they run at the same time). On Windows
/// each worker calls from the multithreaded apartment (the calling thread from its own), fetching the
/// sink from the Global Interface Table; a sink advised from a single-threaded apartment that the GIT
/// could not take (no IOPCShutdown proxy/stub registered) cannot be called from there and counts as
/// failed. Call it from a thread that has initialised COM.
///
/// # Parameters
/// - `shutdown`: as for `OpcShutdownNotify`.
/// - `reason`: as for `OpcShutdownNotify`.
/// - `options`: the deadlines (OpcShutdownNotifyOptions: the whole notification's, by default
///   OPC_SHUTDOWN_DEFAULT_TIMEOUT_MS, and one per sink), or NULL for the defaults.
/// - `notified` (out): receives how many sinks accepted the request; may be NULL.
/// - `failed` (out): receives how many refused it or could not be reached (a client process that
///   died); may be NULL.
/// - `timed_out` (out): receives how many had not answered at their deadline, or were not called
///   because their call from an earlier notification has not returned yet; may be NULL.
///
/// # Returns
/// S_OK when every sink accepted the request (also when none is advised), S_FALSE when at least one
/// failed or timed out; E_INVALIDARG when `shutdown` is NULL or not a shutdown object of this library,
/// or `options->struct_size` is not the size of some version of `OpcShutdownNotifyOptions`.
///
/// # Safety
/// `shutdown` must be NULL or a valid COM interface pointer; `reason` NULL or a NUL-terminated UTF-16
/// string; `options` NULL or pointing at `options->struct_size` readable bytes; `notified`, `failed`
/// and `timed_out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcShutdownNotifyBounded(
    shutdown: *mut IUnknown,
    reason: LPCWSTR,
    options: *const OpcShutdownNotifyOptions,
    notified: *mut ULONG,
    failed: *mut ULONG,
    timed_out: *mut ULONG,
) -> Hr {
    ffi::boundary!(Opc, [notified, failed, timed_out], {
        // SAFETY: the caller's contract: each count NULL or writable.
        let (notified, failed, timed_out) =
            unsafe { (ffi::out_opt(notified), ffi::out_opt(failed), ffi::out_opt(timed_out)) };
        // SAFETY: the caller vouches for `options`.
        let bounds = unsafe { read_notify_options(options) }?;
        let reason = if reason.is_null() { NUL_STRING.as_ptr() } else { reason };
        // SAFETY: `shutdown` is valid per the contract; `reason` is a NUL-terminated string.
        let done = unsafe { with_object(shutdown, |obj| obj.notify_bounded(reason, bounds)) }?;
        if let Some(notified) = notified {
            notified.write(done.notified);
        }
        if let Some(failed) = failed {
            failed.write(done.failed);
        }
        if let Some(timed_out) = timed_out {
            timed_out.write(done.timed_out);
        }
        Ok(if done.failed == 0 && done.timed_out == 0 {
            S_OK
        } else {
            S_FALSE
        })
    })
}
