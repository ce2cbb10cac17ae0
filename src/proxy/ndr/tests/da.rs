//! The layouts of the Data Access interfaces (src/proxy/generated/layouts.rs, from idl/opcda.idl):
//! the DA structures as the engine writes them (OPCITEMDEF, OPCITEMRESULT, OPCITEMSTATE, OPCITEMVQT,
//! OPCITEMPROPERTIES with OPCITEMPROPERTY, OPCBROWSEELEMENT) and VARIANT values among them, the bounds
//! of idl/ndr-bounds.txt, and replies Wine's NDR engine wrote for the cross-process test
//! (tests/oop/test_da_tables.c). OPCITEMHEADER1/2 and the other DA 1.0 stream headers travel inside
//! the HGLOBALs of IDataObject, which the system marshals: no DA method carries them.

use super::build::{Msg, V};
use super::*;
use crate::proxy::layouts::Interface as D;

const S_OK_: u32 = 0;
const REF: u32 = 0x20000;

fn idx(iface: D, name: &str) -> u32 {
    let i = iface.layout().methods.iter().position(|m| m.name == name);
    3 + i.unwrap_or_else(|| panic!("{iface:?} has no {name}")) as u32
}

fn req(iface: D, name: &str, m: &Msg, d: Dialect) -> Result<Context, HRESULT> {
    check_request(iface.layout(), idx(iface, name), m.aligned().bytes(), LOCAL, d)
}

fn rep(iface: D, name: &str, ctx: &Context, m: &Msg, d: Dialect) -> Check {
    check_reply(iface.layout(), idx(iface, name), ctx, m.aligned().bytes(), LOCAL, d)
}

fn whole_req(iface: D, name: &str, m: &Msg, d: Dialect) -> Context {
    let i = idx(iface, name);
    whole(|b| check_request(iface.layout(), i, b, LOCAL, d).map(|_| ()), m);
    req(iface, name, m, d).unwrap()
}

fn whole_rep(iface: D, name: &str, ctx: &Context, m: &Msg, d: Dialect) {
    let i = idx(iface, name);
    whole(|b| check_reply(iface.layout(), i, ctx, b, LOCAL, d), m);
}

fn hex(parts: &[&str]) -> Msg {
    let h: String = parts.concat().trim().to_string();
    Msg((0..h.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&h[i..i + 2], 16).unwrap())
        .collect())
}

/// IOPCSyncIO::Read of 5 items (an invalid handle among them), as Wine's engine (x64) wrote the reply:
/// OPCITEMSTATE elements of 24 bytes (the structure is 8-aligned for its VARIANT), the VARIANTs
/// (VT_I4, VT_R8, VT_BSTR, VT_ARRAY | VT_R8, VT_EMPTY) after them, then the HRESULTs.
const SYNC_READ_REPLY: &[&str] = &[
    "0000020005000000e803000000c134fb2d67dc01c00000005573657200000000e90300008057cdfb2d67dc01c0000000",
    "5573657200000000ea03000000ee65fc2d67dc01c00000005573657200000000eb0300008084fefc2d67dc01c0000000",
    "557365720000000000000000000000000000000000000000557365720000000003000000000000000300000000000000",
    "03000000393000000400000000000000050000000000000005000000000000000000000000000a400800000000000000",
    "080000000000000008000000184035000d0000001a0000000d000000540061006e006b002000e400f600fc002000ac20",
    "20003dd800de00000c000000000000000520000000000000002000006040350001000000010000000100800008000000",
    "0000050014000000030000000200000003000000000000000300000000000000000000000000f83f00000000000000c0",
    "9c7500883ce4377e03000000000000000000000000000000000000000400020005000000000000000000000000000000",
    "00000000010004c001000000",
];

/// IOPCBrowse::GetProperties of 3 items, as Wine's engine (x64) wrote the reply: OPCITEMPROPERTIES
/// with their OPCITEMPROPERTY arrays (strings and VARIANT values).
const GET_PROPERTIES_REPLY: &[&str] = &[
    "000002000300000000000000020000000400020000000000070004c00000000000000000000000000000000002000000",
    "140002000000000002000000000000000200000001000000000000000800020055736572000000000000000000000000",
    "08000000650000000c000200100002005573657200000000000000001900000000000000190000004900740065006d00",
    "2000430061006e006f006e006900630061006c0020004400610074006100200054007900700065000000000000000000",
    "03000000000000000200000000000000020000000800000026000000000000002600000050006c0061006e0074002e00",
    "540061006e006b0031002e004e0061006d00650020002800420053005400520029002000ac202e004400650073006300",
    "720069007000740069006f006e0000001100000000000000110000004900740065006d00200044006500730063007200",
    "69007000740069006f006e00000000000f00000000000000080000000000000008000000884735002800000050000000",
    "280000004400650073006300720069007000740069006f006e0020006f006600200050006c0061006e0074002e005400",
    "61006e006b0031002e004e0061006d00650020002800420053005400520029002000ac20020000000200000001000000",
    "00000000180002005573657200000000000000000000000008000000650000001c000200200002005573657200000000",
    "000000001900000000000000190000004900740065006d002000430061006e006f006e006900630061006c0020004400",
    "610074006100200054007900700065000000000000000000030000000000000002000000000000000200000003000000",
    "23000000000000002300000050006c0061006e0074002e00540061006e006b0031002e004c006500760065006c002000",
    "28004900340029002e004400650073006300720069007000740069006f006e0000000000110000000000000011000000",
    "4900740065006d0020004400650073006300720069007000740069006f006e0000000000000000000e00000000000000",
    "08000000000000000800000048593500250000004a000000250000004400650073006300720069007000740069006f00",
    "6e0020006f006600200050006c0061006e0074002e00540061006e006b0031002e004c006500760065006c0020002800",
    "490034002900000001000000",
];

/// IOPCAsyncIO::Write(1, 1, {1}, {VT_I4 3}) as Wine's engine (x64, the widl tables) wrote the request:
/// the array of VARIANTs starts at 8 after its conformance (the format string's array has VARIANT's
/// alignment), with 4 bytes of padding before the first element's place.
const ASYNC_WRITE_REQUEST: &[&str] = &[
    "0100000001000000010000000100000001000000000000005573657200000000",
    "030000000000000003000000000000000300000001000000",
];

#[test]
fn an_array_of_variants_starts_at_8() {
    let wine = hex(ASYNC_WRITE_REQUEST);
    assert_eq!(wine.0.len(), 56);
    for d in [Dialect::Ndr, Dialect::Wine] {
        assert_eq!(whole_req(D::IOPCAsyncIO, "Write", &wine, d), Context::of(&[1]));
        // Without the padding the engine reads the first element's place at 24 from the message's
        // end: refused.
        let mut packed = wine.0.clone();
        packed.drain(20..24);
        assert!(req(D::IOPCAsyncIO, "Write", &Msg(packed), d).is_err());
    }
}

#[test]
fn replies_wines_engine_wrote_pass_and_their_prefixes_do_not() {
    whole_rep(
        D::IOPCSyncIO,
        "Read",
        &Context::of(&[5]),
        &hex(SYNC_READ_REPLY),
        Dialect::Wine,
    );
    whole_rep(
        D::IOPCBrowse,
        "GetProperties",
        &Context::of(&[3]),
        &hex(GET_PROPERTIES_REPLY),
        Dialect::Wine,
    );
    // Another count than the request's is refused: the caller's arrays are sized by dwCount.
    for n in [4, 6, 0] {
        assert_eq!(
            rep(
                D::IOPCSyncIO,
                "Read",
                &Context::of(&[n]),
                &hex(SYNC_READ_REPLY),
                Dialect::Wine
            ),
            Err(BAD_STUB_DATA),
            "{n}"
        );
    }
}

/// One OPCITEMSTATE's flat part: hClient, ftTimeStamp, wQuality, wReserved, the VARIANT's place.
fn item_state(m: Msg, client: u32) -> Msg {
    m.align(8)
        .u32(client)
        .u32(0x1111)
        .u32(0x2222)
        .u16(0xC0)
        .u16(0)
        .u32(USER)
}

#[test]
fn opcitemstate_elements_are_8_aligned_with_their_variants_after_them() {
    for d in [Dialect::Ndr, Dialect::Wine] {
        let values = [V::I4(12345), V::Bstr(Some("Tank".into())), V::R8(3.25)];
        let mut m = Msg::default().u32(REF).u32(3);
        for (i, _) in values.iter().enumerate() {
            m = item_state(m, 1000 + i as u32);
        }
        for v in &values {
            m = m.variant(v, d);
        }
        let good = m.u32(REF).u32(3).u32(0).u32(0).u32(0).u32(S_OK_);
        whole_rep(D::IOPCSyncIO, "Read", &Context::of(&[3]), &good, d);
        // Elements of 20 bytes (4-aligned): the engine would read the second one from the padding.
        let mut packed = Msg::default().u32(REF).u32(3);
        for i in 0..3 {
            packed = packed.u32(1000 + i).u32(0x1111).u32(0x2222).u16(0xC0).u16(0).u32(USER);
        }
        for v in &values {
            packed = packed.variant(v, d);
        }
        let packed = packed.u32(REF).u32(3).u32(0).u32(0).u32(0).u32(S_OK_);
        assert!(rep(D::IOPCSyncIO, "Read", &Context::of(&[3]), &packed, d).is_err());
    }
}

/// One OPCITEMDEF's flat part (access path NULL, item ID, active, client handle, blob, type).
fn item_def(m: Msg, client: u32, blob: u32) -> Msg {
    m.u32(0)
        .u32(REF)
        .u32(1)
        .u32(client)
        .u32(blob)
        .u32(if blob > 0 { REF } else { 0 })
        .u16(3)
        .u16(0)
}

fn add_items(blob: u32, conformance: u32) -> Msg {
    let m = item_def(item_def(Msg::default().u32(2).u32(2), 1, 0), 2, blob);
    let m = m.wstr("Plant.Tank1.Level").wstr("Plant.Tank1.Temp");
    if blob == 0 {
        return m;
    }
    let mut m = m.u32(conformance);
    for i in 0..conformance.min(blob) {
        m = m.u8(i as u8);
    }
    m
}

#[test]
fn opcitemdef_strings_and_blobs_are_checked_against_their_counts() {
    for d in [Dialect::Ndr, Dialect::Wine] {
        let ctx = whole_req(D::IOPCItemMgt, "AddItems", &add_items(5, 5), d);
        assert_eq!(ctx, Context::of(&[2]), "the reply's arrays are sized by dwCount");
        assert_eq!(req(D::IOPCItemMgt, "AddItems", &add_items(5, 6), d), Err(BAD_STUB_DATA));
        // A blob beyond its bound (65,536 bytes, idl/ndr-bounds.txt) is refused as MIDL's [range] does.
        // (Not under Miri: `whole_req` checks every cut of the message, and the message is 64 KiB.)
        if !cfg!(miri) {
            assert_eq!(
                req(D::IOPCItemMgt, "AddItems", &add_items(65_537, 65_537), d),
                Err(INVALID_BOUND)
            );
            whole_req(D::IOPCItemMgt, "AddItems", &add_items(65_536, 65_536), d);
        }
    }
}

#[test]
fn opcitemresult_blobs_are_counted_by_their_own_field() {
    // hServer, vtCanonicalDataType, wReserved, dwAccessRights, dwBlobSize, pBlob; then the blob.
    let result = |blob: u32, sent: u32| {
        let mut m = Msg::default()
            .u32(REF)
            .u32(1)
            .u32(100)
            .u16(5)
            .u16(0)
            .u32(3)
            .u32(blob)
            .u32(REF);
        m = m.u32(sent);
        for i in 0..sent {
            m = m.u8(i as u8);
        }
        m.u32(REF).u32(1).u32(0).u32(S_OK_)
    };
    for d in [Dialect::Ndr, Dialect::Wine] {
        whole_rep(D::IOPCItemMgt, "AddItems", &Context::of(&[1]), &result(3, 3), d);
        assert_eq!(
            rep(D::IOPCItemMgt, "AddItems", &Context::of(&[1]), &result(3, 4), d),
            Err(BAD_STUB_DATA)
        );
        // (Not under Miri, where building the 70,000-byte blob alone takes minutes.)
        if !cfg!(miri) {
            assert_eq!(
                rep(
                    D::IOPCItemMgt,
                    "AddItems",
                    &Context::of(&[1]),
                    &result(70_000, 70_000),
                    d
                ),
                Err(INVALID_BOUND)
            );
        }
        // Two results announced, one sent.
        assert!(rep(D::IOPCItemMgt, "AddItems", &Context::of(&[2]), &result(3, 3), d).is_err());
    }
}

#[test]
fn opcitemvqt_values_are_read_as_variants() {
    // IOPCSyncIO2::WriteVQT(dwCount, phServer, pItemVQT): each OPCITEMVQT is 8-aligned.
    for d in [Dialect::Ndr, Dialect::Wine] {
        // vDataValue's place, bQualitySpecified, wQuality, wReserved, bTimeStampSpecified, dwReserved,
        // ftTimeStamp; the VARIANTs after the elements.
        let build = |second: V| {
            let mut m = Msg::default().u32(2).u32(2).u32(100).u32(101).u32(2);
            for _ in 0..2 {
                m = m
                    .align(8)
                    .u32(USER)
                    .u32(1)
                    .u16(0xC0)
                    .u16(0)
                    .u32(1)
                    .u32(0)
                    .u32(0x3333)
                    .u32(0x4444);
            }
            m.variant(&V::R8(1.5), d).variant(&second, d)
        };
        whole_req(D::IOPCSyncIO2, "WriteVQT", &build(V::Bstr(Some("text".into()))), d);
        whole_req(D::IOPCSyncIO2, "WriteVQT", &build(V::I4(7)), d);
        // A VARIANT of a type no VARIANT may have (VT_RECORD | VT_BYREF...) is refused.
        assert_eq!(
            req(
                D::IOPCSyncIO2,
                "WriteVQT",
                &build(V::Raw(0x4024, 0x4024, vec![0; 8])),
                d
            ),
            Err(BAD_STUB_DATA)
        );
    }
}

#[test]
fn opcbrowseelement_carries_its_properties() {
    // IOPCBrowse::Browse's reply: continuation point, bMoreElements, *pdwCount, the elements.
    // `props` properties counted, `conformance` on the wire, `sent` of them there.
    let element = |props: u32, conformance: u32, sent: u32| {
        let mut m = Msg::default()
            .u32(REF)
            .wstr("cp:3")
            .u32(1)
            .u32(1)
            .u32(REF)
            .u32(1)
            // szName, szItemID, dwFlagValue, dwReserved, ItemProperties (hrErrorID, count, pointer, reserved)
            .u32(REF)
            .u32(REF)
            .u32(2)
            .u32(0)
            .u32(0)
            .u32(props)
            .u32(if props > 0 { REF } else { 0 })
            .u32(0)
            .wstr("Level")
            .wstr("Plant.Tank1.Level");
        if props > 0 {
            m = m.u32(conformance);
            for _ in 0..sent {
                // vtDataType, wReserved, dwPropertyID, szItemID, szDescription, vValue, hrErrorID, dwReserved
                m = m.align(8).u16(3).u16(0).u32(1).u32(0).u32(REF).u32(USER).u32(0).u32(0);
            }
            for _ in 0..sent {
                m = m.wstr("Item Canonical DataType").variant(&V::I4(3), Dialect::Wine);
            }
        }
        m.u32(S_OK_)
    };
    let d = Dialect::Wine;
    whole_rep(D::IOPCBrowse, "Browse", &Context::default(), &element(0, 0, 0), d);
    whole_rep(D::IOPCBrowse, "Browse", &Context::default(), &element(2, 2, 2), d);
    assert_eq!(
        rep(D::IOPCBrowse, "Browse", &Context::default(), &element(2, 3, 3), d),
        Err(BAD_STUB_DATA)
    );
    // 65,537 properties, one more than the bound: refused on the count, before the elements (a reply
    // that carries none of them, so the test stays small under Miri).
    assert_eq!(
        rep(
            D::IOPCBrowse,
            "Browse",
            &Context::default(),
            &element(65_537, 65_537, 0),
            d
        ),
        Err(INVALID_BOUND)
    );
}

#[test]
fn item_counts_beyond_their_bound_are_refused_before_anything_is_read() {
    // IOPCSyncIO::Read(dwSource, dwCount, phServer): 2^20 handles may be asked for, one more may not.
    let read = |n: u32| Msg::default().u16(1).u32(n).u32(n);
    assert_eq!(
        req(D::IOPCSyncIO, "Read", &read(1_048_577), Dialect::Wine),
        Err(INVALID_BOUND)
    );
    // 2^20 announced, none sent: refused for the missing bytes, not allocated.
    assert_eq!(
        req(D::IOPCSyncIO, "Read", &read(1_048_576), Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
    let ok = read(2).u32(100).u32(101);
    assert_eq!(whole_req(D::IOPCSyncIO, "Read", &ok, Dialect::Wine), Context::of(&[2]));
    // The callback: OnDataChange with VARIANT values of each kind the test server sends.
    let change = |d: Dialect| {
        let values = [V::I4(1), V::R8(2.0), V::Bstr(Some("x".into())), V::Empty];
        let mut m = Msg::default().u32(1).u32(7).u32(0).u32(0).u32(4).u32(4);
        for h in 0..4 {
            m = m.u32(1000 + h);
        }
        // The VARIANTs: the conformance, each one's place (the "User" prefix), then their bodies.
        m = m.u32(4);
        for _ in &values {
            m = m.u32(USER);
        }
        for v in &values {
            m = m.variant(v, d);
        }
        m = m.u32(4).u16(0xC0).u16(0xC0).u16(0xC0).u16(0xC0).u32(4);
        for _ in 0..4 {
            m = m.u32(1).u32(2);
        }
        m = m.u32(4);
        for _ in 0..4 {
            m = m.u32(0);
        }
        m
    };
    for d in [Dialect::Ndr, Dialect::Wine] {
        whole_req(D::IOPCDataCallback, "OnDataChange", &change(d), d);
    }
}
