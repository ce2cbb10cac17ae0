//! Version strings (OpcVersionParse, OpcVersionFormat): any text, valid UTF-16 or not, is parsed or
//! refused with E_INVALIDARG (never anything else); what parses is what the convention `MM.mm.bb`
//! allows (three dot-separated runs of 1 to 5 digits, each at most 65535), and formatting a parsed
//! version gives text that parses to the same version.
//!
//! Input: UTF-8 text, or (when it is not UTF-8) UTF-16LE units; cut at the first NUL.
#![no_main]

use libfuzzer_sys::fuzz_target;
use opccomn::com::alloc::OpcTaskMemFree;
use opccomn::com::{E_INVALIDARG, S_OK};
use opccomn::registry::version::{OpcVersion, OpcVersionFormat, OpcVersionParse};

fn units(data: &[u8]) -> Vec<u16> {
    let mut u: Vec<u16> = match std::str::from_utf8(data) {
        Ok(s) => s.encode_utf16().collect(),
        Err(_) => data.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect(),
    };
    u.truncate(u.iter().position(|&x| x == 0).unwrap_or(u.len()));
    u.push(0);
    u
}

/// The convention read off its description, independently of the library's parser.
fn reference(text: &[u16]) -> Option<[u32; 3]> {
    let text = String::from_utf16(text).ok()?;
    let parts: Vec<&str> = text.split('.').collect();
    if parts.len() != 3 {
        return None;
    }
    let mut out = [0; 3];
    for (o, p) in out.iter_mut().zip(parts) {
        if p.is_empty() || p.len() > 5 || !p.chars().all(|c| c.is_ascii_digit()) {
            return None;
        }
        *o = p.parse::<u32>().ok().filter(|v| *v <= 65535)?;
    }
    Some(out)
}

fn parse(text: &[u16]) -> (i32, OpcVersion) {
    let mut v = OpcVersion {
        major: 1,
        minor: 2,
        build: 3,
    };
    // SAFETY: NUL-terminated text, writable out-parameter.
    let hr = unsafe { OpcVersionParse(text.as_ptr(), &mut v) }.get();
    (hr, v)
}

fuzz_target!(|data: &[u8]| {
    let text = units(data);
    let (hr, v) = parse(&text);
    match reference(&text[..text.len() - 1]) {
        Some([major, minor, build]) => {
            assert_eq!(hr, S_OK);
            assert_eq!((v.major as u32, v.minor as u32, v.build as u32), (major, minor, build));
        }
        None => {
            assert_eq!(hr, E_INVALIDARG);
            assert_eq!(v, OpcVersion::default(), "the out-parameter is 0.0.0 on failure");
            return;
        }
    }
    let mut formatted = core::ptr::null_mut();
    // SAFETY: a valid version, writable out-parameter.
    assert_eq!(unsafe { OpcVersionFormat(&v, &mut formatted) }, S_OK);
    // SAFETY: a NUL-terminated string the library allocated; read, then freed once.
    let again = unsafe {
        let len = (0..).take_while(|&i| *formatted.add(i) != 0).count();
        let t: Vec<u16> = core::slice::from_raw_parts(formatted, len + 1).to_vec();
        OpcTaskMemFree(formatted.cast());
        t
    };
    assert_eq!(parse(&again), (S_OK, v), "format then parse");
    assert!(
        reference(&again[..again.len() - 1]).is_some(),
        "the formatted text follows the convention"
    );
});
