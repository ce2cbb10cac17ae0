use super::build::{element_size, sf_type, vt_of, VT_ARRAY};
use super::*;
use crate::proxy::ndr::objref::{OBJREF_SIGNATURE, OBJREF_STANDARD};

const NONE: Context = Context([0; CONTEXT_WORDS]);
const S_OK_: u32 = 0;

// ---- Base types, enums, alignment ----

/// `Scalars(b, s, l, h, f, d, k, w)`: each at its own alignment from the message's start.
fn scalars(k: u16, w: u32) -> Msg {
    Msg::default()
        .u8(1)
        .u16(2)
        .u32(3)
        .u64(4)
        .u32(5.0f32.to_bits())
        .u64(6.0f64.to_bits())
        .u16(k)
        .u32(w)
}

#[test]
fn base_types_are_read_at_their_alignment() {
    let m = scalars(2, 70000);
    assert_eq!(m.0.len(), 40, "b, pad, s, l, h, f, pad, d, k, pad, w");
    for d in BOTH {
        whole_request(T::INdrBase, "Scalars", &m, d);
        whole_reply(
            T::INdrBase,
            "Scalars",
            &NONE,
            &Msg::default().u64(1).u16(0x7FFF).u32(S_OK_),
            d,
        );
    }
}

#[test]
fn enum16_values_above_0x7fff_are_refused_and_v1_enums_are_32_bits() {
    assert_eq!(
        request(T::INdrBase, "Scalars", &scalars(0x7FFF, u32::MAX), Dialect::Wine),
        Ok(NONE)
    );
    assert_eq!(
        request(T::INdrBase, "Scalars", &scalars(0x8000, 1), Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
    assert_eq!(
        reply(
            T::INdrBase,
            "Scalars",
            &NONE,
            &Msg::default().u64(1).u16(0xFFFF).u32(0),
            Dialect::Wine
        ),
        Err(BAD_STUB_DATA)
    );
}

#[test]
fn a_message_with_8_byte_alignment_must_start_at_8() {
    let m = scalars(1, 1);
    let i = index(T::INdrBase, "Scalars");
    let skewed = m.at(4);
    // The NDR engine aligns to the address: at 4 past 8 its hyper would be 4 bytes off the check's.
    assert_eq!(
        check_request(T::INdrBase.layout(), i, skewed.bytes(), LOCAL, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
    // A method with nothing aligned to 8 only needs 4 (as before: the C side refuses less).
    let strings = Msg::default().wstr("a").cstr("b").u32(0);
    let j = index(T::INdrBase, "Strings");
    assert_eq!(
        check_request(T::INdrBase.layout(), j, strings.at(4).bytes(), LOCAL, Dialect::Wine),
        Ok(NONE)
    );
}

#[test]
fn guids_refiid_and_filetime() {
    let m = Msg::default().guid([1; 16]).guid([2; 16]).u32(0x1111).u32(0x2222);
    let reply_ = Msg::default().guid([3; 16]).u32(1).u32(2).u32(S_OK_);
    for d in BOTH {
        whole_request(T::INdrBase, "Guids", &m, d);
        whole_reply(T::INdrBase, "Guids", &NONE, &reply_, d);
    }
}

// ---- Strings ----

#[test]
fn wide_narrow_and_unique_strings() {
    let both = Msg::default().wstr("wide").cstr("narrow").u32(0x20000).wstr("opt");
    let null = Msg::default().wstr("").cstr("").u32(0);
    for d in BOTH {
        whole_request(T::INdrBase, "Strings", &both, d);
        whole_request(T::INdrBase, "Strings", &null, d);
        whole_reply(
            T::INdrBase,
            "Strings",
            &NONE,
            &Msg::default().u32(0x20000).wstr("out").u32(0),
            d,
        );
        whole_reply(T::INdrBase, "Strings", &NONE, &Msg::default().u32(0).u32(0x80004005), d);
    }
}

#[test]
fn malformed_strings_are_refused() {
    let tail = |m: Msg| m.cstr("n").u32(0);
    let cases = [
        ("no NUL", Msg::default().u32(2).u32(0).u32(2).u16(0x61).u16(0x62)),
        (
            "maximum beyond the actual count",
            Msg::default().u32(3).u32(0).u32(2).u16(0x61).u16(0),
        ),
        ("an offset", Msg::default().u32(2).u32(1).u32(2).u16(0x61).u16(0)),
        ("empty", Msg::default().u32(0).u32(0).u32(0)),
        (
            "longer than the message",
            Msg::default().u32(0x4000_0000).u32(0).u32(0x4000_0000),
        ),
    ];
    for (what, m) in cases {
        assert_eq!(
            request(T::INdrBase, "Strings", &tail(m), Dialect::Wine),
            Err(BAD_STUB_DATA),
            "{what}"
        );
    }
    // A narrow string's last byte.
    let m = Msg::default().wstr("w").u32(2).u32(0).u32(2).raw(b"ab").u32(0);
    assert_eq!(request(T::INdrBase, "Strings", &m, Dialect::Wine), Err(BAD_STUB_DATA));
}

// ---- Arrays ----

#[test]
fn conformant_arrays_carry_as_many_elements_as_their_count() {
    let good = Msg::default().u32(3).u32(3).u32(7).u32(8).u32(9);
    whole_request(T::INdrArrays, "InArray", &good, Dialect::Wine);
    let empty = Msg::default().u32(0).u32(0);
    whole_request(T::INdrArrays, "InArray", &empty, Dialect::Wine);
    // The count and the conformance differ either way; elements missing.
    for m in [
        Msg::default().u32(3).u32(2).u32(7).u32(8),
        Msg::default().u32(2).u32(3).u32(7).u32(8).u32(9),
        Msg::default().u32(4096).u32(4096).u32(7),
    ] {
        assert_eq!(request(T::INdrArrays, "InArray", &m, Dialect::Wine), Err(BAD_STUB_DATA));
    }
    // Beyond the bound, before anything else is read.
    let m = Msg::default().u32(DEFAULT_BOUND + 1);
    assert_eq!(request(T::INdrArrays, "InArray", &m, Dialect::Wine), Err(INVALID_BOUND));
}

#[test]
fn a_bound_of_its_own() {
    let at = |n: u32| {
        let mut m = Msg::default().u32(n).u32(n);
        for i in 0..n {
            m = m.u16(i as u16);
        }
        m
    };
    whole_request(T::INdrArrays, "Bounded", &at(16), Dialect::Wine);
    assert_eq!(
        request(T::INdrArrays, "Bounded", &at(17), Dialect::Wine),
        Err(INVALID_BOUND)
    );
}

#[test]
fn fixed_arrays_have_no_conformance() {
    whole_request(
        T::INdrArrays,
        "Fixed",
        &Msg::default().u32(1).u32(2).u32(3).u32(4),
        Dialect::Wine,
    );
}

#[test]
fn an_in_count_sizes_the_out_array_through_the_context() {
    let ctx = request(T::INdrArrays, "OutArray", &Msg::default().u32(2), Dialect::Wine).unwrap();
    assert_eq!(ctx, Context::of(&[2]));
    let good = Msg::default().u32(0x20000).u32(2).u32(0).u32(0x80004005).u32(0);
    whole_reply(T::INdrArrays, "OutArray", &ctx, &good, Dialect::Wine);
    // A failed call returns no array: NULL with the request's count is what every server sends.
    whole_reply(
        T::INdrArrays,
        "OutArray",
        &ctx,
        &Msg::default().u32(0).u32(0x80004005),
        Dialect::Wine,
    );
    // The conformance is the request's count, whatever the reply says.
    let wider = Msg::default().u32(0x20000).u32(3).u32(0).u32(0).u32(0).u32(0);
    assert_eq!(
        reply(T::INdrArrays, "OutArray", &ctx, &wider, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
    // The request's count is bounded as soon as it is read: the reply's array is the caller's to allocate.
    assert_eq!(
        request(
            T::INdrArrays,
            "OutArray",
            &Msg::default().u32(DEFAULT_BOUND + 1),
            Dialect::Wine
        ),
        Err(INVALID_BOUND)
    );
}

#[test]
fn an_array_of_pointers_has_its_ids_then_its_pointees() {
    let good = Msg::default()
        .u32(3)
        .u32(0x20000)
        .u32(3)
        .u32(0x20004)
        .u32(0)
        .u32(0x20008)
        .wstr("first")
        .wstr("third")
        .u32(S_OK_);
    whole_reply(T::INdrArrays, "CountedOut", &NONE, &good, Dialect::Wine);
    // A count with no array would have the caller walk NULL.
    let counted_null = Msg::default().u32(3).u32(0).u32(S_OK_);
    assert_eq!(
        reply(T::INdrArrays, "CountedOut", &NONE, &counted_null, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
    whole_reply(
        T::INdrArrays,
        "CountedOut",
        &NONE,
        &Msg::default().u32(0).u32(0).u32(1),
        Dialect::Wine,
    );
    // The strings in the order of their pointers: one missing.
    let short = Msg::default()
        .u32(2)
        .u32(0x20000)
        .u32(2)
        .u32(1)
        .u32(1)
        .wstr("only")
        .u32(0);
    assert_eq!(
        reply(T::INdrArrays, "CountedOut", &NONE, &short, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
}

#[test]
fn a_count_after_its_array_is_compared_when_it_arrives() {
    let good = Msg::default().u32(0x20000).u32(2).u32(5).u32(6).u32(2).u32(S_OK_);
    whole_reply(T::INdrArrays, "CountAfter", &NONE, &good, Dialect::Wine);
    let differs = Msg::default().u32(0x20000).u32(2).u32(5).u32(6).u32(3).u32(S_OK_);
    assert_eq!(
        reply(T::INdrArrays, "CountAfter", &NONE, &differs, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
    // NULL, then a count other than 0.
    let null = Msg::default().u32(0).u32(1).u32(S_OK_);
    assert_eq!(
        reply(T::INdrArrays, "CountAfter", &NONE, &null, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
    whole_reply(
        T::INdrArrays,
        "CountAfter",
        &NONE,
        &Msg::default().u32(0).u32(0).u32(0),
        Dialect::Wine,
    );
    // A conformance beyond the bound, before the count says anything.
    let wide = Msg::default().u32(0x20000).u32(DEFAULT_BOUND + 1);
    assert_eq!(
        reply(T::INdrArrays, "CountAfter", &NONE, &wide, Dialect::Wine),
        Err(INVALID_BOUND)
    );
}

#[test]
fn varying_arrays_have_offset_zero_and_an_actual_count_within_their_size() {
    let ctx = request(T::INdrArrays, "Varying", &Msg::default().u32(4), Dialect::Wine).unwrap();
    let good = Msg::default().u32(4).u32(0).u32(2).u32(7).u32(8).u32(2).u32(S_OK_);
    whole_reply(T::INdrArrays, "Varying", &ctx, &good, Dialect::Wine);
    for (what, m) in [
        (
            "conformance other than the request's",
            Msg::default().u32(5).u32(0).u32(2).u32(7).u32(8).u32(2).u32(0),
        ),
        (
            "an offset",
            Msg::default().u32(4).u32(1).u32(2).u32(7).u32(8).u32(2).u32(0),
        ),
        (
            "more than the size",
            Msg::default().u32(4).u32(0).u32(5).raw(&[0; 20]).u32(5).u32(0),
        ),
        (
            "the actual count unlike *pdwActual",
            Msg::default().u32(4).u32(0).u32(2).u32(7).u32(8).u32(1).u32(0),
        ),
    ] {
        assert_eq!(
            reply(T::INdrArrays, "Varying", &ctx, &m, Dialect::Wine),
            Err(BAD_STUB_DATA),
            "{what}"
        );
    }
}

#[test]
fn two_levels_of_arrays() {
    // n = 2 pointers, m = 3 values behind each: the pointers, then each array in their order.
    let good = Msg::default()
        .u32(2)
        .u32(3)
        .u32(2)
        .u32(0x20000)
        .u32(0x20004)
        .u32(3)
        .u32(10)
        .u32(11)
        .u32(12)
        .u32(3)
        .u32(20)
        .u32(21)
        .u32(22);
    whole_request(T::INdrArrays, "TwoLevel", &good, Dialect::Wine);
    // The inner conformance is m.
    let bad = Msg::default().u32(2).u32(3).u32(2).u32(1).u32(0).u32(2).u32(10).u32(11);
    assert_eq!(
        request(T::INdrArrays, "TwoLevel", &bad, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
    // A NULL inner array of the request's m values: the server would walk NULL.
    let mut seen_null_check = Msg::default().u32(1).u32(3).u32(1).u32(0);
    seen_null_check = seen_null_check.u32(0);
    assert_eq!(
        request(T::INdrArrays, "TwoLevel", &seen_null_check, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
}

#[test]
fn arrays_of_enums_are_checked_element_by_element() {
    whole_request(
        T::INdrArrays,
        "Enums",
        &Msg::default().u32(3).u32(3).u16(0).u16(1).u16(0x7FFF),
        Dialect::Wine,
    );
    let m = Msg::default().u32(3).u32(3).u16(0).u16(0x8000).u16(1);
    assert_eq!(request(T::INdrArrays, "Enums", &m, Dialect::Wine), Err(BAD_STUB_DATA));
}

// ---- Structures ----

fn plain(m: Msg, a: u32) -> Msg {
    m.u32(a).u16(1).u16(2).guid([a as u8; 16])
}

#[test]
fn plain_structures_in_one_step_and_padded_ones_field_by_field() {
    let m = plain(plain(Msg::default().u32(2).u32(2), 1), 2);
    whole_request(T::INdrStructs, "Plain", &m, Dialect::Wine);
    let padded = Msg::default().u32(5).u8(6).u32(S_OK_);
    whole_reply(T::INdrStructs, "Plain", &NONE, &padded, Dialect::Wine);
}

/// A RECORD's flat part (MS-RPCE: embedded pointers as referent IDs, the VARIANT's prefix).
fn record_flat(m: Msg, name: bool, blob: u32, blob_id: bool, kind: u16, optional: bool) -> Msg {
    let m = m
        .u32(if name { 0x20000 } else { 0 })
        .u32(blob)
        .u32(if blob_id { 0x20004 } else { 0 })
        .u16(kind)
        .u32(USER);
    plain(m, 9).u32(if optional { 0x20008 } else { 0 })
}

/// Its deferred pointees, in the order of their pointers.
fn record_pointees(m: Msg, name: Option<&str>, blob: Option<&[u8]>, v: &V, optional: Option<u32>, d: Dialect) -> Msg {
    let mut m = m;
    if let Some(n) = name {
        m = m.wstr(n);
    }
    if let Some(b) = blob {
        m = m.u32(b.len() as u32).raw(b);
    }
    m = m.variant(v, d);
    if let Some(o) = optional {
        m = m.u32(o);
    }
    m
}

#[test]
fn structures_with_embedded_pointers_have_their_pointees_after_the_whole_array() {
    for d in BOTH {
        // Two records: every flat part first, then each record's pointees.
        let m = record_flat(Msg::default().u32(2).u32(2), true, 3, true, 1, true);
        let m = record_flat(m, false, 0, false, 2, false);
        let m = record_pointees(m, Some("first"), Some(&[1, 2, 3]), &V::I4(5), Some(77), d);
        let m = record_pointees(m, None, None, &V::Bstr(Some("second".into())), None, d);
        whole_request(T::INdrStructs, "Records", &m, d);
    }
}

#[test]
fn a_field_sizes_its_pointer_s_array_and_has_its_own_bound() {
    let with_blob = |size: u32, blob: &[u8]| {
        let m = record_flat(Msg::default().u32(1).u32(1), false, size, true, 0, false);
        record_pointees(m, None, Some(blob), &V::Empty, None, Dialect::Wine)
    };
    assert!(request(T::INdrStructs, "Records", &with_blob(2, &[1, 2]), Dialect::Wine).is_ok());
    // The blob's conformance is the field.
    let m = record_flat(Msg::default().u32(1).u32(1), false, 2, true, 0, false)
        .u32(3)
        .raw(&[1, 2, 3]);
    assert_eq!(
        request(T::INdrStructs, "Records", &m, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
    // RECORD.pBlob's bound: 1024.
    let big = vec![0u8; 1025];
    assert_eq!(
        request(T::INdrStructs, "Records", &with_blob(1025, &big), Dialect::Wine),
        Err(INVALID_BOUND)
    );
    // A size with a NULL blob.
    let m = record_flat(Msg::default().u32(1).u32(1), false, 2, false, 0, false).variant(&V::Empty, Dialect::Wine);
    assert_eq!(
        request(T::INdrStructs, "Records", &m, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
    // An enum field above 0x7FFF.
    let m = record_flat(Msg::default().u32(1).u32(1), false, 0, false, 0x8000, false).variant(&V::Empty, Dialect::Wine);
    assert_eq!(
        request(T::INdrStructs, "Records", &m, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
}

#[test]
fn an_out_array_of_structures_sized_by_the_request() {
    let ctx = request(
        T::INdrStructs,
        "Records",
        &record_pointees(
            record_flat(Msg::default().u32(1).u32(1), false, 0, false, 0, false),
            None,
            None,
            &V::Empty,
            None,
            Dialect::Wine,
        ),
        Dialect::Wine,
    )
    .unwrap();
    assert_eq!(ctx, Context::of(&[1]));
    let m = record_flat(Msg::default().u32(0x20000).u32(1), true, 0, false, 1, false);
    let m = record_pointees(m, Some("out"), None, &V::R8(1.5), None, Dialect::Ndr).u32(S_OK_);
    whole_reply(T::INdrStructs, "Records", &ctx, &m, Dialect::Ndr);
}

#[test]
fn pointees_are_read_depth_first() {
    // NESTED { n; pRecords -> RECORD[n]; szNarrow }: its flat part, the records (their flat parts,
    // then their pointees), then the narrow string: each pointee with its own pointees right after it.
    let d = Dialect::Wine;
    let m = Msg::default().u32(1).u32(0x20000).u32(0x20004);
    let m = record_flat(m.u32(1), true, 0, false, 0, false);
    let m = record_pointees(m, Some("inner"), None, &V::I2(3), None, d);
    let good = m.cstr("narrow");
    whole_request(T::INdrStructs, "Nested", &good, d);
    // The narrow string before the record's name: refused.
    let m = Msg::default().u32(1).u32(0x20000).u32(0x20004);
    let m = record_flat(m.u32(1), true, 0, false, 0, false).cstr("narrow");
    let m = record_pointees(m, Some("inner"), None, &V::I2(3), None, d);
    assert!(request(T::INdrStructs, "Nested", &m, d).is_err());
    // The field n is the records' conformance.
    let m = Msg::default().u32(2).u32(0x20000).u32(0);
    let m = record_flat(m.u32(1), false, 0, false, 0, false).variant(&V::Empty, d);
    assert_eq!(request(T::INdrStructs, "Nested", &m, d), Err(BAD_STUB_DATA));
}

#[test]
fn structures_aligned_to_8_with_enums_and_fixed_arrays() {
    // TIMED: FILETIME, hyper, enum, short[3]; then the HRESULT.
    let m = Msg::default()
        .u32(1)
        .u32(2)
        .u64(3)
        .u16(1)
        .u16(4)
        .u16(5)
        .u16(6)
        .u32(S_OK_);
    assert_eq!(m.0.len(), 28);
    whole_reply(T::INdrStructs, "Nested", &NONE, &m, Dialect::Wine);
    let m = Msg::default()
        .u32(1)
        .u32(2)
        .u64(3)
        .u16(0x9000)
        .u16(4)
        .u16(5)
        .u16(6)
        .u32(S_OK_);
    assert_eq!(
        reply(T::INdrStructs, "Nested", &NONE, &m, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
}

// ---- Unions ----

#[test]
fn unions_read_the_arm_their_discriminant_selects() {
    // TAGGED { kind; [switch_is(kind)] VALUE }, then kind, then a VALUE switched by it.
    let text = Msg::default().u16(2).u32(2).u32(0x20000).wstr("text");
    let m = text.clone().u16(1).u32(1).u32(42);
    whole_request(T::INdrStructs, "Tagged", &m, Dialect::Wine);
    let hyper = Msg::default().u16(16).u32(16).u64(7).u16(16).u32(16).u64(8);
    whole_request(T::INdrStructs, "Tagged", &hyper, Dialect::Wine);
    // The default arm is empty.
    let none = Msg::default().u16(5).u32(5).u16(0).u32(0);
    whole_request(T::INdrStructs, "Tagged", &none, Dialect::Wine);
    // A discriminant other than the field's, or than the parameter's.
    let m = Msg::default().u16(1).u32(2).u32(0);
    assert_eq!(request(T::INdrStructs, "Tagged", &m, Dialect::Wine), Err(BAD_STUB_DATA));
    let m = text.u16(1).u32(16).u64(9);
    assert_eq!(request(T::INdrStructs, "Tagged", &m, Dialect::Wine), Err(BAD_STUB_DATA));
}

// ---- BSTR, VARIANT, SAFEARRAY ----

#[test]
fn bstrs_null_empty_and_odd() {
    for d in BOTH {
        for text in [None, Some(""), Some("text")] {
            let m = Msg::default().user(d, 4, |m| m.blob(text));
            whole_request(T::INdrAutomation, "Bstrs", &m, d);
            let r = Msg::default().user(d, 4, |m| m.blob(text)).u32(S_OK_);
            whole_reply(T::INdrAutomation, "Bstrs", &NONE, &r, d);
        }
        // An odd byte count: 3 bytes in 2 units.
        let m = Msg::default().user(d, 4, |m| m.u32(2).u32(3).u32(2).u16(0x61).u16(0x62));
        whole_request(T::INdrAutomation, "Bstrs", &m, d);
    }
}

#[test]
fn malformed_bstrs_are_refused() {
    let d = Dialect::Wine;
    for (what, blob) in [
        ("conformance unlike clSize", Msg::default().u32(2).u32(4).u32(1).u16(1)),
        ("clSize unlike cBytes", Msg::default().u32(1).u32(4).u32(1).u16(1)),
        (
            "a NULL BSTR with units",
            Msg::default().u32(1).u32(u32::MAX).u32(1).u16(1),
        ),
        (
            "more than the message",
            Msg::default().u32(0x1000_0000).u32(0x2000_0000).u32(0x1000_0000),
        ),
    ] {
        let m = Msg::default().user(d, 4, |m| m.raw(&blob.0));
        assert_eq!(request(T::INdrAutomation, "Bstrs", &m, d), Err(BAD_STUB_DATA), "{what}");
    }
    // Windows' reader could take a prefix of 0 for NULL; Wine's ignores it.
    let m = Msg::default().u32(0).blob(Some("x"));
    assert_eq!(
        request(T::INdrAutomation, "Bstrs", &m, Dialect::Ndr),
        Err(BAD_STUB_DATA)
    );
    assert!(request(
        T::INdrAutomation,
        "Bstrs",
        &Msg::default().u32(0).align(8).blob(Some("x")),
        Dialect::Wine
    )
    .is_ok());
}

#[test]
fn the_body_of_a_bstr_is_at_4_for_windows_and_at_8_for_wine() {
    // After the 4-byte prefix at 0 the body starts at 4 (NDR) or 8 (Wine's NdrUserMarshalUnmarshall).
    let ndr = Msg::default().user(Dialect::Ndr, 4, |m| m.blob(Some("ab")));
    let wine = Msg::default().user(Dialect::Wine, 4, |m| m.blob(Some("ab")));
    assert_eq!(ndr.0.len() + 4, wine.0.len());
    assert!(request(T::INdrAutomation, "Bstrs", &ndr, Dialect::Ndr).is_ok());
    assert!(request(T::INdrAutomation, "Bstrs", &wine, Dialect::Wine).is_ok());
    assert!(request(T::INdrAutomation, "Bstrs", &ndr, Dialect::Wine).is_err());
    assert!(request(T::INdrAutomation, "Bstrs", &wine, Dialect::Ndr).is_err());
}

/// A VARIANT parameter, none in the array, an empty VARIANT out.
/// `Variants(v, 0, [], ...)`: the array's elements would start at 8 (the engine pads to it even for
/// none).
fn variants(v: &V, d: Dialect) -> Msg {
    Msg::default().u32(USER).variant(v, d).u32(0).u32(0).align(8)
}

fn every_scalar() -> Vec<V> {
    vec![
        V::Empty,
        V::Null,
        V::I1(-1),
        V::Ui1(200),
        V::I2(-2),
        V::Bool(true),
        V::I4(-4),
        V::Int(4),
        V::R4(1.5),
        V::Error(0x80004005_u32 as i32),
        V::R8(2.5),
        V::Cy(12345),
        V::Date(45000.5),
        V::Decimal([14, 0, 2, 0, 0, 0, 0, 0, 0x39, 0x30, 0, 0, 0, 0, 0, 0]),
        V::Bstr(None),
        V::Bstr(Some(String::new())),
        V::Bstr(Some("value".into())),
    ]
}

#[test]
fn every_variant_arm_an_opc_value_has() {
    for d in BOTH {
        for v in every_scalar() {
            whole_request(T::INdrAutomation, "Variants", &variants(&v, d), d);
            let r = Msg::default().u32(USER).variant(&v, d).u32(S_OK_);
            whole_reply(T::INdrAutomation, "Variants", &NONE, &r, d);
        }
    }
    // VT_I8 and VT_UI8: 8 bytes at 8.
    for d in BOTH {
        for v in [
            V::I8(-8),
            V::Raw(21, 21, vec![0xEE, 0xEE, 0xEE, 0xEE, 1, 0, 0, 0, 0, 0, 0, 0]),
        ] {
            whole_request(T::INdrAutomation, "Variants", &variants(&v, d), d);
        }
    }
}

#[test]
fn variants_an_opc_value_cannot_be_are_refused() {
    let raw = |vt: u16, bytes: &[u8]| V::Raw(vt, u32::from(vt), bytes.to_vec());
    for (what, v) in [
        ("VT_UNKNOWN", raw(13, &[0; 8])),
        ("VT_DISPATCH", raw(9, &[0; 8])),
        ("VT_RECORD", raw(36, &[0; 8])),
        ("VT_BYREF | VT_I4", raw(0x4003, &[4, 0, 0, 0, 1, 0, 0, 0])),
        ("VT_VECTOR | VT_I4", raw(0x1003, &[0; 8])),
        ("VT_VARIANT alone", raw(12, &[0; 8])),
        ("an unknown VARTYPE", raw(0x0FFF, &[0; 8])),
        (
            "VT_ARRAY | VT_DECIMAL",
            V::Raw(VT_ARRAY | 14, 0x2000, vec![0x55, 0x73, 0x65, 0x72, 0, 0, 0, 0]),
        ),
        ("a discriminant other than vt", V::Raw(3, 4, vec![0; 4])),
        (
            "an array's discriminant with its type",
            V::Raw(VT_ARRAY | 3, 0x2003, vec![0x55, 0x73, 0x65, 0x72, 0, 0, 0, 0]),
        ),
    ] {
        for d in BOTH {
            assert_eq!(
                request(T::INdrAutomation, "Variants", &variants(&v, d), d),
                Err(BAD_STUB_DATA),
                "{what}, {d:?}"
            );
        }
    }
}

fn sa(vt: u16, bounds: &[(u32, i32)], data: SaData) -> V {
    V::Array(Some(Sa {
        vt,
        bounds: bounds.to_vec(),
        data,
    }))
}

#[test]
fn safearrays_of_every_element_type_in_both_dialects() {
    for d in BOTH {
        let arrays = [
            sa(17, &[(5, 0)], SaData::Plain(vec![1, 2, 3, 4, 5])),
            sa(11, &[(2, 1)], SaData::Plain(vec![0xFF, 0xFF, 0, 0])),
            sa(4, &[(2, 0), (3, 0)], SaData::Plain(vec![0; 24])),
            sa(5, &[(3, -1)], SaData::Plain(vec![0; 24])),
            sa(20, &[(1, 0)], SaData::Plain(vec![0; 8])),
            sa(
                8,
                &[(3, 0)],
                SaData::Bstrs(vec![Some("a".into()), None, Some("ccc".into())]),
            ),
            sa(
                12,
                &[(2, 0)],
                SaData::Variants(vec![V::I4(1), V::Bstr(Some("two".into()))]),
            ),
            sa(3, &[(0, 0)], SaData::Plain(vec![])),
            sa(3, &[(0, 0)], SaData::Null),
            V::Array(None),
        ];
        for v in &arrays {
            whole_request(T::INdrAutomation, "Variants", &variants(v, d), d);
        }
    }
}

#[test]
fn a_safearray_is_read_as_its_reader_reads_it() {
    // BSTRs and VARIANTs: referent IDs then the elements (Windows), or the elements only (Wine);
    // no data: no conformance (Windows) or one still (Wine). Each is refused by the other reader.
    // (A single VARIANT's ID can fall where Wine's reader pads to 8 and reads the same VARIANT: two
    // make the layouts differ.)
    for v in [
        sa(8, &[(2, 0)], SaData::Bstrs(vec![Some("a".into()), Some("b".into())])),
        sa(12, &[(2, 0)], SaData::Variants(vec![V::I2(1), V::I2(2)])),
        sa(3, &[(0, 0)], SaData::Null),
    ] {
        // One more VARIANT in the array after it, so that a misread shifts what follows.
        let then = |d| {
            Msg::default()
                .u32(USER)
                .variant(&v, d)
                .u32(1)
                .u32(1)
                .align(8)
                .u32(USER)
                .variant(&V::I4(7), d)
        };
        let ndr = then(Dialect::Ndr);
        let wine = then(Dialect::Wine);
        assert!(request(T::INdrAutomation, "Variants", &ndr, Dialect::Ndr).is_ok());
        assert!(request(T::INdrAutomation, "Variants", &wine, Dialect::Wine).is_ok());
        assert!(
            request(T::INdrAutomation, "Variants", &ndr, Dialect::Wine).is_err(),
            "{v:?}"
        );
        assert!(
            request(T::INdrAutomation, "Variants", &wine, Dialect::Ndr).is_err(),
            "{v:?}"
        );
    }
}

/// A SAFEARRAY of 2 VT_I4 with one of its header's words replaced (by its byte offset in the
/// wireSAFEARRAY, after the inner pointer).
fn i4_array_with(offset: usize, value: u32) -> Msg {
    let v = sa(3, &[(2, 0)], SaData::Plain(vec![1, 0, 0, 0, 2, 0, 0, 0]));
    let mut m = variants(&v, Dialect::Wine);
    // VARIANT: prefix (4), pad (4), header (20), arm prefix (4), inner pointer (4).
    let at = 8 + 20 + 4 + 4 + offset;
    m.0[at..at + 4].copy_from_slice(&value.to_le_bytes());
    m
}

#[test]
fn malformed_safearrays_are_refused() {
    let d = Dialect::Wine;
    assert!(request(T::INdrAutomation, "Variants", &i4_array_with(0, 1), d).is_ok());
    let bad = [
        ("conformance unlike cDims", 0, 2, BAD_STUB_DATA),
        ("no dimension", 4, 0x0080_0000, BAD_STUB_DATA),
        ("cbElements unlike the type", 8, 8, BAD_STUB_DATA),
        ("the VARTYPE in cLocks of another size", 12, 5 << 16, BAD_STUB_DATA),
        ("an interface array", 16, 13, BAD_STUB_DATA),
        ("another union type", 16, 20, BAD_STUB_DATA),
        ("a cell count unlike the bounds", 20, 3, BAD_STUB_DATA),
        ("an upper bound beyond 2^31", 32, i32::MAX as u32, BAD_STUB_DATA),
        ("the data's conformance unlike the cells", 36, 3, BAD_STUB_DATA),
        ("more cells than the message", 20, 100, BAD_STUB_DATA),
    ];
    for (what, offset, value, code) in bad {
        assert_eq!(
            request(T::INdrAutomation, "Variants", &i4_array_with(offset, value), d),
            Err(code),
            "{what}"
        );
    }
    // cDims beyond 32, elements beyond 2^24: bounds.
    let v = sa(17, &[(1, 0); 33], SaData::Plain(vec![1]));
    assert_eq!(
        request(T::INdrAutomation, "Variants", &variants(&v, d), d),
        Err(INVALID_BOUND)
    );
    let v = sa(17, &[(0, 0), ((1 << 24) + 1, 0)], SaData::Plain(vec![]));
    assert_eq!(
        request(T::INdrAutomation, "Variants", &variants(&v, d), d),
        Err(INVALID_BOUND)
    );
    // Bounds whose 32-bit product wraps to 0 (Wine would allocate nothing for 2^32 cells).
    let v = sa(17, &[(1 << 16, 0), (1 << 16, 0)], SaData::Plain(vec![]));
    let mut m = variants(&v, d);
    let at = 8 + 20 + 4 + 4 + 20;
    m.0[at..at + 4].copy_from_slice(&0u32.to_le_bytes());
    assert!(request(T::INdrAutomation, "Variants", &m, d).is_err());
    // A VARIANT whose element type is not the array's.
    let v = sa(3, &[(1, 0)], SaData::Plain(vec![0; 4]));
    let mut m = variants(&v, d);
    m.0[8 + 8..8 + 10].copy_from_slice(&(VT_ARRAY | 5).to_le_bytes());
    assert_eq!(request(T::INdrAutomation, "Variants", &m, d), Err(BAD_STUB_DATA));
    // A NULL data pointer with cells.
    let v = sa(3, &[(2, 0)], SaData::Null);
    assert_eq!(
        request(T::INdrAutomation, "Variants", &variants(&v, d), d),
        Err(BAD_STUB_DATA)
    );
    assert_eq!(element_size(3), 4);
    assert_eq!(sf_type(3), 3);
}

#[test]
fn variants_nest_at_most_four_deep() {
    let mut v = V::I4(1);
    for depth in 1..=5 {
        v = sa(12, &[(1, 0)], SaData::Variants(vec![v]));
        for d in BOTH {
            let r = request(T::INdrAutomation, "Variants", &variants(&v, d), d);
            if depth < MAX_VARIANT_DEPTH {
                assert!(r.is_ok(), "depth {depth}");
            } else {
                assert_eq!(r, Err(BAD_STUB_DATA), "depth {depth}");
            }
        }
    }
}

#[test]
fn an_array_of_variants_has_its_prefixes_then_their_bodies() {
    for d in BOTH {
        let m = Msg::default()
            .u32(USER)
            .variant(&V::Empty, d)
            .u32(2)
            .u32(2)
            .u32(USER)
            .u32(USER)
            .variant(&V::I4(1), d)
            .variant(&V::Bstr(Some("b".into())), d);
        whole_request(T::INdrAutomation, "Variants", &m, d);
    }
}

#[test]
fn safearray_parameters() {
    let v = Sa {
        vt: 8,
        bounds: vec![(1, 0)],
        data: SaData::Bstrs(vec![Some("x".into())]),
    };
    for d in BOTH {
        let m = Msg::default().user(d, 4, |m| m.safearray(Some(&v), d));
        whole_request(T::INdrAutomation, "Arrays", &m, d);
        let null = Msg::default().user(d, 4, |m| m.safearray(None, d));
        whole_request(T::INdrAutomation, "Arrays", &null, d);
        let r = Msg::default().user(d, 4, |m| m.safearray(Some(&v), d)).u32(S_OK_);
        whole_reply(T::INdrAutomation, "Arrays", &NONE, &r, d);
    }
    let (vt, switch) = vt_of(&V::Array(Some(v)));
    assert_eq!((vt, switch), (VT_ARRAY | 8, 0x2000));
}

// ---- Interface pointers ----

/// A standard OBJREF (MS-DCOM 2.2.18) for `iid`, with an empty DUALSTRINGARRAY.
fn objref(iid: [u8; 16]) -> Vec<u8> {
    let mut b = OBJREF_SIGNATURE.to_le_bytes().to_vec();
    b.extend_from_slice(&OBJREF_STANDARD.to_le_bytes());
    b.extend_from_slice(&iid);
    b.extend_from_slice(&[0x11; 40]);
    b.extend_from_slice(&[0, 0, 0, 0]);
    b
}

fn pointer(o: &[u8], d: Dialect) -> Msg {
    match d {
        Dialect::Wine => Msg::default().u32(o.len() as u32).raw(o),
        Dialect::Ndr => Msg::default()
            .u32(0x20000)
            .u32(o.len() as u32)
            .u32(o.len() as u32)
            .raw(o),
    }
}

const IID_IENUMGUID: [u8; 16] = [0x00, 0xE0, 0x02, 0x00, 0, 0, 0, 0, 0xC0, 0, 0, 0, 0, 0, 0, 0x46];
const IID_IUNKNOWN: [u8; 16] = [0, 0, 0, 0, 0, 0, 0, 0, 0xC0, 0, 0, 0, 0, 0, 0, 0x46];

#[test]
fn interface_pointers_of_a_fixed_interface() {
    for d in BOTH {
        let m = pointer(&objref(IID_IENUMGUID), d).u32(S_OK_);
        whole_reply(T::INdrInterfaces, "Fixed", &NONE, &m, d);
        let other = if d == Dialect::Wine {
            Dialect::Ndr
        } else {
            Dialect::Wine
        };
        assert_eq!(reply(T::INdrInterfaces, "Fixed", &NONE, &m, other), Err(BAD_STUB_DATA));
        let m = pointer(&objref(IID_IUNKNOWN), d).u32(S_OK_);
        assert_eq!(reply(T::INdrInterfaces, "Fixed", &NONE, &m, d), Err(BAD_STUB_DATA));
    }
}

#[test]
fn iid_is_takes_the_iid_from_the_request() {
    let riid = [0x42; 16];
    let ctx = request(T::INdrInterfaces, "ByIid", &Msg::default().guid(riid), Dialect::Wine).unwrap();
    assert_eq!(ctx, Context::of(&[0x4242_4242; 4]));
    for method in ["ByIid", "Void"] {
        for d in BOTH {
            let m = pointer(&objref(riid), d).u32(S_OK_);
            whole_reply(T::INdrInterfaces, method, &ctx, &m, d);
            // The interface the request did not ask for.
            let m = pointer(&objref(IID_IUNKNOWN), d).u32(S_OK_);
            assert_eq!(reply(T::INdrInterfaces, method, &ctx, &m, d), Err(BAD_STUB_DATA));
            whole_reply(T::INdrInterfaces, method, &ctx, &Msg::default().u32(0).u32(1), d);
        }
    }
}

#[test]
fn interface_pointers_in_requests() {
    let base = T::INdrBase.layout().iid;
    for d in BOTH {
        let m = pointer(&objref(IID_IUNKNOWN), d).raw(&pointer(&objref(base), d).0);
        whole_request(T::INdrInterfaces, "In", &m, d);
        let m = Msg::default().u32(0).raw(&pointer(&objref(IID_IUNKNOWN), d).0);
        assert_eq!(request(T::INdrInterfaces, "In", &m, d), Err(BAD_STUB_DATA));
    }
}

// ---- Methods, inheritance ----

#[test]
fn inherited_methods_come_first_and_unknown_ones_are_refused() {
    let derived = T::INdrDerived.layout();
    assert_eq!(derived.vtable, 7);
    let names: Vec<&str> = derived.methods.iter().map(|m| m.name).collect();
    assert_eq!(names, ["Scalars", "Guids", "Strings", "More"]);
    assert_eq!(
        check_request(derived, 3, scalars(1, 1).aligned().bytes(), LOCAL, Dialect::Wine),
        Ok(NONE)
    );
    for method in [0, 1, 2, 7, u32::MAX] {
        assert_eq!(
            check_request(derived, method, &[0; 8], LOCAL, Dialect::Wine),
            Err(PROCNUM_OUT_OF_RANGE)
        );
        assert_eq!(
            check_reply(derived, method, &NONE, &[0; 8], LOCAL, Dialect::Wine),
            Err(PROCNUM_OUT_OF_RANGE)
        );
    }
    // A foreign data representation.
    assert_eq!(
        check_request(derived, 6, &[0; 4], 0x0000, Dialect::Wine),
        Err(BAD_STUB_DATA)
    );
}

/// Arbitrary bytes against every method of the test IDL in both dialects: one of the three codes or
/// success, never a panic (Miri runs this too: no read outside the message).
#[test]
fn arbitrary_bytes_are_answered() {
    let mut seed = 0x5DEE_CE66_D1CE_4E5Bu64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let rounds = if cfg!(miri) { 300 } else { 30_000 };
    let words = [
        0u32,
        1,
        2,
        3,
        0x20000,
        USER,
        0x2000,
        0x200C,
        0x2008,
        12,
        8,
        0xFFFF_FFFF,
        0x574F_454D,
    ];
    for _ in 0..rounds {
        let mut m = Msg::default();
        for _ in 0..next() % 24 {
            m = match next() % 3 {
                0 => m.u32(words[(next() as usize) % words.len()]),
                1 => m.u32(next() as u32 % 5),
                _ => m.u8(next() as u8),
            };
        }
        let iface = T::all()[(next() as usize) % T::all().len()];
        let method = 3 + (next() % 8) as u32;
        let ctx = Context::of(&[(next() % 4) as u32, 0x4242_4242]);
        for d in BOTH {
            for r in [
                check_request(iface.layout(), method, m.aligned().bytes(), LOCAL, d).map(|_| ()),
                check_reply(iface.layout(), method, &ctx, m.aligned().bytes(), LOCAL, d),
            ] {
                if let Err(hr) = r {
                    assert!(
                        [BAD_STUB_DATA, INVALID_BOUND, PROCNUM_OUT_OF_RANGE].contains(&hr),
                        "{hr:#x}"
                    );
                }
            }
        }
    }
}

// ---- The fuzz target's seeds ----

/// Well-formed messages for the methods of the test IDL: (interface, method, reply?, dialect, context,
/// message).
fn seeds() -> Vec<(T, &'static str, bool, Dialect, Context, Msg)> {
    let mut out = Vec::new();
    for d in BOTH {
        out.push((T::INdrBase, "Scalars", false, d, NONE, scalars(2, 70000)));
        out.push((
            T::INdrBase,
            "Strings",
            false,
            d,
            NONE,
            Msg::default().wstr("w").cstr("n").u32(1).wstr("o"),
        ));
        out.push((
            T::INdrArrays,
            "InArray",
            false,
            d,
            NONE,
            Msg::default().u32(2).u32(2).u32(7).u32(8),
        ));
        out.push((
            T::INdrArrays,
            "CountedOut",
            true,
            d,
            NONE,
            Msg::default().u32(2).u32(1).u32(2).u32(1).u32(0).wstr("a").u32(0),
        ));
        out.push((
            T::INdrArrays,
            "Varying",
            true,
            d,
            Context::of(&[4]),
            Msg::default().u32(4).u32(0).u32(1).u32(7).u32(1).u32(0),
        ));
        let rec = record_flat(Msg::default().u32(1).u32(1), true, 2, true, 1, true);
        out.push((
            T::INdrStructs,
            "Records",
            false,
            d,
            NONE,
            record_pointees(rec, Some("n"), Some(&[1, 2]), &V::Bstr(Some("b".into())), Some(3), d),
        ));
        out.push((
            T::INdrStructs,
            "Tagged",
            false,
            d,
            NONE,
            Msg::default().u16(2).u32(2).u32(1).wstr("t").u16(1).u32(1).u32(5),
        ));
        for v in every_scalar().into_iter().chain([
            sa(12, &[(2, 0)], SaData::Variants(vec![V::I4(1), V::Bstr(None)])),
            sa(8, &[(1, 0)], SaData::Bstrs(vec![Some("x".into())])),
            sa(5, &[(1, 0)], SaData::Plain(vec![0; 8])),
        ]) {
            out.push((T::INdrAutomation, "Variants", false, d, NONE, variants(&v, d)));
        }
        out.push((
            T::INdrInterfaces,
            "Fixed",
            true,
            d,
            NONE,
            pointer(&objref(IID_IENUMGUID), d).u32(0),
        ));
        out.push((
            T::INdrInterfaces,
            "ByIid",
            true,
            d,
            Context::of(&[0x4242_4242; 4]),
            pointer(&objref([0x42; 16]), d).u32(0),
        ));
    }
    out
}

#[test]
fn the_fuzz_seeds_pass() {
    for (iface, name, is_reply, d, ctx, m) in seeds() {
        let r = if is_reply {
            reply(iface, name, &ctx, &m, d)
        } else {
            request(iface, name, &m, d).map(|_| ())
        };
        assert_eq!(r, Ok(()), "{iface:?} {name}");
    }
}

/// Writes the seeds to fuzz/seeds/ndr in the `ndr` target's input format:
/// `cargo test --lib write_ndr_fuzz_seeds -- --ignored`.
#[test]
#[ignore = "writes the fuzz target's seed corpus"]
fn write_ndr_fuzz_seeds() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/ndr");
    std::fs::create_dir_all(&dir).unwrap();
    for (n, (iface, name, is_reply, d, ctx, m)) in seeds().into_iter().enumerate() {
        let mut input = vec![
            iface as u8,
            (index(iface, name) - 3) as u8,
            u8::from(d == Dialect::Wine) | (u8::from(is_reply) << 1),
        ];
        for w in &ctx.0[..4] {
            input.extend_from_slice(&w.to_le_bytes());
        }
        input.extend_from_slice(&m.0);
        std::fs::write(dir.join(format!("{n:03}-{iface:?}-{name}")), input).unwrap();
    }
}
