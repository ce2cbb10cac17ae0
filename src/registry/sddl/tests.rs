use super::*;

fn hex(text: &str) -> Vec<u8> {
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap())
        .collect()
}

/// SDDL text, the bytes Wine's ConvertStringSecurityDescriptorToSecurityDescriptorW gives for it, and
/// the text its ConvertSecurityDescriptorToStringSecurityDescriptorW gives back (recorded under Wine 8;
/// the Windows-target test below compares with the live functions).
const VECTORS: [(&str, &str, &str); 5] = [
    (
        "O:BAG:BAD:(A;;0xB;;;AU)(A;;0x1F;;;BA)(A;;0x1F;;;SY)",
        "010004801400000024000000000000003400000001020000000000052000000020020000010200000000000520000000\
         200200000200480003000000000014000b00000001010000000000050b000000000018001f000000010200000000000520\
         00000020020000000014001f000000010100000000000512000000",
        "O:BAG:BAD:(A;;CCDCSW;;;AU)(A;;CCDCLCSWRP;;;BA)(A;;CCDCLCSWRP;;;SY)",
    ),
    (
        "D:P(A;;CCDCSW;;;WD)",
        "010004900000000000000000000000001400000002001c0001000000000014000b000000010100000000000100000000",
        "D:P(A;;CCDCSW;;;WD)",
    ),
    (
        "O:SYD:AI(D;OICI;0x1F01FF;;;AN)(A;;GA;;;S-1-5-21-1-2-3-1001)",
        "0100048414000000000000000000000020000000010100000000000512000000020040000200000001031400ff011f00\
         0101000000000005070000000000240000000010010500000000000515000000010000000200000003000000e9030000",
        "O:SYD:AI(D;OICI;FA;;;AN)(A;;GA;;;S-1-5-21-1-2-3-1001)",
    ),
    ("D:", "01000480000000000000000000000000140000000200080000000000", "D:"),
    (
        "O:BA",
        "010000801400000000000000000000000000000001020000000000052000000020020000",
        "O:BA",
    ),
];

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn known_byte_vectors() {
    for (sddl, bytes, back) in VECTORS {
        let bytes: String = bytes.split_whitespace().collect();
        assert_eq!(sddl_to_bytes(sddl).unwrap(), hex(&bytes), "{sddl}");
        assert_eq!(bytes_to_sddl(&hex(&bytes)).unwrap(), back, "{sddl}");
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn round_trips() {
    for sddl in [
        "O:BAG:BAD:(A;;CCDCSW;;;AU)(A;;CCDCLCSWRP;;;BA)(A;;CCDCLCSWRP;;;SY)",
        "D:PARAI(A;OICINPIOIDSAFA;0x200;;;S-1-5-21-4294967295-0-7-500)",
        "O:S-1-5-21-1-2-3-500G:S-1-5-21-1-2-3-513D:(D;;CC;;;AN)(A;;FR;;;IU)(A;;KA;;;NS)",
        "G:LS",
        "D:(A;;;;;WD)",
        "O:S-1-5",
        "O:S-1-4294967295-1",
    ] {
        let bytes = sddl_to_bytes(sddl).unwrap_or_else(|e| panic!("{sddl}: {e:#x}"));
        assert_eq!(bytes_to_sddl(&bytes).unwrap(), sddl);
        assert_eq!(sddl_to_bytes(&bytes_to_sddl(&bytes).unwrap()).unwrap(), bytes);
    }
    for (alias, authority, subs) in ALIASES {
        let sddl = format!("O:{alias}");
        let sd = SecurityDescriptor::parse(&sddl).unwrap();
        assert_eq!(sd.owner.as_ref().unwrap().authority, authority);
        assert_eq!(sd.owner.as_ref().unwrap().sub_authorities, subs);
        let numeric: String = core::iter::once(format!("O:S-1-{authority}"))
            .chain(subs.iter().map(|s| format!("-{s}")))
            .collect();
        // A SID with an alias is written by its alias.
        assert_eq!(bytes_to_sddl(&sddl_to_bytes(&numeric).unwrap()).unwrap(), sddl);
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn rights_are_written_as_windows_writes_them() {
    for (mask, text) in [
        (0xB, "CCDCSW"),
        (0x1F, "CCDCLCSWRP"),
        (0x1F01FF, "FA"),
        (0x20019, "KR"),
        (0x10000000, "GA"),
        (0x200, "0x200"),
        (0x1000_0001, "CCGA"),
    ] {
        assert_eq!(rights_text(mask), text);
        assert_eq!(parse_rights(text).unwrap(), mask);
    }
    assert_eq!(parse_rights("11").unwrap(), 11);
    assert_eq!(parse_rights("0XfF").unwrap(), 255);
    assert_eq!(parse_rights("CCCC").unwrap(), 1, "a letter given twice is the same bit");
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn malformed_sddl_is_refused() {
    for bad in [
        "",
        "X:BA",
        "O:",
        "O:B",
        "O:XX",
        "O:DA",
        "O:S-1-",
        "O:S-2-5",
        "O:S-1-5-",
        "O:S-1-5--1",
        "O:S-1-01",
        "O:S-1-4294967296",
        "O:S-1-0x123456789ABC-1",
        "O:S-1-5-4294967296",
        "O:S-1-5-1-2-3-4-5-6-7-8-9-10-11-12-13-14-15-16",
        "O:BA ",
        " O:BA",
        "G:BAO:BA",
        "D:(A;;0xB;;;AU)O:BA",
        "O:BAO:BA",
        "D:(A;;0xB;;;AU",
        "D:A;;0xB;;;AU)",
        "D:(X;;0xB;;;AU)",
        "D:(OA;;0xB;;;AU)",
        "D:(A;;0xB;;;AU;x)",
        "D:(A;;0xB;;AU)",
        "D:(A;;0xB;00000000-0000-0000-0000-000000000000;;AU)",
        "D:(A;XX;0xB;;;AU)",
        "D:(A;CICI;0xB;;;AU)",
        "D:(A;;0x;;;AU)",
        "D:(A;;0x123456789;;;AU)",
        "D:(A;;0xG;;;AU)",
        "D:(A;;C;;;AU)",
        "D:(A;;ZZ;;;AU)",
        "D:(A;;-1;;;AU)",
        "D:(A;;010;;;AU)",
        "D:NO_ACCESS_CONTROL",
        "D:PP(A;;CC;;;WD)",
        "D:(A;;CC;;;WD)S:(AU;SA;CC;;;WD)",
        "D:(A;;CC;;;WD)x",
        "O:Bé",
        "O:é",
    ] {
        assert_eq!(sddl_to_bytes(bad), Err(E_INVALIDARG), "{bad:?}");
    }
    let too_many = format!("D:{}", "(A;;CC;;;WD)".repeat(MAX_ACES + 1));
    assert_eq!(sddl_to_bytes(&too_many), Err(E_INVALIDARG));
    let most = format!("D:{}", "(A;;CC;;;WD)".repeat(MAX_ACES));
    assert!(most.len() <= MAX_SDDL_CHARS);
    assert_eq!(
        SecurityDescriptor::parse(&most).unwrap().dacl.unwrap().1.len(),
        MAX_ACES
    );
    let too_long = format!("O:S-1-5{}", "-1".repeat(MAX_SDDL_CHARS));
    assert_eq!(sddl_to_bytes(&too_long), Err(E_INVALIDARG));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn malformed_binary_is_refused() {
    let good = sddl_to_bytes("O:BAG:BAD:(A;;0xB;;;AU)").unwrap();
    for cut in 0..good.len() {
        assert_eq!(bytes_to_sddl(&good[..cut]), Err(E_INVALIDARG), "cut at {cut}");
    }
    let mut absolute = good.clone();
    absolute[3] &= 0x7F; // not self-relative
    assert_eq!(bytes_to_sddl(&absolute), Err(E_INVALIDARG));
    let mut sacl = good.clone();
    sacl[12] = 0x14; // a SACL offset
    assert_eq!(bytes_to_sddl(&sacl), Err(E_INVALIDARG));
    let mut null_dacl = good.clone();
    null_dacl[16..20].copy_from_slice(&[0; 4]);
    assert_eq!(bytes_to_sddl(&null_dacl), Err(E_INVALIDARG));
    let mut into_header = good.clone();
    into_header[4] = 4;
    assert_eq!(bytes_to_sddl(&into_header), Err(E_INVALIDARG));
    let mut huge = good.clone();
    huge[16..20].copy_from_slice(&u32::MAX.to_le_bytes());
    assert_eq!(bytes_to_sddl(&huge), Err(E_INVALIDARG));
    let dacl = u32::from_le_bytes(good[16..20].try_into().unwrap()) as usize;
    let mut object_ace = good.clone();
    object_ace[dacl + 8] = 5; // ACCESS_ALLOWED_OBJECT_ACE_TYPE
    assert_eq!(bytes_to_sddl(&object_ace), Err(E_INVALIDARG));
    let mut short_ace = good.clone();
    short_ace[dacl + 10] = 12; // an ACE smaller than its SID
    assert_eq!(bytes_to_sddl(&short_ace), Err(E_INVALIDARG));
    // Found by the fuzz target: a descriptor with nothing in it has no SDDL of the subset.
    let mut empty = vec![0u8; 20];
    empty[0] = 1;
    empty[3] = 0x80;
    assert_eq!(bytes_to_sddl(&empty), Err(E_INVALIDARG));
    empty.extend_from_slice(&[0; 30]);
    assert_eq!(bytes_to_sddl(&empty), Err(E_INVALIDARG));
    let mut more_aces = good.clone();
    more_aces[dacl + 4] = 2; // counts an ACE that is not there
    assert_eq!(bytes_to_sddl(&more_aces), Err(E_INVALIDARG));
}

/// A cheap property test: random edits of valid SDDL and random bytes never panic, and whatever
/// parses round-trips through the binary form.
#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn random_input_never_panics() {
    let mut seed = 0x2545F4914F6CDD1Du64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let alphabet: Vec<char> = "OGDSA:;()-0123456789xXBAUWDYPICNé ".chars().collect();
    let base = "O:BAG:BAD:P(A;;0xB;;;AU)(D;OICI;CCDC;;;S-1-5-21-1-2-3)";
    for _ in 0..20_000 {
        let mut text: Vec<char> = base.chars().collect();
        for _ in 0..(next() % 4 + 1) {
            let at = (next() as usize) % (text.len() + 1);
            let c = alphabet[(next() as usize) % alphabet.len()];
            match next() % 3 {
                0 if at < text.len() => text[at] = c,
                1 if at < text.len() => {
                    text.remove(at);
                }
                _ => text.insert(at, c),
            }
        }
        let text: String = text.into_iter().collect();
        if let Ok(sd) = SecurityDescriptor::parse(&text) {
            let bytes = sd.to_bytes();
            assert_eq!(SecurityDescriptor::from_bytes(&bytes).as_ref(), Ok(&sd), "{text}");
            assert_eq!(SecurityDescriptor::parse(&sd.to_sddl()).as_ref(), Ok(&sd), "{text}");
        }
    }
    let good = sddl_to_bytes(base).unwrap();
    for _ in 0..20_000 {
        let mut bytes = good.clone();
        for _ in 0..(next() % 4 + 1) {
            let at = (next() as usize) % bytes.len();
            bytes[at] = next() as u8;
        }
        if let Ok(sd) = SecurityDescriptor::from_bytes(&bytes) {
            assert_eq!(SecurityDescriptor::from_bytes(&sd.to_bytes()).as_ref(), Ok(&sd));
        }
    }
}

/// Under Windows (Wine in the tests): the library's bytes are the system's, byte for byte, and the
/// system reads them back as the library's SDDL.
#[cfg(windows)]
#[test]
fn same_bytes_as_the_system() {
    use crate::com::LPWSTR;
    #[link(name = "advapi32")]
    extern "system" {
        fn ConvertStringSecurityDescriptorToSecurityDescriptorW(
            s: *const u16,
            revision: u32,
            sd: *mut *mut core::ffi::c_void,
            size: *mut u32,
        ) -> i32;
        fn ConvertSecurityDescriptorToStringSecurityDescriptorW(
            sd: *const core::ffi::c_void,
            revision: u32,
            info: u32,
            s: *mut LPWSTR,
            len: *mut u32,
        ) -> i32;
    }
    #[link(name = "kernel32")]
    extern "system" {
        fn LocalFree(p: *mut core::ffi::c_void) -> *mut core::ffi::c_void;
    }
    let mut cases: Vec<String> = VECTORS.iter().map(|(s, _, _)| s.to_string()).collect();
    cases.extend(
        [
            "D:PAI(A;;0x3;;;IU)(A;OICI;CCDCLCSWRP;;;S-1-5-21-1-2-3-4)(D;;GA;;;AN)",
            "O:NSG:LSD:AR(A;;KA;;;NU)(A;;FR;;;PS)(A;;FW;;;RC)(A;;FX;;;SU)(A;;KW;;;ED)",
            "D:(A;NPIOIDSAFA;0x12345678;;;WD)",
            "O:S-1-9-1G:S-1-5-32-999D:(A;;11;;;S-1-0-0)",
        ]
        .map(String::from),
    );
    // Wine 8 does not know these documented aliases (Performance Monitor Users, Performance Log
    // Users, IIS_IUSRS, Event Log Readers): Windows only.
    let unknown_to_wine = ["MU", "LU", "IS", "ER"];
    cases.extend(
        ALIASES
            .iter()
            .filter(|(alias, _, _)| !unknown_to_wine.contains(alias))
            .map(|(alias, _, _)| format!("O:{alias}D:(A;;0x1F;;;{alias})")),
    );
    for sddl in cases {
        let wide: Vec<u16> = sddl.encode_utf16().chain(Some(0)).collect();
        let (mut sd, mut size) = (core::ptr::null_mut(), 0u32);
        // SAFETY: a NUL-terminated string and writable out-parameters; the result is freed below.
        let ok = unsafe { ConvertStringSecurityDescriptorToSecurityDescriptorW(wide.as_ptr(), 1, &mut sd, &mut size) };
        assert_ne!(ok, 0, "the system refuses {sddl}");
        // SAFETY: the system returned `size` bytes at `sd`.
        let system = unsafe { core::slice::from_raw_parts(sd.cast::<u8>(), size as usize) }.to_vec();
        // SAFETY: allocated by the call above, freed once.
        unsafe { LocalFree(sd) };
        let ours = sddl_to_bytes(&sddl).unwrap();
        assert_eq!(ours, system, "{sddl}");
        let mut text: LPWSTR = core::ptr::null_mut();
        // SAFETY: `ours` is a valid self-relative descriptor; OWNER|GROUP|DACL_SECURITY_INFORMATION.
        let ok = unsafe {
            ConvertSecurityDescriptorToStringSecurityDescriptorW(
                ours.as_ptr().cast(),
                1,
                7,
                &mut text,
                core::ptr::null_mut(),
            )
        };
        assert_ne!(ok, 0, "the system cannot read ours for {sddl}");
        // SAFETY: a NUL-terminated string the system allocated, read then freed once.
        let back = unsafe {
            let len = (0..).take_while(|&i| *text.add(i) != 0).count();
            let back = String::from_utf16_lossy(core::slice::from_raw_parts(text, len));
            LocalFree(text.cast());
            back
        };
        assert_eq!(back, bytes_to_sddl(&ours).unwrap(), "{sddl}");
    }
}
