//! The one allocator for memory handed to callers.
//!
//! On Windows it is the COM task allocator (CoTaskMemAlloc / CoTaskMemFree), so callers free what the
//! library returns with CoTaskMemFree as COM requires. Elsewhere it is malloc / free. Both are exported
//! as `OpcTaskMemAlloc` / `OpcTaskMemFree`, so C code frees library memory the same way everywhere.

use super::ffi::Crossed;
use core::ffi::c_void;
use core::ptr;

use super::hresult::E_OUTOFMEMORY;
use super::types::{HRESULT, LPWSTR, WCHAR};

/// Allocates `size` bytes from the task allocator; NULL when out of memory. A size of 0 still
/// returns a unique pointer that must be freed.
#[inline]
pub fn task_alloc(size: usize) -> *mut c_void {
    #[cfg(windows)]
    {
        // SAFETY: CoTaskMemAlloc accepts any size and returns NULL on failure.
        unsafe { super::ole32::CoTaskMemAlloc(size.max(1)) }
    }
    #[cfg(not(windows))]
    {
        // SAFETY: malloc accepts any size and returns NULL on failure.
        unsafe { libc::malloc(size.max(1)) }
    }
}

/// Frees memory from [`task_alloc`]; NULL is ignored.
///
/// # Safety
/// `p` must be NULL or a pointer from the task allocator that has not been freed.
pub unsafe fn task_free(p: *mut c_void) {
    if p.is_null() {
        return;
    }
    #[cfg(windows)]
    // SAFETY: the caller vouches `p` came from CoTaskMemAlloc.
    unsafe {
        super::ole32::CoTaskMemFree(p)
    };
    #[cfg(not(windows))]
    // SAFETY: the caller vouches `p` came from malloc.
    unsafe {
        libc::free(p)
    };
}

/// Copies `items` into a new task-allocated array (a unique non-NULL pointer even when empty).
///
/// An empty array still gets a block of at least `align_of::<T>()` bytes, so the pointer is aligned
/// for `T` (malloc aligns a block only for objects that fit in it: a 1-byte block may be 2-aligned),
/// and nothing is copied into it.
pub fn alloc_array<T: Copy>(items: &[T]) -> Result<*mut T, HRESULT> {
    let bytes = core::mem::size_of_val(items).max(core::mem::align_of::<T>());
    let p = task_alloc(bytes) as *mut T;
    if p.is_null() {
        return Err(E_OUTOFMEMORY);
    }
    if !items.is_empty() {
        // SAFETY: `p` has room for `items.len()` elements and is aligned for `T`: malloc and
        // CoTaskMemAlloc align a block of `size_of_val(items)` bytes for any type that fits in it.
        unsafe { ptr::copy_nonoverlapping(items.as_ptr(), p, items.len()) };
    }
    Ok(p)
}

/// Copies UTF-16 `units` into a new task-allocated, NUL-terminated string.
pub fn alloc_wstr(units: &[WCHAR]) -> Result<LPWSTR, HRESULT> {
    let len = units.len().checked_add(1).ok_or(E_OUTOFMEMORY)?;
    let bytes = len.checked_mul(core::mem::size_of::<WCHAR>()).ok_or(E_OUTOFMEMORY)?;
    let p = task_alloc(bytes) as LPWSTR;
    if p.is_null() {
        return Err(E_OUTOFMEMORY);
    }
    // SAFETY: `p` has room for `units.len() + 1` code units.
    unsafe {
        ptr::copy_nonoverlapping(units.as_ptr(), p, units.len());
        *p.add(units.len()) = 0;
    }
    Ok(p)
}

/// Copies `units`, which end with their NUL, into a new task-allocated string (one copy).
#[inline]
pub fn alloc_wstr_terminated(units: &[WCHAR]) -> Result<LPWSTR, HRESULT> {
    debug_assert_eq!(units.last(), Some(&0));
    let p = task_alloc(core::mem::size_of_val(units)) as LPWSTR;
    if p.is_null() {
        return Err(E_OUTOFMEMORY);
    }
    // SAFETY: `p` has room for `units.len()` code units.
    unsafe { ptr::copy_nonoverlapping(units.as_ptr(), p, units.len()) };
    Ok(p)
}

/// Encodes `text` as a new task-allocated, NUL-terminated UTF-16 string.
pub fn alloc_wstr_from_str(text: &str) -> Result<LPWSTR, HRESULT> {
    let units: Vec<WCHAR> = text.encode_utf16().collect();
    alloc_wstr(&units)
}

/// Allocates memory with the allocator the library uses for all memory it hands to callers:
/// CoTaskMemAlloc on Windows, malloc elsewhere. What a server hands to the library to free or keep
/// (the text of an OpcVendorErrorTextFn) comes from here.
///
/// # Parameters
/// - `size`: the number of bytes; 0 still gives a unique pointer.
///
/// # Returns
/// The memory, to be freed with `OpcTaskMemFree` (or CoTaskMemFree on Windows); NULL when out of
/// memory.
#[no_mangle]
pub extern "C" fn OpcTaskMemAlloc(size: usize) -> Crossed<*mut c_void> {
    super::ffi::guard!(ptr::null_mut(), { task_alloc(size) })
}

/// Frees memory returned by the library (strings, arrays) or by `OpcTaskMemAlloc`.
///
/// # Parameters
/// - `memory`: the memory, or NULL (ignored).
///
/// # Safety
/// `memory` must be NULL or memory from the library's task allocator that has not been freed yet.
#[no_mangle]
pub unsafe extern "C" fn OpcTaskMemFree(memory: *mut c_void) {
    super::ffi::guard!((), {
        // SAFETY: forwarded from the caller's contract.
        unsafe { task_free(memory) }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wide_strings_are_nul_terminated_copies() {
        let p = alloc_wstr_from_str("Grüße").unwrap();
        // SAFETY: `p` holds 6 units including the NUL.
        let got = unsafe { core::slice::from_raw_parts(p, 6) };
        assert_eq!(got, &[0x47, 0x72, 0xFC, 0xDF, 0x65, 0]);
        // SAFETY: allocated above.
        unsafe { task_free(p.cast()) };
    }

    #[test]
    fn empty_allocations_are_unique_and_freeable() {
        let a = alloc_array::<u32>(&[]).unwrap();
        assert!(!a.is_null());
        assert!(a.is_aligned());
        let b = alloc_array::<u64>(&[]).unwrap();
        assert!(b.is_aligned() && b != a.cast());
        let c = alloc_array(&[7u32, 8]).unwrap();
        // SAFETY: `c` holds the two elements copied above.
        assert_eq!(unsafe { core::slice::from_raw_parts(c, 2) }, &[7, 8]);
        // SAFETY: allocated above; NULL is tolerated.
        unsafe {
            OpcTaskMemFree(a.cast());
            OpcTaskMemFree(b.cast());
            OpcTaskMemFree(c.cast());
            OpcTaskMemFree(ptr::null_mut());
        }
    }
}
