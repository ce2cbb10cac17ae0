use super::*;
use crate::com::guids::{IID_IEnumGUID, IID_IOPCEnumGUID};
use crate::com::GUID;
use crate::proxy::ndr::objref::{
    OBJREF_CUSTOM, OBJREF_EXTENDED, OBJREF_EXTENDED_SIGNATURE, OBJREF_HANDLER, OBJREF_SIGNATURE, OBJREF_STANDARD,
};

type Check = Result<(), HRESULT>;

/// A GUID as NDR and an OBJREF carry it: `Data1` to `Data3` little-endian, then `Data4`.
fn guid_bytes(g: &GUID) -> [u8; 16] {
    let mut b = [0; 16];
    b[..4].copy_from_slice(&g.Data1.to_le_bytes());
    b[4..6].copy_from_slice(&g.Data2.to_le_bytes());
    b[6..8].copy_from_slice(&g.Data3.to_le_bytes());
    b[8..].copy_from_slice(&g.Data4);
    b
}

/// The context of a request with these words (`Next`'s `celt` is the only one of these interfaces).
fn ctx(celt: u32) -> Context {
    Context::of(&[celt])
}

const LOCAL: u32 = 0x10;

/// NDR 2.0 little-endian message builder.
#[derive(Default, Clone)]
struct Msg(Vec<u8>);

impl Msg {
    fn u32(mut self, v: u32) -> Self {
        while self.0.len() % 4 != 0 {
            self.0.push(0);
        }
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn guids(mut self, n: usize) -> Self {
        for i in 0..n * 16 {
            self.0.push(i as u8);
        }
        self
    }
    fn string(self, text: &str) -> Self {
        let units: Vec<u16> = text.encode_utf16().chain([0]).collect();
        let mut m = self.u32(units.len() as u32).u32(0).u32(units.len() as u32);
        for u in units {
            m.0.extend_from_slice(&u.to_le_bytes());
        }
        m
    }
    /// Bytes as they are (an OBJREF is bytes to NDR), starting at a 4-byte boundary.
    fn raw(mut self, bytes: &[u8]) -> Self {
        while self.0.len() % 4 != 0 {
            self.0.push(0);
        }
        self.0.extend_from_slice(bytes);
        self
    }
    fn bytes(&self) -> &[u8] {
        &self.0
    }
}

fn request(iface: Interface, method: u32, m: &Msg) -> Check {
    check_request(iface, method, m.bytes(), LOCAL, Dialect::Wine)
}

fn reply(iface: Interface, method: u32, context: u32, m: &Msg) -> Check {
    check_reply(iface, method, &ctx(context), m.bytes(), LOCAL, Dialect::Wine)
}

/// Every proper prefix of a message that is accepted whole is refused.
fn truncations_refused(accepted: &Msg, check: impl Fn(&[u8]) -> Check) {
    assert_eq!(check(accepted.bytes()), Ok(()));
    for len in 0..accepted.0.len() {
        assert!(check(&accepted.0[..len]).is_err(), "prefix of {len} bytes accepted");
    }
}

#[test]
fn well_formed_requests_pass_and_every_truncation_is_refused() {
    let cases: Vec<(Interface, u32, Msg)> = vec![
        (Interface::IOPCShutdown, 3, Msg::default().string("server stops")),
        (Interface::IOPCCommon, 3, Msg::default().u32(0x409)),
        (Interface::IOPCCommon, 6, Msg::default().u32(0x80004005)),
        (Interface::IOPCCommon, 7, Msg::default().string("client")),
        (
            Interface::IOPCServerList,
            3,
            Msg::default().u32(2).u32(2).guids(2).u32(1).u32(1).guids(1),
        ),
        (Interface::IOPCServerList2, 4, Msg::default().guids(1)),
        (Interface::IOPCServerList2, 5, Msg::default().string("OPC.Sim.1")),
        (Interface::IOPCEnumGUID, 3, Msg::default().u32(10)),
        (Interface::IOPCEnumGUID, 4, Msg::default().u32(3)),
    ];
    for (iface, method, m) in cases {
        truncations_refused(&m, |b| check_request(iface, method, b, LOCAL, Dialect::Wine));
    }
    for (iface, method) in [
        (Interface::IOPCCommon, 4),
        (Interface::IOPCCommon, 5),
        (Interface::IOPCEnumGUID, 5),
        (Interface::IOPCEnumGUID, 6),
    ] {
        assert_eq!(request(iface, method, &Msg::default()), Ok(()));
    }
}

#[test]
fn a_category_count_that_differs_from_the_array_on_the_wire_is_refused() {
    // cImplemented = 4096 with one GUID on the wire (the audit's request).
    let m = Msg::default().u32(4096).u32(1).guids(1).u32(0).u32(0);
    assert_eq!(request(Interface::IOPCServerList, 3, &m), Err(BAD_STUB_DATA));
    let m = Msg::default().u32(1).u32(1).guids(1).u32(3).u32(2).guids(2);
    assert_eq!(request(Interface::IOPCServerList2, 3, &m), Err(BAD_STUB_DATA));
    // Counts that agree but whose GUIDs are not all there.
    let m = Msg::default().u32(4096).u32(4096).guids(1);
    assert_eq!(request(Interface::IOPCServerList, 3, &m), Err(BAD_STUB_DATA));
    // Beyond the bound, whatever is on the wire.
    let m = Msg::default().u32(MAX_ELEMENTS + 1).u32(MAX_ELEMENTS + 1);
    assert_eq!(request(Interface::IOPCServerList, 3, &m), Err(INVALID_BOUND));
}

#[test]
fn next_asks_for_at_most_the_bound() {
    assert_eq!(
        request(Interface::IOPCEnumGUID, 3, &Msg::default().u32(MAX_ELEMENTS)),
        Ok(())
    );
    assert_eq!(
        request(Interface::IOPCEnumGUID, 3, &Msg::default().u32(0x0FFF_FFFF)),
        Err(INVALID_BOUND)
    );
    assert_eq!(
        request(Interface::IOPCEnumGUID, 3, &Msg::default().u32(u32::MAX)),
        Err(INVALID_BOUND)
    );
}

#[test]
fn strings_must_be_whole_and_terminated() {
    let good = Msg::default().string("ab");
    assert_eq!(request(Interface::IOPCCommon, 7, &good), Ok(()));
    let no_nul = Msg::default().u32(2).u32(0).u32(2).u32(0x0062_0061);
    assert_eq!(request(Interface::IOPCCommon, 7, &no_nul), Err(BAD_STUB_DATA));
    let max_beyond_actual = Msg::default().u32(0x7FFF_FFFF).u32(0).u32(1).u32(0);
    assert_eq!(
        request(Interface::IOPCCommon, 7, &max_beyond_actual),
        Err(BAD_STUB_DATA)
    );
    let offset = Msg::default().u32(1).u32(1).u32(1).u32(0);
    assert_eq!(request(Interface::IOPCCommon, 7, &offset), Err(BAD_STUB_DATA));
    let empty = Msg::default().u32(0).u32(0).u32(0);
    assert_eq!(request(Interface::IOPCCommon, 7, &empty), Err(BAD_STUB_DATA));
    let huge = Msg::default().u32(u32::MAX).u32(0).u32(u32::MAX).u32(0);
    assert_eq!(request(Interface::IOPCShutdown, 3, &huge), Err(BAD_STUB_DATA));
}

#[test]
fn foreign_data_representations_and_unknown_methods_are_refused() {
    let m = Msg::default().u32(1);
    // Big-endian integers (the NDR engine would read them as little-endian), EBCDIC, VAX floats.
    for drep in [0x00, 0x01, 0x0110, 0x0011] {
        assert_eq!(
            check_request(Interface::IOPCEnumGUID, 3, m.bytes(), drep, Dialect::Wine),
            Err(BAD_STUB_DATA)
        );
    }
    for (iface, method) in [
        (Interface::IOPCShutdown, 0),
        (Interface::IOPCShutdown, 2),
        (Interface::IOPCShutdown, 4),
        (Interface::IOPCCommon, 8),
        (Interface::IOPCServerList, 6),
        (Interface::IOPCEnumGUID, 7),
        (Interface::IOPCServerList2, u32::MAX),
    ] {
        assert_eq!(request(iface, method, &m), Err(PROCNUM_OUT_OF_RANGE));
        assert_eq!(reply(iface, method, 0, &m), Err(PROCNUM_OUT_OF_RANGE));
    }
}

#[test]
fn next_replies_fit_the_callers_buffer() {
    let good = Msg::default().u32(4).u32(0).u32(2).guids(2).u32(2).u32(1);
    truncations_refused(&good, |b| {
        check_reply(Interface::IOPCEnumGUID, 3, &ctx(4), b, LOCAL, Dialect::Wine)
    });
    // The audit's reply: celt 1, conformance and count 64.
    let wide = Msg::default().u32(64).u32(0).u32(64).guids(64).u32(64).u32(0);
    assert_eq!(reply(Interface::IOPCEnumGUID, 3, 1, &wide), Err(BAD_STUB_DATA));
    // Conformance = celt but more elements than that, an offset, a fetched count that differs.
    let more = Msg::default().u32(1).u32(0).u32(2).guids(2).u32(2).u32(0);
    assert_eq!(reply(Interface::IOPCEnumGUID, 3, 1, &more), Err(BAD_STUB_DATA));
    let offset = Msg::default().u32(2).u32(1).u32(1).guids(1).u32(1).u32(0);
    assert_eq!(reply(Interface::IOPCEnumGUID, 3, 2, &offset), Err(BAD_STUB_DATA));
    let fetched = Msg::default().u32(2).u32(0).u32(1).guids(1).u32(2).u32(0);
    assert_eq!(reply(Interface::IOPCEnumGUID, 3, 2, &fetched), Err(BAD_STUB_DATA));
    // The context is the proxy's own request.
    assert_eq!(
        reply_context(Interface::IOPCEnumGUID, 3, Msg::default().u32(7).bytes(), Dialect::Wine),
        ctx(7)
    );
    assert_eq!(
        reply_context(Interface::IOPCEnumGUID, 4, Msg::default().u32(7).bytes(), Dialect::Wine),
        ctx(0)
    );
}

#[test]
fn locale_lists_carry_as_many_locales_as_they_count() {
    let good = Msg::default().u32(2).u32(0x20000).u32(2).u32(0x409).u32(0x407).u32(0);
    truncations_refused(&good, |b| {
        check_reply(Interface::IOPCCommon, 5, &ctx(0), b, LOCAL, Dialect::Wine)
    });
    let none = Msg::default().u32(0).u32(0).u32(0x80004005);
    assert_eq!(reply(Interface::IOPCCommon, 5, 0, &none), Ok(()));
    // The audit's reply: a count of 100000 with one locale.
    let short = Msg::default().u32(100_000).u32(0x20000).u32(1).u32(0x409).u32(0);
    assert_eq!(reply(Interface::IOPCCommon, 5, 0, &short), Err(INVALID_BOUND));
    let short = Msg::default().u32(2).u32(0x20000).u32(1).u32(0x409).u32(0);
    assert_eq!(reply(Interface::IOPCCommon, 5, 0, &short), Err(BAD_STUB_DATA));
    let counted_null = Msg::default().u32(5).u32(0).u32(0);
    assert_eq!(reply(Interface::IOPCCommon, 5, 0, &counted_null), Err(BAD_STUB_DATA));
}

#[test]
fn string_and_guid_replies() {
    let text = Msg::default().u32(0x20000).string("text").u32(0);
    truncations_refused(&text, |b| {
        check_reply(Interface::IOPCCommon, 6, &ctx(0), b, LOCAL, Dialect::Wine)
    });
    assert_eq!(
        reply(Interface::IOPCCommon, 6, 0, &Msg::default().u32(0).u32(0x80004005)),
        Ok(())
    );
    let details = Msg::default()
        .u32(0x20000)
        .string("OPC.Sim.1")
        .u32(0x20004)
        .string("Simulation")
        .u32(0)
        .u32(0);
    truncations_refused(&details, |b| {
        check_reply(Interface::IOPCServerList2, 4, &ctx(0), b, LOCAL, Dialect::Wine)
    });
    let two = Msg::default().u32(0).u32(0x20004).string("x").u32(0);
    assert_eq!(reply(Interface::IOPCServerList, 4, 0, &two), Ok(()));
    let clsid = Msg::default().guids(1).u32(0);
    truncations_refused(&clsid, |b| {
        check_reply(Interface::IOPCServerList, 5, &ctx(0), b, LOCAL, Dialect::Wine)
    });
}

// ---- Interface pointers: OBJREFs (MS-DCOM 2.2.18) in both layouts ----

/// An OBJREF built field by field from MS-DCOM 2.2.18: signature, flags, IID, then the flavour.
#[derive(Clone)]
struct Objref(Vec<u8>);

impl Objref {
    fn header(flags: u32, iid: &GUID) -> Self {
        let mut b = OBJREF_SIGNATURE.to_le_bytes().to_vec();
        b.extend_from_slice(&flags.to_le_bytes());
        b.extend_from_slice(&guid_bytes(iid));
        Objref(b)
    }
    /// STDOBJREF (MS-DCOM 2.2.18.1): flags, cPublicRefs, OXID, OID, IPID.
    fn std(mut self) -> Self {
        self.0.extend_from_slice(&0u32.to_le_bytes());
        self.0.extend_from_slice(&5u32.to_le_bytes());
        self.0.extend_from_slice(&0x1122_3344_5566_7788u64.to_le_bytes());
        self.0.extend_from_slice(&0x99AA_BBCC_DDEE_FF00u64.to_le_bytes());
        self.0.extend((0..16).map(|i| 0xC0 + i as u8));
        self
    }
    fn u16s(mut self, units: &[u16]) -> Self {
        for u in units {
            self.0.extend_from_slice(&u.to_le_bytes());
        }
        self
    }
    fn bytes(mut self, b: &[u8]) -> Self {
        self.0.extend_from_slice(b);
        self
    }
    /// A DUALSTRINGARRAY (MS-DCOM 2.2.19.1) as Windows fills it: one string binding (ncacn_ip_tcp,
    /// "127.0.0.1[49670]") and one security binding (NTLM, default authorization, no principal).
    fn windows_bindings(self) -> Self {
        let mut units: Vec<u16> = vec![0x07];
        units.extend("127.0.0.1[49670]".encode_utf16());
        units.push(0);
        units.push(0); // end of the string bindings
        let security = units.len() as u16;
        units.extend([0x0A, 0xFFFF, 0, 0]); // a binding with an empty principal, then the end
        self.u16s(&[units.len() as u16, security]).u16s(&units)
    }
    /// A standard OBJREF as Windows writes it.
    fn windows(iid: &GUID) -> Self {
        Objref::header(OBJREF_STANDARD, iid).std().windows_bindings()
    }
    /// A standard OBJREF as Wine's combase writes it: an empty DUALSTRINGARRAY (68 bytes in all).
    fn wine(iid: &GUID) -> Self {
        Objref::header(OBJREF_STANDARD, iid).std().u16s(&[0, 0])
    }
    fn len(&self) -> u32 {
        self.0.len() as u32
    }
}

/// `[out] I **` then the HRESULT in NDR's layout (MS-DCOM 2.2.14 `PMInterfacePointer`): the referent
/// ID Windows uses first, conformance, ulCntData, the OBJREF.
fn ndr_reply(o: &Objref) -> Msg {
    Msg::default()
        .u32(0x0002_0000)
        .u32(o.len())
        .u32(o.len())
        .raw(&o.0)
        .u32(0)
}

/// The same in Wine's layout: the byte count, the OBJREF.
fn wine_reply(o: &Objref) -> Msg {
    Msg::default().u32(o.len()).raw(&o.0).u32(0)
}

/// The three methods that return an interface pointer, with the IID each declares.
const IP_METHODS: [(Interface, u32, GUID); 3] = [
    (Interface::IOPCServerList, 3, IID_IEnumGUID),
    (Interface::IOPCServerList2, 3, IID_IOPCEnumGUID),
    (Interface::IOPCEnumGUID, 6, IID_IOPCEnumGUID),
];

fn ip_reply(iface: Interface, method: u32, m: &Msg, reader: Dialect) -> Check {
    check_reply(iface, method, &ctx(0), m.bytes(), LOCAL, reader)
}

#[test]
fn a_null_interface_pointer_is_one_zero_in_either_layout() {
    let null = Msg::default().u32(0).u32(0x80004005);
    for (iface, method, _) in IP_METHODS {
        truncations_refused(&null, |b| check_reply(iface, method, &ctx(0), b, LOCAL, Dialect::Ndr));
        truncations_refused(&null, |b| check_reply(iface, method, &ctx(0), b, LOCAL, Dialect::Wine));
    }
}

#[test]
fn interface_pointers_as_windows_writes_them_pass_where_ndr_is_read() {
    for (iface, method, iid) in IP_METHODS {
        let m = ndr_reply(&Objref::windows(&iid));
        truncations_refused(&m, |b| check_reply(iface, method, &ctx(0), b, LOCAL, Dialect::Ndr));
        // Wine's rpcrt4 would take the referent ID for a byte count.
        assert_eq!(ip_reply(iface, method, &m, Dialect::Wine), Err(BAD_STUB_DATA));
        // Any referent ID but 0 is a pointer; the bytes after the OBJREF are padded to the HRESULT.
        let odd = Objref::windows(&iid).bytes(&[0xEE]);
        let m = Msg::default().u32(1).u32(odd.len()).u32(odd.len()).raw(&odd.0).u32(0);
        assert_eq!(m.0.len() % 4, 0);
        truncations_refused(&m, |b| check_reply(iface, method, &ctx(0), b, LOCAL, Dialect::Ndr));
    }
}

#[test]
fn interface_pointers_as_wine_writes_them_pass_where_wines_layout_is_read() {
    for (iface, method, iid) in IP_METHODS {
        let m = wine_reply(&Objref::wine(&iid));
        assert_eq!(m.0.len(), 4 + 68 + 4);
        truncations_refused(&m, |b| check_reply(iface, method, &ctx(0), b, LOCAL, Dialect::Wine));
        // Windows' rpcrt4 would take the signature for a conformance.
        assert_eq!(ip_reply(iface, method, &m, Dialect::Ndr), Err(BAD_STUB_DATA));
        // Windows' OBJREF in Wine's framing is Wine's layout too.
        let m = wine_reply(&Objref::windows(&iid));
        assert_eq!(ip_reply(iface, method, &m, Dialect::Wine), Ok(()));
    }
}

#[test]
fn every_objref_flavour_passes_within_its_count() {
    let iid = IID_IOPCEnumGUID;
    let flavours = [
        Objref::header(OBJREF_HANDLER, &iid)
            .std()
            .bytes(&[0x11; 16])
            .windows_bindings(),
        // A custom marshaller's CLSID, cbExtension, reserved and its data.
        Objref::header(OBJREF_CUSTOM, &iid)
            .bytes(&[0x22; 16])
            .bytes(&[0; 8])
            .bytes(b"marshalled by value"),
        Objref::header(OBJREF_CUSTOM, &iid).bytes(&[0x22; 16]).bytes(&[0; 8]),
        Objref::header(OBJREF_EXTENDED, &iid)
            .std()
            .bytes(&OBJREF_EXTENDED_SIGNATURE.to_le_bytes())
            .windows_bindings()
            .bytes(&1u32.to_le_bytes())
            .bytes(&OBJREF_EXTENDED_SIGNATURE.to_le_bytes())
            .bytes(&[0x33; 24]),
    ];
    for o in &flavours {
        truncations_refused(&ndr_reply(o), |b| {
            check_reply(Interface::IOPCEnumGUID, 6, &ctx(0), b, LOCAL, Dialect::Ndr)
        });
        truncations_refused(&wine_reply(o), |b| {
            check_reply(Interface::IOPCEnumGUID, 6, &ctx(0), b, LOCAL, Dialect::Wine)
        });
    }
}

/// Each way an interface pointer can be malformed, in both layouts: refused whichever runtime reads.
#[test]
fn malformed_interface_pointers_are_refused_in_either_layout() {
    let iid = IID_IOPCEnumGUID;
    let good = Objref::windows(&iid);
    let with = |at: usize, bytes: &[u8]| {
        let mut o = good.clone();
        o.0[at..at + bytes.len()].copy_from_slice(bytes);
        o
    };
    let objrefs = [
        ("no signature", with(0, b"WOEM")),
        ("no flavour", with(4, &0u32.to_le_bytes())),
        ("two flavours", with(4, &3u32.to_le_bytes())),
        ("an unknown flavour", with(4, &16u32.to_le_bytes())),
        (
            "another interface",
            with(8, &guid_bytes(&crate::com::guids::IID_IUnknown)),
        ),
        ("the other enumerator", with(8, &guid_bytes(&IID_IEnumGUID))),
        ("bindings beyond the OBJREF", with(64, &200u16.to_le_bytes())),
        ("a security offset beyond the bindings", with(66, &200u16.to_le_bytes())),
        ("cut in the STDOBJREF", Objref(good.0[..40].to_vec())),
        ("cut in the bindings", Objref(good.0[..good.0.len() - 2].to_vec())),
        ("the header only", Objref(good.0[..24].to_vec())),
        (
            "an extended OBJREF without its signature",
            Objref::header(OBJREF_EXTENDED, &iid).std().bytes(&[0; 4]).u16s(&[0, 0]),
        ),
        (
            "a custom OBJREF cut in its header",
            Objref::header(OBJREF_CUSTOM, &iid).bytes(&[0; 20]),
        ),
    ];
    for (what, o) in &objrefs {
        for reader in [Dialect::Ndr, Dialect::Wine] {
            assert_eq!(
                ip_reply(Interface::IOPCEnumGUID, 6, &ndr_reply(o), reader),
                Err(BAD_STUB_DATA),
                "{what}, NDR's layout, {reader:?} reading"
            );
            assert_eq!(
                ip_reply(Interface::IOPCEnumGUID, 6, &wine_reply(o), reader),
                Err(BAD_STUB_DATA),
                "{what}, Wine's layout, {reader:?} reading"
            );
        }
    }
    let n = good.len();
    let framings = [
        // NDR: ulCntData unequal to the conformance, either way; a count beyond the message.
        (
            "ulCntData below the conformance",
            Msg::default().u32(1).u32(n).u32(n - 4).raw(&good.0).u32(0),
        ),
        (
            "ulCntData above the conformance",
            Msg::default().u32(1).u32(n).u32(n + 4).raw(&good.0).u32(0),
        ),
        (
            "a conformance beyond the reply",
            Msg::default().u32(1).u32(0x1000).u32(0x1000).raw(&good.0).u32(0),
        ),
        (
            "a count the OBJREF does not fill",
            Msg::default().u32(1).u32(n + 8).u32(n + 8).raw(&good.0).u32(0),
        ),
        (
            "a count short of the OBJREF",
            Msg::default().u32(1).u32(n - 8).u32(n - 8).raw(&good.0).u32(0),
        ),
        ("no HRESULT after it", Msg::default().u32(1).u32(n).u32(n).raw(&good.0)),
        // Wine: a byte count beyond the reply, short of the OBJREF, or covering the HRESULT.
        (
            "a size beyond the reply",
            Msg::default().u32(0x1000).raw(&good.0).u32(0),
        ),
        ("a size short of the OBJREF", Msg::default().u32(24).raw(&good.0).u32(0)),
        ("a size over the HRESULT", Msg::default().u32(n + 4).raw(&good.0).u32(0)),
        // The ambiguity: an NDR conformance equal to the signature reads as Wine's layout with ulCntData
        // for a flavour, which none is.
        (
            "a conformance equal to the signature",
            Msg::default()
                .u32(1)
                .u32(OBJREF_SIGNATURE)
                .u32(OBJREF_SIGNATURE)
                .raw(&good.0)
                .u32(0),
        ),
    ];
    for (what, m) in &framings {
        for (iface, method, _) in IP_METHODS {
            for reader in [Dialect::Ndr, Dialect::Wine] {
                assert_eq!(
                    ip_reply(iface, method, m, reader),
                    Err(BAD_STUB_DATA),
                    "{what}, {reader:?} reading"
                );
            }
        }
    }
}

/// The checks made before both layouts were told apart took Windows' layout on trust: any reply of
/// four bytes or more passed. Each of these did.
#[test]
fn ndr_layout_is_checked_not_skipped() {
    let objref = Objref::windows(&IID_IOPCEnumGUID);
    let n = objref.len();
    for m in [
        Msg::default().u32(1).u32(n).u32(n + 4).raw(&objref.0).u32(0),
        Msg::default().u32(1).u32(0x7FFF_FFFF).u32(0x7FFF_FFFF).u32(0),
        ndr_reply(&Objref::windows(&IID_IEnumGUID)),
        Msg::default().u32(1).u32(8).u32(8).u32(0).u32(0).u32(0),
    ] {
        assert_eq!(
            ip_reply(Interface::IOPCEnumGUID, 6, &m, Dialect::Ndr),
            Err(BAD_STUB_DATA)
        );
    }
}

/// Arbitrary bytes never make the checks panic or read out of bounds (Miri runs this too).
#[test]
fn arbitrary_bytes_are_answered() {
    let mut seed = 0x2545_F491_4F6C_DD1Du64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let rounds = if cfg!(miri) { 200 } else { 20_000 };
    for _ in 0..rounds {
        let len = (next() % 48) as usize;
        let bytes: Vec<u8> = (0..len)
            .map(|_| match next() % 4 {
                0 => 0,
                1 => 0xFF,
                _ => next() as u8,
            })
            .collect();
        let iface = Interface::from_index((next() % 5) as u32).unwrap();
        let method = (next() % 9) as u32;
        let _ = check_request(iface, method, &bytes, LOCAL, Dialect::Wine);
        let context = (next() % 70) as u32;
        let wine = check_reply(iface, method, &ctx(context), &bytes, LOCAL, Dialect::Wine);
        let ndr = check_reply(iface, method, &ctx(context), &bytes, LOCAL, Dialect::Ndr);
        // Only a NULL interface pointer reads the same in both layouts.
        if wine.is_ok() && ndr.is_ok() && IP_METHODS.iter().any(|&(i, m, _)| (i, m) == (iface, method)) {
            assert_eq!(bytes[..4], [0; 4]);
        }
        let _ = reply_context(iface, method, &bytes, Dialect::Wine);
    }
}

// ---- The generated checks against the hand-written ones they replaced ----

/// Well-formed requests and replies of every method (interface, method, `Next`'s `celt`, bytes).
fn corpus() -> Vec<(Interface, u32, u32, Vec<u8>)> {
    let mut out = Vec::new();
    let requests: Vec<(Interface, u32, Msg)> = vec![
        (Interface::IOPCShutdown, 3, Msg::default().string("server stops")),
        (Interface::IOPCCommon, 3, Msg::default().u32(0x409)),
        (Interface::IOPCCommon, 6, Msg::default().u32(0x80004005)),
        (Interface::IOPCCommon, 7, Msg::default().string("client")),
        (
            Interface::IOPCServerList,
            3,
            Msg::default().u32(2).u32(2).guids(2).u32(1).u32(1).guids(1),
        ),
        (
            Interface::IOPCServerList2,
            3,
            Msg::default().u32(0).u32(0).u32(1).u32(1).guids(1),
        ),
        (Interface::IOPCServerList, 4, Msg::default().guids(1)),
        (Interface::IOPCServerList2, 5, Msg::default().string("OPC.Sim.1")),
        (Interface::IOPCEnumGUID, 3, Msg::default().u32(10)),
        (Interface::IOPCEnumGUID, 4, Msg::default().u32(3)),
    ];
    for (i, m, msg) in requests {
        out.push((i, m, 0, msg.0));
    }
    let replies: Vec<(Interface, u32, u32, Msg)> = vec![
        (
            Interface::IOPCEnumGUID,
            3,
            4,
            Msg::default().u32(4).u32(0).u32(2).guids(2).u32(2).u32(1),
        ),
        (
            Interface::IOPCEnumGUID,
            3,
            0,
            Msg::default().u32(0).u32(0).u32(0).u32(0).u32(1),
        ),
        (
            Interface::IOPCCommon,
            5,
            0,
            Msg::default().u32(2).u32(0x20000).u32(2).u32(0x409).u32(0x407).u32(0),
        ),
        (
            Interface::IOPCCommon,
            5,
            0,
            Msg::default().u32(0).u32(0).u32(0x80004005),
        ),
        (Interface::IOPCCommon, 4, 0, Msg::default().u32(0x409).u32(0)),
        (
            Interface::IOPCCommon,
            6,
            0,
            Msg::default().u32(0x20000).string("text").u32(0),
        ),
        (
            Interface::IOPCServerList2,
            4,
            0,
            Msg::default()
                .u32(0x20000)
                .string("OPC.Sim.1")
                .u32(0x20004)
                .string("Simulation")
                .u32(0)
                .u32(0),
        ),
        (
            Interface::IOPCServerList,
            4,
            0,
            Msg::default().u32(0).u32(0x20004).string("x").u32(0),
        ),
        (Interface::IOPCServerList, 5, 0, Msg::default().guids(1).u32(0)),
        (Interface::IOPCShutdown, 3, 0, Msg::default().u32(0)),
    ];
    for (i, m, celt, msg) in replies {
        out.push((i, m, celt, msg.0));
    }
    for (i, m, iid) in IP_METHODS {
        out.push((i, m, 0, ndr_reply(&Objref::windows(&iid)).0));
        out.push((i, m, 0, wine_reply(&Objref::wine(&iid)).0));
        out.push((i, m, 0, Msg::default().u32(0).u32(0x80004005).0));
    }
    out
}

/// The generated checks and the hand-written ones give the same answer to `bytes`, as a request and
/// as a reply read by either runtime.
fn same_answers(iface: Interface, method: u32, celt: u32, bytes: &[u8]) {
    for drep in [LOCAL, 0x0000_0110] {
        assert_eq!(
            check_request(iface, method, bytes, drep, Dialect::Wine),
            reference::check_request(iface, method, bytes, drep),
            "request {iface:?} {method} {bytes:02x?}"
        );
        for dialect in [Dialect::Ndr, Dialect::Wine] {
            assert_eq!(
                check_reply(iface, method, &ctx(celt), bytes, drep, dialect),
                reference::check_reply(iface, method, celt, bytes, drep, dialect),
                "reply {iface:?} {method} celt {celt} {dialect:?} {bytes:02x?}"
            );
        }
    }
    if check_request(iface, method, bytes, LOCAL, Dialect::Wine).is_ok() {
        assert_eq!(
            reply_context(iface, method, bytes, Dialect::Wine),
            ctx(reference::reply_context(iface, method, bytes))
        );
    }
}

/// Every well-formed message, every prefix of it, and thousands of mutations of each: changed bytes,
/// words set to the values counts are checked against (0, 1, the bound and one past it, the message's
/// length...), bytes added; and arbitrary messages. The answers must be the same.
#[test]
fn the_generated_checks_answer_as_the_hand_written_ones() {
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let rounds = if cfg!(miri) { 4 } else { 400 };
    let corpus = corpus();
    let methods: Vec<(Interface, u32)> = super::COMMON
        .iter()
        .flat_map(|&i| (0..9).map(move |m| (i, m)))
        .collect();
    for (iface, method, celt, msg) in &corpus {
        for len in 0..=msg.len() {
            same_answers(*iface, *method, *celt, &msg[..len]);
        }
        for _ in 0..rounds {
            let mut m = msg.clone();
            for _ in 0..1 + next() % 3 {
                if m.is_empty() {
                    break;
                }
                let at = (next() as usize) % m.len();
                match next() % 4 {
                    0 => m[at] = next() as u8,
                    1 => {
                        let at = at & !3;
                        let words = [
                            0,
                            1,
                            2,
                            *celt,
                            MAX_ELEMENTS,
                            MAX_ELEMENTS + 1,
                            u32::MAX,
                            m.len() as u32,
                            0x574F_454D,
                        ];
                        let w = words[(next() as usize) % words.len()].to_le_bytes();
                        for (i, b) in w.iter().enumerate() {
                            if let Some(x) = m.get_mut(at + i) {
                                *x = *b;
                            }
                        }
                    }
                    2 => m.truncate(at),
                    _ => m.extend((0..1 + next() % 8).map(|_| next() as u8)),
                }
            }
            // Any method and context, not only the message's own.
            let (iface, method) = if next() % 4 == 0 {
                methods[(next() as usize) % methods.len()]
            } else {
                (*iface, *method)
            };
            let celt = if next() % 4 == 0 { (next() % 70) as u32 } else { *celt };
            same_answers(iface, method, celt, &m);
        }
    }
    for _ in 0..rounds * 20 {
        let len = (next() % 48) as usize;
        let bytes: Vec<u8> = (0..len)
            .map(|_| match next() % 4 {
                0 => 0,
                1 => (next() % 4) as u8,
                _ => next() as u8,
            })
            .collect();
        let (iface, method) = methods[(next() as usize) % methods.len()];
        same_answers(iface, method, (next() % 8) as u32, &bytes);
    }
}
