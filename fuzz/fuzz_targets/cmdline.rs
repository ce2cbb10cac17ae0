//! EXE server command lines (OpcParseCommandLine): any text, valid UTF-16 or not, gives S_OK with one of
//! the four commands or E_INVALIDARG with OPC_SERVER_COMMAND_NONE; the answer agrees with a reference
//! that reads the rules of the function's documentation (blank-separated arguments, double quotes group
//! blanks, `/` or `-` switches matched without regard to case, register together with unregister is an
//! error).
//!
//! Input: UTF-8 text, or (when it is not UTF-8) UTF-16LE units; cut at the first NUL.
#![no_main]

use libfuzzer_sys::fuzz_target;
use opccomn::com::{E_INVALIDARG, S_OK};
use opccomn::registry::cmdline::OpcParseCommandLine;

fn units(data: &[u8]) -> Vec<u16> {
    let mut u: Vec<u16> = match std::str::from_utf8(data) {
        Ok(s) => s.encode_utf16().collect(),
        Err(_) => data.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect(),
    };
    u.truncate(u.iter().position(|&x| x == 0).unwrap_or(u.len()));
    u.push(0);
    u
}

/// (HRESULT, command) as the documentation describes them.
fn reference(text: &[u16]) -> (i32, u32) {
    let Ok(line) = String::from_utf16(text) else {
        return (E_INVALIDARG, 0);
    };
    // Arguments: quotes toggle grouping and are dropped; unquoted blanks and tabs separate.
    let mut args: Vec<String> = Vec::new();
    let mut quoted = false;
    let mut current: Option<String> = None;
    for c in line.chars() {
        if c == '"' {
            quoted = !quoted;
            current.get_or_insert_with(String::new);
        } else if (c == ' ' || c == '\t') && !quoted {
            args.extend(current.take());
        } else {
            current.get_or_insert_with(String::new).push(c);
        }
    }
    args.extend(current);
    let has = |names: &[&str]| {
        args.iter()
            .any(|a| (a.starts_with('/') || a.starts_with('-')) && names.iter().any(|n| a[1..].eq_ignore_ascii_case(n)))
    };
    match (
        has(&["regserver"]),
        has(&["unregserver"]),
        has(&["embedding", "automation"]),
    ) {
        (true, true, _) => (E_INVALIDARG, 0),
        (true, false, _) => (S_OK, 1),
        (false, true, _) => (S_OK, 2),
        (false, false, true) => (S_OK, 3),
        _ => (S_OK, 0),
    }
}

fuzz_target!(|data: &[u8]| {
    let text = units(data);
    let mut command = 99;
    // SAFETY: NUL-terminated text, writable out-parameter.
    let hr = unsafe { OpcParseCommandLine(text.as_ptr(), &mut command) }.get();
    assert_eq!(
        (hr, command),
        reference(&text[..text.len() - 1]),
        "{:?}",
        String::from_utf16_lossy(&text)
    );
});
