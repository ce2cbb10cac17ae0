//! MatchPattern: the string filter of the specification's Appendix B (Visual Basic `Like` syntax),
//! exact, safe on any input and fast.
//!
//! Semantics (see docs/guide/matchpattern.md): `?` one character, `*` zero or more, `#` one ASCII digit, `[list]` /
//! `[!list]` one character in / not in the list (ranges `a-z` by code point), `[]` the empty string,
//! `[!]` a literal `!`, a `-` first, last or right after a range is itself. An unclosed `[` or a
//! reversed range makes the pattern malformed: it never matches. Case-insensitive comparison uses
//! Unicode simple case folding. A character is a Unicode scalar value; unpaired surrogates and bytes
//! that do not decode are characters of their own.
//!
//! - `MatchPatternW` / `MatchPatternA`: one call, one answer (the specification's function).
//! - `OpcPatternCompileW` / `A`, `OpcPatternMatchW` / `A`, `OpcPatternFree`: compile a filter once and
//!   test it against many names, as a server's browse does.

mod fold;
mod fold_table;
mod narrow;
mod program;
#[cfg(any(test, feature = "fuzzing"))]
#[doc(hidden)]
pub mod reference;
mod smallvec;
mod steps;
mod stream;
mod text;

#[cfg(test)]
mod tests;

use crate::com::ffi::{self, Crossed, Fail, FfiResult, Hr};
use crate::com::wstr::wstr_units;
use crate::com::{BOOL, FALSE, LPCSTR, LPCWSTR, OPC_E_INVALIDFILTER, S_OK, TRUE};
use program::{Malformed, Program};
use stream::WideCursor;
use text::Utf16;

fn to_bool(b: bool) -> BOOL {
    if b {
        TRUE
    } else {
        FALSE
    }
}

/// Whether a string matches a filter pattern (OPC Common, Appendix B: MatchPattern).
///
/// The pattern syntax is that of Visual Basic's `Like` operator:
/// `?` any one character; `*` zero or more characters; `#` one digit `0`-`9`;
/// `[list]` one character in the list and `[!list]` one not in it, where `a-z` is a range by code point,
/// `-` first, last or right after a range stands for itself and `!` negates only right after `[`;
/// `[]` matches the empty string and `[!]` a literal `!`; `[*]`, `[?]`, `[#]` and `[[]` match the
/// special character itself; `]` outside a list and every other character match themselves.
///
/// A character is one Unicode scalar value (a surrogate pair is one character; an unpaired surrogate is
/// one character too). With `bCaseSensitive` FALSE, characters compare by Unicode simple case folding,
/// in literals and in ranges alike (`[a-z]` matches `Q`, `é` matches `É`).
///
/// Never reads past either terminating NUL (strings have no length limit). Time is at most
/// proportional to len(string) x len(pattern), and linear for typical filters. Patterns of up to 128
/// code units are read in place and allocate no memory; longer ones with a `*` are compiled first, as
/// `OpcPatternCompileW` does. Thread-safe. The parameters have the specification's names.
///
/// # Parameters
/// - `string`: the string to test, NUL-terminated UTF-16.
/// - `pattern`: the filter pattern, NUL-terminated UTF-16.
/// - `bCaseSensitive`: TRUE to compare characters as they are; FALSE to compare them by Unicode simple
///   case folding.
///
/// # Returns
/// TRUE (1) if `string` matches `pattern`; FALSE (0) if not, if either argument is NULL, or if the
/// pattern is malformed (an unclosed `[` or a reversed range such as `[Z-A]`; `OpcPatternCompileW`
/// reports these as OPC_E_INVALIDFILTER).
///
/// # Safety
/// `string` and `pattern` must each be NULL or point at a NUL-terminated UTF-16 string.
#[no_mangle]
pub unsafe extern "C" fn MatchPatternW(string: LPCWSTR, pattern: LPCWSTR, bCaseSensitive: BOOL) -> Crossed<BOOL> {
    ffi::guard!(FALSE, {
        if string.is_null() || pattern.is_null() {
            return FALSE;
        }
        let case_sensitive = bCaseSensitive != 0;
        // SAFETY: both are NUL-terminated (the caller's contract).
        let matched = match unsafe { stream::matches(WideCursor(string), WideCursor(pattern), case_sensitive) } {
            Some(matched) => matched,
            // SAFETY: as above.
            None => unsafe { match_long_pattern(string, pattern, case_sensitive) },
        };
        to_bool(matched)
    })
}

/// `MatchPatternW` for a pattern longer than `stream::LONG_PATTERN` with a `*`: compiled first (on the
/// heap; ordinary patterns never get here, and keeping this out of line keeps the common path lean).
///
/// # Safety
/// Both must point at NUL-terminated strings.
#[cold]
#[inline(never)]
unsafe fn match_long_pattern(string: LPCWSTR, pattern: LPCWSTR, case_sensitive: bool) -> bool {
    // SAFETY: NUL-terminated (the caller's contract).
    let units = unsafe { wstr_units(pattern, usize::MAX) }.unwrap_or_default();
    match Program::compile(&Utf16(units), case_sensitive) {
        // SAFETY: as above.
        Ok(program) => unsafe { program.matches_cursor(WideCursor(string)) },
        Err(_) => false,
    }
}

/// `MatchPatternW` for narrow strings, with the same syntax and rules.
///
/// Narrow strings are UTF-8, except on Windows where they are in the process's ANSI code page (as for
/// every `...A` Win32 function). A byte that does not decode is one character of its own, matched only
/// by itself, `?`, `*` or a list containing that same byte; it is never rejected and never causes a
/// read past the terminating NUL.
///
/// # Parameters
/// - `string`: the string to test, NUL-terminated.
/// - `pattern`: the filter pattern, NUL-terminated.
/// - `bCaseSensitive`: as for `MatchPatternW`.
///
/// # Returns
/// TRUE (1) if `string` matches `pattern`; FALSE (0) if not, if either argument is NULL, or if the
/// pattern is malformed.
///
/// # Safety
/// `string` and `pattern` must each be NULL or point at a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn MatchPatternA(string: LPCSTR, pattern: LPCSTR, bCaseSensitive: BOOL) -> Crossed<BOOL> {
    ffi::guard!(FALSE, {
        if string.is_null() || pattern.is_null() {
            return FALSE;
        }
        // SAFETY: both are NUL-terminated (the caller's contract).
        to_bool(unsafe { narrow::match_once(string.cast(), pattern.cast(), bCaseSensitive != 0) })
    })
}

/// A compiled filter: a pattern checked and prepared once by `OpcPatternCompileW` or
/// `OpcPatternCompileA`, then tested against many strings with `OpcPatternMatchW` / `OpcPatternMatchA`,
/// and released with `OpcPatternFree`. It is never modified after compilation, so several threads may
/// use one filter at the same time.
pub struct OpcPattern {
    program: Program,
}

/// A compiled pattern as the caller's new filter, or OPC_E_INVALIDFILTER.
fn deliver(compiled: Result<Program, Malformed>, out: ffi::Out<'_, *mut OpcPattern>) -> FfiResult {
    let program = compiled.map_err(|_| OPC_E_INVALIDFILTER)?;
    out.write(Box::into_raw(Box::new(OpcPattern { program })));
    Ok(S_OK)
}

/// Compiles a filter pattern (the syntax of `MatchPatternW`) once for matching many strings.
///
/// # Parameters
/// - `pattern`: the filter pattern, NUL-terminated UTF-16.
/// - `case_sensitive`: TRUE to compare characters as they are; FALSE to compare them by Unicode
///   simple case folding.
/// - `filter` (out): receives the compiled filter (free it with `OpcPatternFree`), or NULL on failure.
///
/// # Returns
/// S_OK; OPC_E_INVALIDFILTER for a malformed pattern (an unclosed `[` or a reversed range such as
/// `[Z-A]`), which is what a browse call must return for a bad filter; E_INVALIDARG for a NULL
/// `pattern` or `filter`.
///
/// # Safety
/// `pattern` must be NULL or point at a NUL-terminated UTF-16 string; `filter` must be NULL or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn OpcPatternCompileW(
    pattern: LPCWSTR,
    case_sensitive: BOOL,
    filter: *mut *mut OpcPattern,
) -> Hr {
    ffi::boundary!(Opc, [filter], {
        // SAFETY: the caller vouches a non-NULL `filter` is writable.
        let out = unsafe { ffi::out(filter) }?;
        // SAFETY: the caller vouches `pattern` is NULL or NUL-terminated (no length limit).
        let pattern = unsafe { wstr_units(pattern, usize::MAX) }.ok_or(Fail::Null)?;
        deliver(Program::compile(&Utf16(pattern), case_sensitive != 0), out)
    })
}

/// `OpcPatternCompileW` for a narrow pattern (UTF-8; the ANSI code page on Windows). The compiled
/// filter matches wide and narrow strings alike.
///
/// # Parameters
/// - `pattern`: the filter pattern, NUL-terminated.
/// - `case_sensitive`: as for `OpcPatternCompileW`.
/// - `filter` (out): receives the compiled filter (free it with `OpcPatternFree`), or NULL on failure.
///
/// # Returns
/// As `OpcPatternCompileW`.
///
/// # Safety
/// `pattern` must be NULL or point at a NUL-terminated string; `filter` must be NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcPatternCompileA(pattern: LPCSTR, case_sensitive: BOOL, filter: *mut *mut OpcPattern) -> Hr {
    ffi::boundary!(Opc, [filter], {
        // SAFETY: the caller vouches a non-NULL `filter` is writable.
        let out = unsafe { ffi::out(filter) }?;
        // SAFETY: the caller vouches `pattern` is NULL or NUL-terminated.
        let pattern = unsafe { narrow::cstr_bytes(pattern) }.ok_or(Fail::Null)?;
        deliver(narrow::compile(pattern, case_sensitive != 0), out)
    })
}

/// Whether a string matches a compiled filter: the result of `MatchPatternW` with the pattern and
/// case mode the filter was compiled from. Allocates nothing; thread-safe.
///
/// # Parameters
/// - `filter`: the compiled filter.
/// - `string`: the string to test, NUL-terminated UTF-16.
///
/// # Returns
/// TRUE (1) if `string` matches; FALSE (0) if not or if either argument is NULL.
///
/// # Safety
/// `filter` must be NULL or a filter from `OpcPatternCompileW` or `OpcPatternCompileA` not yet freed;
/// `string` must be NULL or point at a NUL-terminated UTF-16 string.
#[no_mangle]
pub unsafe extern "C" fn OpcPatternMatchW(filter: *const OpcPattern, string: LPCWSTR) -> Crossed<BOOL> {
    ffi::guard!(FALSE, {
        // SAFETY: the caller vouches `filter` is NULL or a live filter.
        let Some(filter) = (unsafe { filter.as_ref() }) else {
            return FALSE;
        };
        if string.is_null() {
            return FALSE;
        }
        // SAFETY: the caller vouches `string` is NUL-terminated.
        to_bool(unsafe { filter.program.matches_cursor(WideCursor(string)) })
    })
}

/// `OpcPatternMatchW` for a narrow string (UTF-8; the ANSI code page on Windows).
///
/// # Parameters
/// - `filter`: the compiled filter.
/// - `string`: the string to test, NUL-terminated.
///
/// # Returns
/// TRUE (1) if `string` matches; FALSE (0) if not or if either argument is NULL.
///
/// # Safety
/// `filter` must be NULL or a filter from `OpcPatternCompileW` or `OpcPatternCompileA` not yet freed;
/// `string` must be NULL or point at a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn OpcPatternMatchA(filter: *const OpcPattern, string: LPCSTR) -> Crossed<BOOL> {
    ffi::guard!(FALSE, {
        // SAFETY: the caller vouches `filter` is NULL or a live filter.
        let Some(filter) = (unsafe { filter.as_ref() }) else {
            return FALSE;
        };
        if string.is_null() {
            return FALSE;
        }
        // SAFETY: the caller vouches `string` is NUL-terminated.
        to_bool(unsafe { narrow::matches(&filter.program, string.cast()) })
    })
}

/// Frees a compiled filter.
///
/// # Parameters
/// - `filter`: a filter from `OpcPatternCompileW` or `OpcPatternCompileA`, or NULL (ignored).
///
/// # Safety
/// `filter` must be NULL or a filter from `OpcPatternCompileW` or `OpcPatternCompileA` that has not
/// been freed, and no other thread may be using it.
#[no_mangle]
pub unsafe extern "C" fn OpcPatternFree(filter: *mut OpcPattern) {
    ffi::guard!((), {
        if !filter.is_null() {
            // SAFETY: the caller vouches it came from `Box::into_raw` in `deliver` and is freed once.
            drop(unsafe { Box::from_raw(filter) });
        }
    })
}
