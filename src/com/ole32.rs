//! The COM runtime functions the library takes from `ole32.dll`.
//!
//! windows-sys links `CoTaskMemAlloc`, `CoTaskMemFree` and `CoCreateFreeThreadedMarshaler` from
//! `combase.dll`, which exists only from Windows 8 on. `ole32.dll` exports the same functions on every
//! Windows version (from Windows 8 on it forwards them to combase.dll), so importing them from there
//! costs nothing on new systems and lets the DLL load on Windows 7 and Server 2008 R2 (the
//! `*-win7-windows-gnu` builds). Linked through mingw's import library `libole32.a`.

use core::ffi::c_void;

use super::types::{GUID, HRESULT};

#[link(name = "ole32")]
extern "system" {
    /// Allocates from the COM task allocator; NULL when out of memory.
    pub fn CoTaskMemAlloc(cb: usize) -> *mut c_void;
    /// Frees task-allocator memory; NULL is ignored.
    pub fn CoTaskMemFree(pv: *const c_void);
    /// Creates the free-threaded marshaler aggregated into `outer`.
    pub fn CoCreateFreeThreadedMarshaler(outer: *mut c_void, marshal: *mut *mut c_void) -> HRESULT;
    /// Writes the marshal data of `unk`'s `riid` to `stream`.
    pub fn CoMarshalInterface(
        stream: *mut c_void,
        riid: *const GUID,
        unk: *mut c_void,
        dest_context: u32,
        dest_context_data: *mut c_void,
        flags: u32,
    ) -> HRESULT;
    /// Releases the marshal data at `stream`'s position (and what they hold).
    pub fn CoReleaseMarshalData(stream: *mut c_void) -> HRESULT;
    /// A stream on `hglobal` (NULL: new memory), which frees it when released if `delete_on_release`.
    pub fn CreateStreamOnHGlobal(hglobal: *mut c_void, delete_on_release: i32, stream: *mut *mut c_void) -> HRESULT;
}

/// `GlobalAlloc`'s flag for movable memory (what CreateStreamOnHGlobal takes).
///
/// cbindgen:ignore
pub const GMEM_MOVEABLE: u32 = 0x0002;

// (kernel32's, for the memory of CreateStreamOnHGlobal's streams; kernel32 is linked already, by the
// standard library: a link attribute here would name it twice in the static library's list.)
extern "system" {
    /// Allocates `bytes` of global memory with `flags`; NULL when out of memory.
    pub fn GlobalAlloc(flags: u32, bytes: usize) -> *mut c_void;
    /// Frees global memory; NULL when it did.
    pub fn GlobalFree(memory: *mut c_void) -> *mut c_void;
}
