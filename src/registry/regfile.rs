//! Registry files (`.reg`, "Windows Registry Editor Version 5.00"): export of a registry subtree, so an
//! installer can ship a server's registration, and applying one.
//!
//! Export writes every key of the subtree (empty ones too, so they survive a round trip) in a stable
//! order (names sorted without regard to case), `@` for default values, `"..."` strings with `\` and
//! `"` escaped, `dword:` for DWORDs and `hex(n):` for everything else, including strings that contain a
//! line break or NUL, which the quoted form cannot carry. Lines end in CR LF. Save the text as UTF-16LE
//! with a byte-order mark for regedit; `reg import` also reads UTF-8.
//!
//! Applying understands what export writes plus the rest of the format: `REGEDIT4` headers, `;`
//! comments, `[-key]` (delete a key and its subtree), `"name"=-` (delete a value), `hex:` and
//! lines continued with a trailing `\`. Only `HKEY_CLASSES_ROOT` (or `HKCR`) is accepted as root. The
//! whole text is parsed before anything is written, so a malformed file changes nothing.

use core::fmt::Write as _;

use super::path::RegPath;
use super::{registries, OpcRegistry, RegValue, Registry, MAX_KEY_DEPTH, MAX_NAME_UNITS, REGDB_E_KEYMISSING};
use crate::com::alloc::alloc_wstr_from_str;
use crate::com::ffi::{self, Hr};
use crate::com::{E_INVALIDARG, HRESULT, LPCWSTR, LPWSTR, S_OK};

const HEADER: &str = "Windows Registry Editor Version 5.00";
const ROOT: &str = "HKEY_CLASSES_ROOT";

fn sorted(mut names: Vec<String>) -> Vec<String> {
    names.sort_by_key(|n| RegPath::new(n.as_str()));
    names
}

fn quote(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        if c == '\\' || c == '"' {
            out.push('\\');
        }
        out.push(c);
    }
    out.push('"');
    out
}

fn hex(kind: u32, bytes: &[u8]) -> String {
    const DIGITS: &[u8; 16] = b"0123456789abcdef";
    let mut out = if kind == 3 {
        String::from("hex:")
    } else {
        format!("hex({kind:x}):")
    };
    out.reserve(bytes.len() * 3);
    for (i, &b) in bytes.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        out.push(DIGITS[usize::from(b >> 4)] as char);
        out.push(DIGITS[usize::from(b & 15)] as char);
    }
    out
}

fn utf16_bytes(text: &str) -> Vec<u8> {
    text.encode_utf16().chain([0]).flat_map(u16::to_le_bytes).collect()
}

fn format_value(value: &RegValue) -> String {
    match value {
        RegValue::Sz(s) if !s.bytes().any(|b| matches!(b, b'\r' | b'\n' | 0)) => quote(s),
        RegValue::Sz(s) => hex(1, &utf16_bytes(s)),
        RegValue::ExpandSz(s) => hex(2, &utf16_bytes(s)),
        RegValue::Dword(d) => format!("dword:{d:08x}"),
        RegValue::Other { kind, bytes } => hex(*kind, bytes),
    }
}

fn export_key(reg: &dyn Registry, path: &str, out: &mut String) {
    let mut values = reg.values(path);
    values.sort_by_key(|(name, _)| RegPath::new(name.as_str()));
    if !path.is_empty() {
        let _ = write!(out, "[{ROOT}\\{path}]\r\n");
    }
    for (name, value) in &values {
        let name = if name.is_empty() { "@".to_string() } else { quote(name) };
        let _ = write!(out, "{name}={}\r\n", format_value(value));
    }
    if !path.is_empty() || !values.is_empty() {
        out.push_str("\r\n");
    }
}

/// Writes the subtree at `path`, each key before its subkeys in sorted order. A walk with its own
/// stack of pending keys, not recursion: the depth of the tree costs no call stack.
fn export_tree(reg: &dyn Registry, path: &str, out: &mut String) {
    let mut pending = vec![path.to_string()];
    while let Some(key) = pending.pop() {
        export_key(reg, &key, out);
        // Reversed, so the first name is taken next.
        for child in sorted(reg.subkeys(&key)).into_iter().rev() {
            pending.push(if key.is_empty() {
                child
            } else {
                format!("{key}\\{child}")
            });
        }
    }
}

/// The `.reg` text of the subtree at `path` (the whole registry for the empty path).
pub fn export(reg: &dyn Registry, path: &str) -> Result<String, HRESULT> {
    let path = path.trim_matches('\\');
    if !path.is_empty() && !reg.key_exists(path) {
        return Err(REGDB_E_KEYMISSING);
    }
    let mut out = format!("{HEADER}\r\n\r\n");
    export_tree(reg, path, &mut out);
    Ok(out)
}

/// One change a registry file asks for.
#[derive(Debug, PartialEq)]
enum Change {
    CreateKey(String),
    DeleteTree(String),
    Set(String, String, RegValue),
    DeleteValue(String, String),
}

/// The key path of a `[...]` header relative to HKEY_CLASSES_ROOT.
fn key_path(header: &str) -> Result<String, HRESULT> {
    let (root, rest) = header.split_once('\\').unwrap_or((header, ""));
    if !root.eq_ignore_ascii_case(ROOT) && !root.eq_ignore_ascii_case("HKCR") {
        return Err(E_INVALIDARG);
    }
    if rest.is_empty() || rest.split('\\').any(|name| !name_fits(name)) {
        return Err(E_INVALIDARG);
    }
    // Deeper than the registry goes: refused while parsing, so the file changes nothing.
    if rest.split('\\').count() > MAX_KEY_DEPTH {
        return Err(E_INVALIDARG);
    }
    Ok(rest.to_string())
}

/// A key name the registry takes (1 to MAX_NAME_UNITS UTF-16 units; value names have the same upper
/// bound and may be empty). Checked while parsing, so that a file the registry would refuse halfway
/// is refused before anything is written.
fn name_fits(name: &str) -> bool {
    !name.is_empty() && name.encode_utf16().count() <= MAX_NAME_UNITS
}

/// Parses a quoted string at the start of `s`; returns it and the rest after the closing quote.
fn unquote(s: &str) -> Result<(String, &str), HRESULT> {
    let mut chars = s.char_indices();
    if chars.next().map(|(_, c)| c) != Some('"') {
        return Err(E_INVALIDARG);
    }
    let mut out = String::new();
    while let Some((i, c)) = chars.next() {
        match c {
            '"' => return Ok((out, &s[i + 1..])),
            '\\' => match chars.next() {
                Some((_, e @ ('\\' | '"'))) => out.push(e),
                _ => return Err(E_INVALIDARG),
            },
            c => out.push(c),
        }
    }
    Err(E_INVALIDARG)
}

fn parse_hex_bytes(list: &str) -> Result<Vec<u8>, HRESULT> {
    let list = list.trim();
    if list.is_empty() {
        return Ok(Vec::new());
    }
    list.split(',')
        .map(|b| {
            let b = b.trim();
            if b.is_empty() || b.len() > 2 {
                return Err(E_INVALIDARG);
            }
            u8::from_str_radix(b, 16).map_err(|_| E_INVALIDARG)
        })
        .collect()
}

fn utf16_string(bytes: &[u8]) -> Result<String, HRESULT> {
    if bytes.len() % 2 != 0 {
        return Err(E_INVALIDARG);
    }
    let mut units: Vec<u16> = bytes.chunks(2).map(|c| u16::from_le_bytes([c[0], c[1]])).collect();
    if units.last() == Some(&0) {
        units.pop();
    }
    String::from_utf16(&units).map_err(|_| E_INVALIDARG)
}

/// Parses the data after `=`: `-` (delete) gives `None`.
fn parse_data(data: &str) -> Result<Option<RegValue>, HRESULT> {
    let data = data.trim();
    if data == "-" {
        return Ok(None);
    }
    if data.starts_with('"') {
        let (text, rest) = unquote(data)?;
        if !rest.trim().is_empty() {
            return Err(E_INVALIDARG);
        }
        return Ok(Some(RegValue::Sz(text)));
    }
    if let Some(d) = data.strip_prefix("dword:") {
        if d.is_empty() || d.len() > 8 {
            return Err(E_INVALIDARG);
        }
        return u32::from_str_radix(d, 16)
            .map(|v| Some(RegValue::Dword(v)))
            .map_err(|_| E_INVALIDARG);
    }
    let (kind, list) = if let Some(list) = data.strip_prefix("hex:") {
        (3, list)
    } else if let Some(rest) = data.strip_prefix("hex(") {
        let (kind, list) = rest.split_once("):").ok_or(E_INVALIDARG)?;
        (u32::from_str_radix(kind, 16).map_err(|_| E_INVALIDARG)?, list)
    } else {
        return Err(E_INVALIDARG);
    };
    let bytes = parse_hex_bytes(list)?;
    Ok(Some(match kind {
        1 => RegValue::Sz(utf16_string(&bytes)?),
        2 => RegValue::ExpandSz(utf16_string(&bytes)?),
        4 if bytes.len() == 4 => RegValue::Dword(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
        kind => RegValue::Other { kind, bytes },
    }))
}

/// Parses a registry file into the changes it asks for.
fn parse(text: &str) -> Result<Vec<Change>, HRESULT> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text.lines();
    let header = lines.next().map(str::trim).ok_or(E_INVALIDARG)?;
    if header != HEADER && header != "REGEDIT4" {
        return Err(E_INVALIDARG);
    }
    let mut changes = Vec::new();
    let mut key: Option<String> = None;
    while let Some(line) = lines.next() {
        let mut line = line.trim().to_string();
        // A trailing backslash continues hex data on the next line.
        while line.ends_with('\\') && line.contains("=hex") {
            line.pop();
            line.push_str(lines.next().ok_or(E_INVALIDARG)?.trim());
        }
        if line.is_empty() || line.starts_with(';') {
            continue;
        }
        if let Some(inner) = line.strip_prefix('[') {
            let inner = inner.strip_suffix(']').ok_or(E_INVALIDARG)?;
            if let Some(deleted) = inner.strip_prefix('-') {
                changes.push(Change::DeleteTree(key_path(deleted)?));
                key = None;
            } else {
                let path = key_path(inner)?;
                changes.push(Change::CreateKey(path.clone()));
                key = Some(path);
            }
            continue;
        }
        let path = key.clone().ok_or(E_INVALIDARG)?;
        let (name, rest) = if let Some(rest) = line.strip_prefix('@') {
            (String::new(), rest)
        } else {
            unquote(&line)?
        };
        if name.encode_utf16().count() > MAX_NAME_UNITS {
            return Err(E_INVALIDARG);
        }
        let data = rest.trim_start().strip_prefix('=').ok_or(E_INVALIDARG)?;
        changes.push(match parse_data(data)? {
            Some(value) => Change::Set(path, name, value),
            None => Change::DeleteValue(path, name),
        });
    }
    Ok(changes)
}

/// Deletes the key at `path` with its subtree, every key after its subkeys. A walk with its own
/// stack, not recursion: the depth of the tree costs no call stack.
fn delete_tree(reg: &dyn Registry, path: &str) -> Result<(), HRESULT> {
    // (key, its subkeys are gone already)
    let mut pending = vec![(path.to_string(), false)];
    while let Some((key, emptied)) = pending.pop() {
        if emptied {
            reg.delete_key(&key)?;
            continue;
        }
        let children = reg.subkeys(&key);
        pending.push((key.clone(), true));
        pending.extend(children.into_iter().map(|child| (format!("{key}\\{child}"), false)));
    }
    Ok(())
}

/// Applies a registry file to `reg`. Nothing is written when the text is malformed.
pub fn apply(reg: &dyn Registry, text: &str) -> Result<(), HRESULT> {
    for change in parse(text)? {
        match change {
            Change::CreateKey(path) => reg.create_key(&path)?,
            Change::DeleteTree(path) => delete_tree(reg, &path)?,
            Change::Set(path, name, value) => reg.set_value(&path, &name, &value)?,
            Change::DeleteValue(path, name) => reg.delete_value(&path, &name)?,
        }
    }
    Ok(())
}

/// Exports a subtree as the text of a `.reg` file, "Windows Registry Editor Version 5.00". On Windows
/// the registry view of the calling process is exported. Save it as UTF-16LE with a byte-order mark for
/// regedit.
///
/// # Parameters
/// - `reg`: the registry, or NULL for the system registry.
/// - `key`: the subtree's key, relative to HKEY_CLASSES_ROOT; NULL or "" for the whole registry (for
///   the system registry all of HKEY_CLASSES_ROOT, which is slow).
/// - `text` (out): receives the text (free it with `OpcTaskMemFree`), or NULL on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `text`; E_INVALIDARG for a key that is not valid UTF-16;
/// REGDB_E_KEYMISSING when `key` does not exist.
///
/// # Safety
/// `reg` NULL or a live handle; `key` NULL or NUL-terminated; `text` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcRegistryExport(reg: *const OpcRegistry, key: LPCWSTR, text: *mut LPWSTR) -> Hr {
    ffi::boundary!(Opc, [text], {
        // SAFETY: the caller's contract: `text` NULL or writable, `key` NULL or NUL-terminated.
        let (text, key) = unsafe { (ffi::out(text)?, ffi::in_string_opt(key)?) };
        // SAFETY: as above.
        let regs = unsafe { registries(reg) };
        text.write(alloc_wstr_from_str(&export(&*regs.write, &key.unwrap_or_default())?)?);
        Ok(S_OK)
    })
}

/// Applies the text of a `.reg` file to a registry. The whole text is checked first: a malformed file
/// changes nothing.
///
/// # Parameters
/// - `reg`: the registry, or NULL for the system registry.
/// - `text`: the file's text: keys and values under HKEY_CLASSES_ROOT, deletions with `[-key]` and
///   `"name"=-`.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `text`; E_INVALIDARG for malformed text or a root other than
/// HKEY_CLASSES_ROOT; a registry error (for example E_ACCESSDENIED) when a write fails, in which case
/// the changes before it remain.
///
/// # Safety
/// `reg` NULL or a live handle; `text` NULL or NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn OpcRegistryApply(reg: *const OpcRegistry, text: LPCWSTR) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: the caller's contract: `text` NULL or NUL-terminated.
        let text = unsafe { ffi::in_string(text) }?;
        // SAFETY: as above.
        let regs = unsafe { registries(reg) };
        apply(&*regs.write, &text)?;
        Ok(S_OK)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registry::memory::MemoryRegistry;

    fn sample() -> MemoryRegistry {
        let reg = MemoryRegistry::new();
        reg.set_value("Vendor.Server.1", "", &RegValue::Sz("A \"quoted\" C:\\path".into()))
            .unwrap();
        reg.set_value("Vendor.Server.1\\CLSID", "", &RegValue::Sz("{X}".into()))
            .unwrap();
        reg.create_key("Vendor.Server.1\\OPC").unwrap();
        reg.set_value("AppID\\{X}", "Lines", &RegValue::Sz("one\r\ntwo".into()))
            .unwrap();
        reg.set_value("AppID\\{X}", "Count", &RegValue::Dword(0xA)).unwrap();
        reg.set_value("AppID\\{X}", "Path", &RegValue::ExpandSz("%SystemRoot%".into()))
            .unwrap();
        reg.set_value(
            "AppID\\{X}",
            "Raw",
            &RegValue::Other {
                kind: 3,
                bytes: vec![0, 0xFF],
            },
        )
        .unwrap();
        reg
    }

    #[test]
    fn export_escapes_and_round_trips() {
        let reg = sample();
        let text = export(&reg, "").unwrap();
        assert!(text.starts_with("Windows Registry Editor Version 5.00\r\n\r\n[HKEY_CLASSES_ROOT\\AppID]\r\n"));
        assert!(text.contains("@=\"A \\\"quoted\\\" C:\\\\path\"\r\n"), "{text}");
        assert!(text.contains("\"Count\"=dword:0000000a\r\n"));
        assert!(text.contains("\"Raw\"=hex:00,ff\r\n"));
        assert!(text.contains("[HKEY_CLASSES_ROOT\\Vendor.Server.1\\OPC]\r\n"));
        let copy = MemoryRegistry::new();
        apply(&copy, &text).unwrap();
        assert_eq!(export(&copy, "").unwrap(), text);
        assert_eq!(
            copy.value("AppID\\{X}", "Lines"),
            Some(RegValue::Sz("one\r\ntwo".into()))
        );
    }

    #[test]
    fn export_of_a_missing_key_fails() {
        assert_eq!(export(&sample(), "Nope"), Err(REGDB_E_KEYMISSING));
        let sub = export(&sample(), "Vendor.Server.1\\OPC").unwrap();
        assert_eq!(
            sub,
            format!("{HEADER}\r\n\r\n[HKEY_CLASSES_ROOT\\Vendor.Server.1\\OPC]\r\n\r\n")
        );
    }

    #[test]
    fn deletions_and_continuations_apply() {
        let reg = sample();
        let text = "REGEDIT4\n; comment\n[-HKEY_CLASSES_ROOT\\Vendor.Server.1]\n[HKCR\\AppID\\{X}]\n\"Count\"=-\n\"Bin\"=hex:01,\\\n  02\n";
        apply(&reg, text).unwrap();
        assert!(!reg.key_exists("Vendor.Server.1"));
        assert_eq!(reg.value("AppID\\{X}", "Count"), None);
        assert_eq!(
            reg.value("AppID\\{X}", "Bin"),
            Some(RegValue::Other {
                kind: 3,
                bytes: vec![1, 2]
            })
        );
    }

    #[test]
    fn malformed_files_change_nothing() {
        let reg = MemoryRegistry::new();
        for bad in [
            "",
            "[HKEY_CLASSES_ROOT\\A]",
            "Windows Registry Editor Version 5.00\n[HKEY_LOCAL_MACHINE\\A]",
            "Windows Registry Editor Version 5.00\n[HKEY_CLASSES_ROOT\\A]\n\"x\"=\"unterminated",
            "Windows Registry Editor Version 5.00\n[HKEY_CLASSES_ROOT\\A]\n\"x\"=dword:123456789",
            "Windows Registry Editor Version 5.00\n[HKEY_CLASSES_ROOT\\A]\n\"x\"=\"bad \\q escape\"",
            "Windows Registry Editor Version 5.00\n\"x\"=\"no key\"",
            "Windows Registry Editor Version 5.00\n[HKEY_CLASSES_ROOT\\A]\n\"x\"=hex(1):41",
            "Windows Registry Editor Version 5.00\n[HKEY_CLASSES_ROOT\\A\\\\B]",
            "Windows Registry Editor Version 5.00\n[HKEY_CLASSES_ROOT\\A]\n\"x\"=hex:1,,2",
        ] {
            assert_eq!(apply(&reg, bad), Err(E_INVALIDARG), "{bad:?}");
        }
        // Names the registry refuses (found by the fuzz target: the key was written, then the value
        // refused): the whole file is refused before the first write.
        let long = "n".repeat(MAX_NAME_UNITS + 1);
        for bad in [
            format!("REGEDIT4\n[HKCR\\A]\n\"{long}\"=\"v\""),
            format!("REGEDIT4\n[HKCR\\A]\n\"{long}\"=-"),
            format!("REGEDIT4\n[HKCR\\A]\n[HKCR\\B\\{long}]"),
        ] {
            assert_eq!(apply(&reg, &bad), Err(E_INVALIDARG), "{bad:?}");
        }
        assert!(reg.subkeys("").is_empty());
        // The longest names are taken.
        let longest = "n".repeat(MAX_NAME_UNITS);
        let fits = format!("REGEDIT4\n[HKCR\\{longest}]\n\"{longest}\"=\"v\"");
        assert_eq!(apply(&reg, &fits), Ok(()));
        assert_eq!(reg.subkeys(""), vec![longest]);
    }

    #[test]
    #[cfg_attr(miri, ignore = "safe code only (no unsafe on its path), long under Miri")]
    fn keys_deeper_than_the_registry_are_refused_before_anything_changes() {
        // (Such files overflowed the stack: the export of 5,000 levels, `[-key]` of 20,000.)
        let reg = MemoryRegistry::new();
        for depth in [MAX_KEY_DEPTH + 1, 20_000] {
            let deep = vec!["k"; depth].join("\\");
            for bad in [
                format!("REGEDIT4\n[HKCR\\A]\n[HKCR\\{deep}]\n"),
                format!("REGEDIT4\n[HKCR\\A]\n[-HKCR\\{deep}]\n"),
            ] {
                assert_eq!(apply(&reg, &bad), Err(E_INVALIDARG), "{depth} levels");
            }
        }
        assert!(reg.subkeys("").is_empty());
    }

    #[test]
    #[cfg_attr(miri, ignore = "safe code only (no unsafe on its path), long under Miri")]
    fn the_deepest_keys_are_walked_without_recursion() {
        // Export, import of the export, `[-key]` deletion and freeing of a tree as deep as the
        // registry allows, in a thread with a small stack: a walk by recursion per level overflows it.
        std::thread::Builder::new()
            .stack_size(64 * 1024)
            .spawn(|| {
                let deepest = vec!["k"; MAX_KEY_DEPTH].join("\\");
                let reg = MemoryRegistry::new();
                apply(&reg, &format!("REGEDIT4\n[HKCR\\{deepest}]\n\"v\"=\"x\"\n")).unwrap();
                let text = export(&reg, "").unwrap();
                assert!(text.ends_with(&format!("[{ROOT}\\{deepest}]\r\n\"v\"=\"x\"\r\n\r\n")));
                let copy = MemoryRegistry::new();
                apply(&copy, &text).unwrap();
                assert_eq!(export(&copy, "").unwrap(), text);
                apply(&reg, "REGEDIT4\n[-HKCR\\k]\n").unwrap();
                assert!(reg.subkeys("").is_empty());
            })
            .unwrap()
            .join()
            .unwrap();
    }
}
