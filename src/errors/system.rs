//! System texts on Windows: FormatMessage from the system's message tables.

use core::ptr;

use windows_sys::Win32::System::Diagnostics::Debug::{
    FormatMessageW, FORMAT_MESSAGE_FROM_SYSTEM, FORMAT_MESSAGE_IGNORE_INSERTS,
};

use crate::com::alloc::alloc_wstr;
use crate::com::{HRESULT, LPWSTR};

/// Longest system text read, in UTF-16 units (the longest Windows messages are well below it).
const MAX_UNITS: usize = 4096;

/// The system's text for `code` in `language` (a LANGID; 0 lets the system choose: neutral, thread,
/// user, system, then US English), without the trailing line break; `None` when the system has no
/// text in that language. Win32 codes wrapped in an HRESULT (FACILITY_WIN32) are also looked up as
/// the plain Win32 code.
pub(super) fn message(code: u32, language: u16) -> Option<Result<LPWSTR, HRESULT>> {
    let mut ids = vec![code];
    if code & 0xFFFF_0000 == 0x8007_0000 {
        ids.push(code & 0xFFFF);
    }
    let mut buffer = vec![0u16; MAX_UNITS];
    for id in ids {
        // SAFETY: `buffer` holds MAX_UNITS units; no source module and no inserts are used.
        let n = unsafe {
            FormatMessageW(
                FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS,
                ptr::null(),
                id,
                u32::from(language),
                buffer.as_mut_ptr(),
                MAX_UNITS as u32,
                ptr::null(),
            )
        } as usize;
        let text = trim_end(&buffer[..n.min(MAX_UNITS)]);
        if !text.is_empty() {
            return Some(alloc_wstr(text));
        }
    }
    None
}

/// `text` without trailing CR, LF, spaces and tabs.
fn trim_end(text: &[u16]) -> &[u16] {
    let end = text
        .iter()
        .rposition(|&u| !matches!(u, 0x0D | 0x0A | 0x20 | 0x09))
        .map_or(0, |i| i + 1);
    &text[..end]
}
