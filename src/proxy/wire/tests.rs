use super::*;

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
    fn bytes(&self) -> &[u8] {
        &self.0
    }
}

fn request(iface: Interface, method: u32, m: &Msg) -> Check {
    check_request(iface, method, m.bytes(), LOCAL)
}

fn reply(iface: Interface, method: u32, context: u32, m: &Msg) -> Check {
    check_reply(iface, method, context, m.bytes(), LOCAL, IpLayout::Wine)
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
        (Interface::Shutdown, 3, Msg::default().string("server stops")),
        (Interface::Common, 3, Msg::default().u32(0x409)),
        (Interface::Common, 6, Msg::default().u32(0x80004005)),
        (Interface::Common, 7, Msg::default().string("client")),
        (
            Interface::ServerList,
            3,
            Msg::default().u32(2).u32(2).guids(2).u32(1).u32(1).guids(1),
        ),
        (Interface::ServerList2, 4, Msg::default().guids(1)),
        (Interface::ServerList2, 5, Msg::default().string("OPC.Sim.1")),
        (Interface::EnumGuid, 3, Msg::default().u32(10)),
        (Interface::EnumGuid, 4, Msg::default().u32(3)),
    ];
    for (iface, method, m) in cases {
        truncations_refused(&m, |b| check_request(iface, method, b, LOCAL));
    }
    for (iface, method) in [
        (Interface::Common, 4),
        (Interface::Common, 5),
        (Interface::EnumGuid, 5),
        (Interface::EnumGuid, 6),
    ] {
        assert_eq!(request(iface, method, &Msg::default()), Ok(()));
    }
}

#[test]
fn a_category_count_that_differs_from_the_array_on_the_wire_is_refused() {
    // cImplemented = 4096 with one GUID on the wire (the audit's request).
    let m = Msg::default().u32(4096).u32(1).guids(1).u32(0).u32(0);
    assert_eq!(request(Interface::ServerList, 3, &m), Err(BAD_STUB_DATA));
    let m = Msg::default().u32(1).u32(1).guids(1).u32(3).u32(2).guids(2);
    assert_eq!(request(Interface::ServerList2, 3, &m), Err(BAD_STUB_DATA));
    // Counts that agree but whose GUIDs are not all there.
    let m = Msg::default().u32(4096).u32(4096).guids(1);
    assert_eq!(request(Interface::ServerList, 3, &m), Err(BAD_STUB_DATA));
    // Beyond the bound, whatever is on the wire.
    let m = Msg::default().u32(MAX_ELEMENTS + 1).u32(MAX_ELEMENTS + 1);
    assert_eq!(request(Interface::ServerList, 3, &m), Err(INVALID_BOUND));
}

#[test]
fn next_asks_for_at_most_the_bound() {
    assert_eq!(
        request(Interface::EnumGuid, 3, &Msg::default().u32(MAX_ELEMENTS)),
        Ok(())
    );
    assert_eq!(
        request(Interface::EnumGuid, 3, &Msg::default().u32(0x0FFF_FFFF)),
        Err(INVALID_BOUND)
    );
    assert_eq!(
        request(Interface::EnumGuid, 3, &Msg::default().u32(u32::MAX)),
        Err(INVALID_BOUND)
    );
}

#[test]
fn strings_must_be_whole_and_terminated() {
    let good = Msg::default().string("ab");
    assert_eq!(request(Interface::Common, 7, &good), Ok(()));
    let no_nul = Msg::default().u32(2).u32(0).u32(2).u32(0x0062_0061);
    assert_eq!(request(Interface::Common, 7, &no_nul), Err(BAD_STUB_DATA));
    let max_beyond_actual = Msg::default().u32(0x7FFF_FFFF).u32(0).u32(1).u32(0);
    assert_eq!(request(Interface::Common, 7, &max_beyond_actual), Err(BAD_STUB_DATA));
    let offset = Msg::default().u32(1).u32(1).u32(1).u32(0);
    assert_eq!(request(Interface::Common, 7, &offset), Err(BAD_STUB_DATA));
    let empty = Msg::default().u32(0).u32(0).u32(0);
    assert_eq!(request(Interface::Common, 7, &empty), Err(BAD_STUB_DATA));
    let huge = Msg::default().u32(u32::MAX).u32(0).u32(u32::MAX).u32(0);
    assert_eq!(request(Interface::Shutdown, 3, &huge), Err(BAD_STUB_DATA));
}

#[test]
fn foreign_data_representations_and_unknown_methods_are_refused() {
    let m = Msg::default().u32(1);
    // Big-endian integers (the NDR engine would read them as little-endian), EBCDIC, VAX floats.
    for drep in [0x00, 0x01, 0x0110, 0x0011] {
        assert_eq!(
            check_request(Interface::EnumGuid, 3, m.bytes(), drep),
            Err(BAD_STUB_DATA)
        );
    }
    for (iface, method) in [
        (Interface::Shutdown, 0),
        (Interface::Shutdown, 2),
        (Interface::Shutdown, 4),
        (Interface::Common, 8),
        (Interface::ServerList, 6),
        (Interface::EnumGuid, 7),
        (Interface::ServerList2, u32::MAX),
    ] {
        assert_eq!(request(iface, method, &m), Err(PROCNUM_OUT_OF_RANGE));
        assert_eq!(reply(iface, method, 0, &m), Err(PROCNUM_OUT_OF_RANGE));
    }
}

#[test]
fn next_replies_fit_the_callers_buffer() {
    let good = Msg::default().u32(4).u32(0).u32(2).guids(2).u32(2).u32(1);
    truncations_refused(&good, |b| {
        check_reply(Interface::EnumGuid, 3, 4, b, LOCAL, IpLayout::Wine)
    });
    // The audit's reply: celt 1, conformance and count 64.
    let wide = Msg::default().u32(64).u32(0).u32(64).guids(64).u32(64).u32(0);
    assert_eq!(reply(Interface::EnumGuid, 3, 1, &wide), Err(BAD_STUB_DATA));
    // Conformance = celt but more elements than that, an offset, a fetched count that differs.
    let more = Msg::default().u32(1).u32(0).u32(2).guids(2).u32(2).u32(0);
    assert_eq!(reply(Interface::EnumGuid, 3, 1, &more), Err(BAD_STUB_DATA));
    let offset = Msg::default().u32(2).u32(1).u32(1).guids(1).u32(1).u32(0);
    assert_eq!(reply(Interface::EnumGuid, 3, 2, &offset), Err(BAD_STUB_DATA));
    let fetched = Msg::default().u32(2).u32(0).u32(1).guids(1).u32(2).u32(0);
    assert_eq!(reply(Interface::EnumGuid, 3, 2, &fetched), Err(BAD_STUB_DATA));
    // The context is the proxy's own request.
    assert_eq!(reply_context(Interface::EnumGuid, 3, Msg::default().u32(7).bytes()), 7);
    assert_eq!(reply_context(Interface::EnumGuid, 4, Msg::default().u32(7).bytes()), 0);
}

#[test]
fn locale_lists_carry_as_many_locales_as_they_count() {
    let good = Msg::default().u32(2).u32(0x20000).u32(2).u32(0x409).u32(0x407).u32(0);
    truncations_refused(&good, |b| {
        check_reply(Interface::Common, 5, 0, b, LOCAL, IpLayout::Wine)
    });
    let none = Msg::default().u32(0).u32(0).u32(0x80004005);
    assert_eq!(reply(Interface::Common, 5, 0, &none), Ok(()));
    // The audit's reply: a count of 100000 with one locale.
    let short = Msg::default().u32(100_000).u32(0x20000).u32(1).u32(0x409).u32(0);
    assert_eq!(reply(Interface::Common, 5, 0, &short), Err(INVALID_BOUND));
    let short = Msg::default().u32(2).u32(0x20000).u32(1).u32(0x409).u32(0);
    assert_eq!(reply(Interface::Common, 5, 0, &short), Err(BAD_STUB_DATA));
    let counted_null = Msg::default().u32(5).u32(0).u32(0);
    assert_eq!(reply(Interface::Common, 5, 0, &counted_null), Err(BAD_STUB_DATA));
}

#[test]
fn string_and_guid_replies() {
    let text = Msg::default().u32(0x20000).string("text").u32(0);
    truncations_refused(&text, |b| {
        check_reply(Interface::Common, 6, 0, b, LOCAL, IpLayout::Wine)
    });
    assert_eq!(
        reply(Interface::Common, 6, 0, &Msg::default().u32(0).u32(0x80004005)),
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
        check_reply(Interface::ServerList2, 4, 0, b, LOCAL, IpLayout::Wine)
    });
    let two = Msg::default().u32(0).u32(0x20004).string("x").u32(0);
    assert_eq!(reply(Interface::ServerList, 4, 0, &two), Ok(()));
    let clsid = Msg::default().guids(1).u32(0);
    truncations_refused(&clsid, |b| {
        check_reply(Interface::ServerList, 5, 0, b, LOCAL, IpLayout::Wine)
    });
}

#[test]
fn interface_pointer_replies_stay_inside_the_message() {
    let null = Msg::default().u32(0).u32(0x80004005);
    assert_eq!(reply(Interface::EnumGuid, 6, 0, &null), Ok(()));
    let objref = Msg::default().u32(8).u32(0x574f454d).u32(1).u32(0);
    truncations_refused(&objref, |b| {
        check_reply(Interface::ServerList, 3, 0, b, LOCAL, IpLayout::Wine)
    });
    let beyond = Msg::default().u32(0x1000).u32(0x574f454d).u32(0);
    assert_eq!(reply(Interface::ServerList2, 3, 0, &beyond), Err(BAD_STUB_DATA));
    // Another runtime reads its own layout; an HRESULT must still be there.
    assert_eq!(
        check_reply(Interface::EnumGuid, 6, 0, objref.bytes(), LOCAL, IpLayout::Runtime),
        Ok(())
    );
    assert!(check_reply(Interface::EnumGuid, 6, 0, &[0, 0], LOCAL, IpLayout::Runtime).is_err());
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
        let _ = check_request(iface, method, &bytes, LOCAL);
        let _ = check_reply(iface, method, (next() % 70) as u32, &bytes, LOCAL, IpLayout::Wine);
        let _ = check_reply(iface, method, 1, &bytes, LOCAL, IpLayout::Runtime);
        let _ = reply_context(iface, method, &bytes);
    }
}
