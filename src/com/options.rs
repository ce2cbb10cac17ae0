//! Options structs that grow: every one starts with `u32 struct_size`, fields are only ever added at the
//! end, and the library reads just the bytes the caller's version of the struct has.

use core::ptr;

use super::hresult::E_INVALIDARG;
use super::types::HRESULT;

/// A structure the library reads by its `struct_size` (`read_sized`). `SIZES` is every `struct_size`
/// it accepts: each size a version of the structure has had, ending after a whole field, with or
/// without C's trailing padding; `size_of::<Self>()` among them. A size once accepted stays
/// (docs/abi-policy.md). docs/api-conventions.md lists these sizes per architecture, generated from
/// `SIZES` by `src/struct_size_table.rs`.
///
/// # Safety
/// The implementing type must be `#[repr(C)]` with a `u32 struct_size` as its first field and valid
/// for any bytes a caller may write (integers, GUIDs, raw pointers, optional function pointers).
pub unsafe trait SizedStruct: Copy {
    /// The accepted `struct_size` values, in any order (on 32-bit targets some may coincide).
    const SIZES: &'static [usize];
}

/// Reads a caller's options struct: starts from `defaults` and copies the first `struct_size` bytes of
/// `*options` over it. NULL gives `defaults`. A `struct_size` not in `T::SIZES` — zero, one from a
/// newer version, or one cutting a field (half a pointer) — is E_INVALIDARG.
///
/// # Safety
/// `options` must be NULL or point at `struct_size` readable bytes.
pub unsafe fn read_sized<T: SizedStruct>(options: *const T, defaults: T) -> Result<T, HRESULT> {
    let mut value = defaults;
    if options.is_null() {
        return Ok(value);
    }
    // SAFETY: the first field, a u32, is always present (SizedStruct's contract).
    let size = unsafe { options.cast::<u32>().read_unaligned() } as usize;
    if size > core::mem::size_of::<T>() || !T::SIZES.contains(&size) {
        return Err(E_INVALIDARG);
    }
    // SAFETY: the caller vouches `size` bytes are readable; `value` has room for them (checked above).
    unsafe { ptr::copy_nonoverlapping(options.cast::<u8>(), ptr::addr_of_mut!(value).cast::<u8>(), size) };
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[repr(C)]
    #[derive(Clone, Copy, PartialEq, Debug)]
    struct V2 {
        struct_size: u32,
        a: u32,
        b: u64,
    }
    // SAFETY: repr(C), struct_size first, integers only.
    unsafe impl SizedStruct for V2 {
        const SIZES: &'static [usize] = &[8, 16];
    }

    #[test]
    fn older_versions_keep_defaults_for_newer_fields_and_bad_sizes_are_refused() {
        let defaults = V2 {
            struct_size: 0,
            a: 1,
            b: 2,
        };
        let old = V2 {
            struct_size: 8,
            a: 7,
            b: 99,
        };
        // SAFETY: `old` is readable in full.
        let got = unsafe { read_sized(&old, defaults) }.unwrap();
        assert_eq!((got.a, got.b), (7, 2));
        let new = V2 {
            struct_size: 16,
            a: 7,
            b: 99,
        };
        // SAFETY: as above.
        assert_eq!(unsafe { read_sized(&new, defaults) }.unwrap().b, 99);
        for size in [0, 4, 12, 24] {
            let bad = V2 {
                struct_size: size,
                a: 7,
                b: 99,
            };
            // SAFETY: as above; refused before anything past the first field is read.
            assert_eq!(unsafe { read_sized(&bad, defaults) }, Err(E_INVALIDARG));
        }
        // SAFETY: NULL is allowed.
        assert_eq!(unsafe { read_sized(ptr::null(), defaults) }.unwrap(), defaults);
    }
}
