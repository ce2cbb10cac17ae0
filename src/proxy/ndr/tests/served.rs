//! Every method of every interface the proxy/stub serves (src/proxy/generated/layouts.rs: OPC Common
//! and Data Access), with messages made from the layouts themselves: every integer 1 (so every count
//! is 1 and agrees with its array), every pointer set, strings of one character, VARIANTs of VT_I4,
//! interface pointers NULL. Each request and each reply passes, and every proper prefix of it is
//! refused; the same messages are the `layouts` fuzz target's seeds. Nothing here is written per
//! method: a method added to the IDL is covered by the next run.

use super::build::{Msg, V};
use super::*;
use crate::proxy::layouts::Interface as S;
use crate::proxy::ndr::layout::{Array, Extent, Ty};

const REF: u32 = 0x20000;

/// A value that is not embedded in a construct: a parameter, or a pointee.
fn top(m: Msg, ty: Ty, d: Dialect) -> Msg {
    match ty {
        Ty::Pointer(p) => top(if p.unique { m.u32(REF) } else { m }, p.target, d),
        Ty::Str(2) => m.wstr("a"),
        Ty::Str(_) => m.cstr("a"),
        Ty::Interface(_) => m.u32(0),
        Ty::Bstr => m.user(d, 4, |m| m.blob(Some("a"))),
        Ty::Variant => m.user(d, 8, |m| m.variant(&V::I4(1), d)),
        Ty::SafeArray => m.user(d, 4, |m| m.safearray(None, d)),
        _ => deferred(flat(m, ty), ty, d),
    }
}

/// A value's flat part inside a construct.
fn flat(m: Msg, ty: Ty) -> Msg {
    match ty {
        Ty::Base(1) => m.u8(1),
        Ty::Base(2) | Ty::Enum16 => m.u16(1),
        Ty::Base(8) => m.u64(1),
        Ty::Base(_) => m.u32(1),
        Ty::Guid => m.guid([0; 16]),
        Ty::Empty => m,
        Ty::Bstr | Ty::Variant | Ty::SafeArray => m.u32(USER),
        Ty::Pointer(_) => m.u32(REF),
        Ty::Struct(s) => s.fields.iter().fold(m.align(usize::from(s.align)), |m, f| flat(m, *f)),
        Ty::Array(a) => {
            let (m, n) = header(m, a);
            (0..n).fold(m.align(usize::from(a.align)), |m, _| flat(m, a.elem))
        }
        Ty::Union(_) | Ty::Str(_) | Ty::Interface(_) => panic!("no served layout has {ty:?} here"),
    }
}

/// An array's conformance and variance; its number of elements.
fn header(m: Msg, a: &Array) -> (Msg, u32) {
    let (m, n) = match a.size {
        Extent::Fixed(n) => (m, n),
        Extent::Conformant(_) => (m.u32(1), 1),
    };
    (if a.length.is_some() { m.u32(0).u32(n) } else { m }, n)
}

/// The pointees of a value's flat part, in the order of their pointers.
fn deferred(m: Msg, ty: Ty, d: Dialect) -> Msg {
    match ty {
        Ty::Pointer(p) => top(m, p.target, d),
        Ty::Bstr => m.align(if d == Dialect::Wine { 8 } else { 4 }).blob(Some("a")),
        Ty::Variant => m.variant(&V::I4(1), d),
        Ty::SafeArray => m.safearray(None, d),
        Ty::Struct(s) => s.fields.iter().fold(m, |m, f| deferred(m, *f, d)),
        Ty::Array(a) => {
            let n = match a.size {
                Extent::Fixed(n) => n,
                Extent::Conformant(_) => 1,
            };
            (0..n).fold(m, |m, _| deferred(m, a.elem, d))
        }
        _ => m,
    }
}

/// A served method's request and reply made from its layout, with the context the request gives the
/// reply: (interface, vtable index, method name, request, context, reply).
pub(super) fn messages(d: Dialect) -> Vec<(S, u32, &'static str, Msg, Context, Msg)> {
    let mut out = Vec::new();
    for &iface in S::all() {
        for (i, method) in iface.layout().methods.iter().enumerate() {
            let index = 3 + i as u32;
            let request = method.request.iter().fold(Msg::default(), |m, p| top(m, p.ty, d));
            let context = check_request(iface.layout(), index, request.aligned().bytes(), LOCAL, d)
                .unwrap_or_else(|e| panic!("{iface:?}::{} request {e:#x}: {:02x?}", method.name, request.0));
            let reply = method.reply.iter().fold(Msg::default(), |m, p| top(m, p.ty, d));
            out.push((iface, index, method.name, request, context, reply));
        }
    }
    out
}

#[test]
#[cfg_attr(
    miri,
    ignore = "every prefix of every message of 100 methods: the native run checks it"
)]
fn every_served_method_reads_its_own_messages() {
    let mut methods = 0;
    for d in BOTH {
        for (iface, index, name, request, context, reply) in messages(d) {
            let l = iface.layout();
            whole(|b| check_request(l, index, b, LOCAL, d).map(|_| ()), &request);
            let r = check_reply(l, index, &context, reply.aligned().bytes(), LOCAL, d);
            assert_eq!(r, Ok(()), "{iface:?}::{name} reply {d:?}: {:02x?}", reply.0);
            whole(|b| check_reply(l, index, &context, b, LOCAL, d), &reply);
            methods += 1;
        }
        // One past the last method of each interface is refused.
        for &iface in S::all() {
            let past = iface.layout().vtable;
            assert_eq!(
                check_request(iface.layout(), past, &[0; 64], LOCAL, d),
                Err(PROCNUM_OUT_OF_RANGE)
            );
        }
    }
    assert!(
        methods >= 2 * 95,
        "{methods}: OPC Common's 16 and Data Access's 80, each way"
    );
}

/// The `layouts` fuzz target's input: byte 0 the interface, byte 1 the method (from 3), byte 2 bit 0
/// Wine's dialect and bit 1 a reply, bytes 3 to 18 the reply's context (four words), then the message.
fn fuzz_input(iface: S, index: u32, d: Dialect, reply: bool, context: &Context, m: &Msg) -> Vec<u8> {
    let mut input = vec![
        iface as u8,
        (index - 3) as u8,
        u8::from(d == Dialect::Wine) | (u8::from(reply) << 1),
    ];
    for w in &context.0[..4] {
        input.extend_from_slice(&w.to_le_bytes());
    }
    input.extend_from_slice(&m.0);
    input
}

fn seeds() -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for d in BOTH {
        for (iface, index, name, request, context, reply) in messages(d) {
            let tag = format!("{iface:?}-{name}-{d:?}");
            out.push((
                format!("{tag}-request"),
                fuzz_input(iface, index, d, false, &Context::default(), &request),
            ));
            out.push((
                format!("{tag}-reply"),
                fuzz_input(iface, index, d, true, &context, &reply),
            ));
        }
    }
    out
}

#[test]
#[cfg_attr(miri, ignore = "reads the committed seed files")]
fn the_layouts_fuzz_seeds_are_current() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/layouts");
    for (name, input) in seeds() {
        let committed = std::fs::read(dir.join(&name)).unwrap_or_default();
        assert!(
            committed == input,
            "fuzz/seeds/layouts/{name} is not current: cargo test --lib write_layouts_fuzz_seeds -- --ignored"
        );
    }
}

/// Writes the seeds to fuzz/seeds/layouts: `cargo test --lib write_layouts_fuzz_seeds -- --ignored`.
#[test]
#[ignore = "writes the fuzz target's seed corpus"]
fn write_layouts_fuzz_seeds() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/layouts");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (name, input) in seeds() {
        std::fs::write(dir.join(name), input).unwrap();
    }
}

/// The C header the proxy/stub's hostile-message tests read (tests/oop/ps_served.h): every served
/// method's request and reply of both dialects, with the interface's IID and the reply's context.
fn c_header() -> String {
    use core::fmt::Write;
    let mut s = String::from(
        "/* Generated by src/proxy/ndr/tests/served.rs from the proxy/stub's layouts (src/proxy/generated/\n\
         \x20* layouts.rs): do not edit (`cargo test --lib write_served_messages -- --ignored`; the test\n\
         \x20* the_served_messages_are_current fails when this file is not what they make).\n\
         \x20*\n\
         \x20* A request and a reply of every method of every interface opccomn.dll's proxy/stub serves,\n\
         \x20* made from its layout (every integer 1, every pointer set, strings of one character, VARIANTs of\n\
         \x20* VT_I4, interface pointers NULL), in NDR's dialect and in Wine's, with the context the request\n\
         \x20* gives the reply check. tests/oop/test_served_messages.c sends them, cut short and mutated, into\n\
         \x20* every stub and back through every proxy. */\n\n\
         typedef struct ps_served {\n    const char *iface;\n    GUID iid;\n    unsigned spec_common;\n    unsigned method;\n    const char *name;\n    unsigned wine;\n    unsigned request_len;\n    const unsigned char *request;\n    unsigned reply_len;\n    const unsigned char *reply;\n    unsigned context[8];\n} ps_served;\n\n",
    );
    let bytes = |b: &[u8]| -> String {
        if b.is_empty() {
            return "0".into();
        }
        b.iter().map(|x| format!("{x}")).collect::<Vec<_>>().join(",")
    };
    let mut rows = Vec::new();
    let mut n = 0;
    for d in BOTH {
        for (iface, index, name, request, context, reply) in messages(d) {
            let l = iface.layout();
            let _ = writeln!(
                s,
                "static const unsigned char ps_served_q{n}[] = {{{}}};",
                bytes(&request.0)
            );
            let _ = writeln!(
                s,
                "static const unsigned char ps_served_r{n}[] = {{{}}};",
                bytes(&reply.0)
            );
            let g = l.iid;
            let iid = format!(
                "{{0x{:08X}, 0x{:04X}, 0x{:04X}, {{{}}}}}",
                u32::from_le_bytes([g[0], g[1], g[2], g[3]]),
                u16::from_le_bytes([g[4], g[5]]),
                u16::from_le_bytes([g[6], g[7]]),
                g[8..]
                    .iter()
                    .map(|x| format!("0x{x:02X}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            let common = crate::proxy::wire::COMMON.contains(&iface);
            rows.push(format!(
                "    {{\"{}\", {iid}, {}, {index}, \"{name}\", {}, {}, ps_served_q{n}, {}, ps_served_r{n}, {{{}}}}},",
                l.name,
                u8::from(common),
                u8::from(d == Dialect::Wine),
                request.0.len(),
                reply.0.len(),
                context.0.iter().map(u32::to_string).collect::<Vec<_>>().join(", ")
            ));
            n += 1;
        }
    }
    let _ = writeln!(s, "\nstatic const ps_served PS_SERVED[] = {{\n{}\n}};", rows.join("\n"));
    let _ = writeln!(s, "#define PS_SERVED_COUNT {n}");
    s
}

const C_HEADER: &str = "tests/oop/ps_served.h";

#[test]
#[cfg_attr(miri, ignore = "reads the committed header")]
fn the_served_messages_are_current() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(C_HEADER);
    let committed = std::fs::read_to_string(path).unwrap_or_default();
    assert!(
        committed == c_header(),
        "{C_HEADER} is not current: cargo test --lib write_served_messages -- --ignored"
    );
}

/// Writes tests/oop/ps_served.h: `cargo test --lib write_served_messages -- --ignored`.
#[test]
#[ignore = "writes the C tests' messages"]
fn write_served_messages() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(C_HEADER);
    std::fs::write(path, c_header()).unwrap();
}
