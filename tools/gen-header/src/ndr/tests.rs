use std::collections::BTreeMap;

use super::parse;
use super::resolve::{self, Corr, Extent, Model, Node, Save};

fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn read(path: &str) -> String {
    std::fs::read_to_string(root().join(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn test_model() -> Model {
    super::model(
        &read,
        &[(super::TEST_IDL, "Test")],
        &["idl/combase.idl"],
        super::TEST_BOUNDS,
        false,
    )
    .unwrap()
}

/// The layouts of a small IDL (with combase.idl for IUnknown), or the generator's error.
fn small(idl: &str, bounds: &str) -> Result<Model, String> {
    let files = vec![
        parse::parse("t.idl", idl).map_err(|e| e.to_string())?,
        parse::parse("idl/combase.idl", &read("idl/combase.idl")).unwrap(),
    ];
    let bounds = resolve::parse_bounds("b.txt", bounds)?;
    resolve::model(&files, &[("t.idl", "T")], &bounds, false)
}

/// As [`small`], with every array a peer sizes required in the bounds file (as for the served IDL).
fn small_strict(idl: &str, bounds: &str) -> Result<Model, String> {
    let files = vec![
        parse::parse("t.idl", idl).map_err(|e| e.to_string())?,
        parse::parse("idl/combase.idl", &read("idl/combase.idl")).unwrap(),
    ];
    let bounds = resolve::parse_bounds("b.txt", bounds)?;
    resolve::model(&files, &[("t.idl", "T")], &bounds, true)
}

fn method<'m>(model: &'m Model, iface: &str, name: &str) -> &'m resolve::MethodOut {
    let i = model.interfaces.iter().find(|i| i.name == iface).unwrap();
    i.methods.iter().find(|m| m.name == name).unwrap()
}

fn array(n: &Node) -> &resolve::ArrayNode {
    match n {
        Node::Array(a) => a,
        Node::Pointer(_, t) => array(t),
        other => panic!("no array in {other:?}"),
    }
}

#[test]
fn the_test_idl_resolves_every_construct() {
    let m = test_model();
    let names: Vec<&str> = m.interfaces.iter().map(|i| i.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "INdrBase",
            "INdrArrays",
            "INdrStructs",
            "INdrAutomation",
            "INdrInterfaces",
            "INdrDerived"
        ]
    );
    // Base types, enums, alignment.
    let s = method(&m, "INdrBase", "Scalars");
    let kinds: Vec<&Node> = s.request.iter().map(|p| &p.node).collect();
    assert_eq!(
        kinds,
        [
            &Node::Base(1),
            &Node::Base(2),
            &Node::Base(4),
            &Node::Base(8),
            &Node::Base(4),
            &Node::Base(8),
            &Node::Enum16,
            &Node::Base(4)
        ]
    );
    assert!(s.request_align8 && s.reply_align8);
    assert!(!method(&m, "INdrBase", "Strings").request_align8);
    // Strings: [ref] at the top, [unique] by request, pointer_default inside.
    let st = method(&m, "INdrBase", "Strings");
    assert_eq!(st.request[0].node, Node::Pointer(false, Box::new(Node::Str(2))));
    assert_eq!(st.request[1].node, Node::Pointer(false, Box::new(Node::Str(1))));
    assert_eq!(st.request[2].node, Node::Pointer(true, Box::new(Node::Str(2))));
    assert_eq!(
        st.reply[0].node,
        Node::Pointer(false, Box::new(Node::Pointer(true, Box::new(Node::Str(2)))))
    );
    // An [in] count of an [out] array: kept for the reply, bounded in the request.
    let o = method(&m, "INdrArrays", "OutArray");
    assert_eq!(o.request[0].save, Save::Int(0));
    assert_eq!(o.context, [Save::Int(0)]);
    assert_eq!(o.bounds, [(0, resolve::DEFAULT_BOUND)]);
    // An [out] count: no context.
    let c = method(&m, "INdrArrays", "CountedOut");
    assert!(c.context.is_empty() && c.bounds.is_empty());
    assert_eq!(c.reply[0].save, Save::Int(0));
    let a = array(&c.reply[1].node);
    assert_eq!(a.size, Extent::Conformant(Corr::Slot(0)));
    assert_eq!(a.elem, Node::Pointer(true, Box::new(Node::Str(2))));
    // Varying: size from the request, length from the reply.
    let v = method(&m, "INdrArrays", "Varying");
    let a = array(&v.reply[0].node);
    assert_eq!(
        (a.size, a.length),
        (Extent::Conformant(Corr::Slot(0)), Some(Corr::Slot(1)))
    );
    assert_eq!(v.context, [Save::Int(0)]);
    // The bounds file.
    assert_eq!(array(&method(&m, "INdrArrays", "Bounded").request[1].node).bound, 16);
    assert_eq!(m.structs["RECORD"].fields[2].0, "pBlob");
    assert_eq!(array(&m.structs["RECORD"].fields[2].1).bound, 1024);
    assert_eq!(
        array(&m.structs["RECORD"].fields[2].1).size,
        Extent::Conformant(Corr::Field(1))
    );
    // Fixed arrays: as a parameter, a [ref] pointer to it; in a structure, inline.
    let f = &method(&m, "INdrArrays", "Fixed").request[0].node;
    assert_eq!(array(f).size, Extent::Fixed(4));
    assert!(matches!(&m.structs["TIMED"].fields[3].1, Node::Array(a) if a.size == Extent::Fixed(3)));
    // Two levels.
    let t = array(&method(&m, "INdrArrays", "TwoLevel").request[2].node);
    assert_eq!(t.size, Extent::Conformant(Corr::Slot(0)));
    assert_eq!(array(&t.elem).size, Extent::Conformant(Corr::Slot(1)));
}

#[test]
fn structures_unions_and_their_sizes() {
    let m = test_model();
    let s = &m.structs;
    assert_eq!(
        (s["PLAIN"].align, s["PLAIN"].plain, s["PLAIN"].deferred),
        (4, 24, false)
    );
    assert_eq!(
        (s["PADDED"].align, s["PADDED"].plain),
        (4, 0),
        "padding at its end: not plain"
    );
    assert_eq!(
        (s["TIMED"].align, s["TIMED"].plain),
        (8, 0),
        "an enum to check: not plain"
    );
    assert_eq!((s["FILETIME"].align, s["FILETIME"].plain), (4, 8));
    assert!(s["RECORD"].deferred && s["NESTED"].deferred && s["TAGGED"].deferred);
    assert_eq!(s["RECORD"].fields[4].1, Node::Variant);
    let Node::Union(u) = &s["TAGGED"].fields[1].1 else {
        panic!()
    };
    assert_eq!((u.switch, u.size), (Corr::Field(0), 4));
    let cases: Vec<u32> = u.arms.iter().map(|a| a.0).collect();
    assert_eq!(cases, [1, 2, 16], "KIND_LONG, KIND_TEXT, KIND_HYPER");
    assert_eq!(u.default, Some(Node::Empty));
    assert_eq!(s["TAGGED"].align, 8);
    // A union parameter switched by another parameter.
    let t = method(&m, "INdrStructs", "Tagged");
    let Node::Pointer(false, u) = &t.request[2].node else {
        panic!()
    };
    assert!(matches!(&**u, Node::Union(u) if u.switch == Corr::Slot(0)));
}

#[test]
fn automation_types_and_interface_pointers() {
    let m = test_model();
    let b = method(&m, "INdrAutomation", "Bstrs");
    assert_eq!(b.request[0].node, Node::Bstr);
    assert_eq!(b.reply[0].node, Node::Pointer(false, Box::new(Node::Bstr)));
    assert!(b.request_align8, "Wine aligns a BSTR's body to 8");
    assert_eq!(method(&m, "INdrAutomation", "Arrays").request[0].node, Node::SafeArray);
    let f = method(&m, "INdrInterfaces", "Fixed");
    let iid = resolve::guid_bytes("0002E000-0000-0000-C000-000000000046").unwrap();
    assert_eq!(
        f.reply[0].node,
        Node::Pointer(false, Box::new(Node::Interface("IEnumGUID".into(), Some(iid), 0)))
    );
    for name in ["ByIid", "Void"] {
        let b = method(&m, "INdrInterfaces", name);
        assert_eq!(b.request[0].save, Save::Guid(0));
        assert_eq!(b.context, [Save::Guid(0)]);
        assert!(matches!(&b.reply[0].node, Node::Pointer(false, i) if matches!(**i, Node::Interface(_, None, 0))));
    }
    // Inheritance.
    let d = m.interfaces.iter().find(|i| i.name == "INdrDerived").unwrap();
    assert_eq!(d.vtable, 7);
    let names: Vec<&str> = d.methods.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["Scalars", "Guids", "Strings", "More"]);
}

#[test]
fn opc_common_resolves_to_the_layouts_it_has_always_had() {
    let m = super::model(
        &read,
        super::SERVED,
        &["idl/combase.idl", "idl/internal.idl"],
        "idl/ndr-bounds.txt",
        true,
    )
    .unwrap();
    let v: Vec<(&str, u32)> = m.interfaces[..5].iter().map(|i| (i.name.as_str(), i.vtable)).collect();
    assert_eq!(
        v,
        [
            ("IOPCShutdown", 4),
            ("IOPCCommon", 8),
            ("IOPCServerList", 6),
            ("IOPCEnumGUID", 7),
            ("IOPCServerList2", 6)
        ]
    );
    let next = method(&m, "IOPCEnumGUID", "Next");
    assert_eq!(next.context, [Save::Int(0)]);
    assert_eq!(next.bounds, [(0, 65_536)]);
    let q = method(&m, "IOPCCommon", "QueryAvailableLocaleIDs");
    assert!(q.request.is_empty());
    assert_eq!(q.reply.len(), 3, "count, array, HRESULT");
    // Every bound is named, with its reason.
    assert!(m.bounds.iter().all(|b| b.reason.is_some()), "{:?}", m.bounds);
}

#[test]
fn data_access_resolves_with_every_bound_decided() {
    let m = super::model(
        &read,
        super::SERVED,
        &["idl/combase.idl", "idl/internal.idl"],
        "idl/ndr-bounds.txt",
        true,
    )
    .unwrap();
    let da: Vec<(&str, u32, &str)> = m
        .interfaces
        .iter()
        .filter(|i| i.spec == "DA")
        .map(|i| (i.name.as_str(), i.vtable, i.spec.as_str()))
        .collect();
    assert_eq!(da.len(), 19);
    // Alarms & Events' 6 and HDA's 10 follow.
    let specs: Vec<&str> = m.interfaces.iter().map(|i| i.spec.as_str()).collect();
    assert_eq!(specs.iter().filter(|s| **s == "AE").count(), 6);
    assert_eq!(specs.iter().filter(|s| **s == "HDA").count(), 10);
    assert!(m.interfaces[..5].iter().all(|i| i.spec == "Common"));
    // Derived interfaces carry their bases' methods first.
    assert!(da.contains(&("IOPCSyncIO2", 7, "DA")));
    assert!(da.contains(&("IOPCAsyncIO3", 12, "DA")));
    assert!(da.contains(&("IOPCGroupStateMgt2", 9, "DA")));
    // A sync read: dwCount sizes the server's arrays in the reply, so the reply needs it and it is
    // bounded as soon as the request is read.
    let read = method(&m, "IOPCSyncIO", "Read");
    assert_eq!(read.context, [Save::Int(0)]);
    assert_eq!(read.bounds, [(0, 1_048_576)]);
    // AddGroup's iid_is: the IID goes to the reply's context (four words).
    let add = method(&m, "IOPCServer", "AddGroup");
    assert_eq!(add.context.len(), 1);
    assert!(matches!(add.context[0], Save::Guid(_)), "{:?}", add.context);
    // Browse: a count the server returns sizes its array.
    let browse = method(&m, "IOPCBrowse", "Browse");
    assert!(browse.bounds.is_empty(), "nothing of the request sizes the reply");
    let blob = m.bounds.iter().find(|b| b.key == "OPCITEMDEF.pBlob").unwrap();
    assert_eq!(blob.bound, 65_536);
    assert!(m.bounds.iter().all(|b| b.reason.is_some()), "{:?}", m.bounds);
}

#[test]
fn the_generated_files_say_what_the_interpreter_needs() {
    let m = test_model();
    let rust = super::emit::rust(&m, "t.idl", "//! test\n");
    assert!(rust.contains("pub enum Interface {\n    INdrBase = 0,"));
    assert!(rust.contains("static STRUCT_RECORD: Struct = Struct {"));
    assert!(rust.contains("//! - `RECORD.pBlob`: 1024 a structure field's own bound"));
    assert!(rust.contains("//! - `INdrArrays.InArray.phItems`: 65536 (the default)"));
    let c = super::emit::c_include(&m, "t.idl", 8);
    assert!(c.contains("#define OPC_PS_INTERFACE_COUNT 6"));
    assert!(c.contains("    &IID_INdrDerived,\n};"));
}

const HEAD: &str =
    "[object, uuid(6E0C1B10-0000-4E44-9C00-0000000000AA), pointer_default(unique)]\ninterface ITest : IUnknown {\n";

fn one(decls: &str, method: &str) -> Result<Model, String> {
    small(&format!("{decls}\n{HEAD}{method}\n}}"), "")
}

#[test]
fn what_the_language_cannot_say_is_refused_with_a_reason() {
    let cases: &[(&str, &str, &str)] = &[
        ("", "HRESULT M([in] DWORD n, [in, size_is(n * 2)] DWORD *p);", "not supported"),
        ("", "HRESULT M([in, ptr] DWORD *p);", "[ptr] is not supported"),
        ("", "HRESULT M([in] UNKNOWN_T x);", "unknown type UNKNOWN_T"),
        ("", "HRESULT M([out] DWORD *n, [in, size_is(*n)] DWORD *p);", "[out]-only"),
        ("", "HRESULT M([in] DWORD n, [in, size_is(m)] DWORD *p);", "names no parameter"),
        ("", "HRESULT M([in, string] DWORD *p);", "[string] on a pointer to something other"),
        ("", "HRESULT M([in, max_is(n)] DWORD *p, [in] DWORD n);", "[max_is] is not supported"),
        ("", "HRESULT M([out] DWORD n);", "an [out] parameter must be a pointer"),
        ("", "HRESULT M([in] ITest *p, [out, iid_is(p)] IUnknown **pp);", "a GUID"),
        ("", "ULONG M();", "return HRESULT"),
        ("", "[local] HRESULT M();", "[local]"),
        ("", "HRESULT M([in] DWORD n, [in, size_is(*n)] DWORD *p);", "must be `n`"),
        ("typedef struct tagS { DWORD n; [size_is(n)] DWORD a[]; } S;", "HRESULT M([in] S *s);", "conformant arrays inside structures"),
        ("typedef struct tagS { IUnknown *p; } S;", "HRESULT M([in] S *s);", "interface pointers inside structures"),
        ("typedef struct tagS { struct tagS *next; } S;", "HRESULT M([in] S *s);", "recursive"),
        ("typedef union tagU { [case(1)] DWORD a; } U;", "HRESULT M([in] DWORD k, [in, switch_is(k)] U *u);", "[switch_type]"),
        ("", "HRESULT M([in] REFIID a, [in] REFIID b, [in] REFIID c, [out, iid_is(a)] IUnknown **x, [out, iid_is(b)] IUnknown **y, [out, iid_is(c)] IUnknown **z);", "more than 8 words"),
        ("", "HRESULT M([in] DWORD n, [in, size_is(n)] IUnknown **pp);", "arrays of interface pointers"),
        ("typedef struct tagE { } E;", "HRESULT M([in] E *e);", "has no field"),
        ("", "HRESULT M([out, iid_is(riid)] IUnknown **pp, [in] REFIID riid);", "names a later parameter"),
    ];
    for (decls, m, expected) in cases {
        let e = one(decls, m).map(|_| ()).unwrap_err();
        assert!(e.contains(expected), "{m}: {e}");
    }
    let e = small(
        &format!("{HEAD}HRESULT M([in] DWORD n, [in, size_is(n)] DWORD *p);\n}}"),
        "ITest.M.q 5 why\n",
    )
    .unwrap_err();
    assert!(e.contains("sizes no array"), "{e}");
    let e = resolve::parse_bounds("b.txt", "ITest.M.p 5\n").unwrap_err();
    assert!(e.contains("needs its reason"), "{e}");
    // Where every bound must be decided (the served IDL), an array a peer sizes without its line is
    // refused, each one named; with its line it resolves to that bound.
    let idl = format!(
        "typedef struct tagS {{ DWORD n; [size_is(n)] BYTE *b; }} S;\n{HEAD}HRESULT M([in] DWORD n, [in, size_is(n)] S *p, [out, size_is(,n)] DWORD **q);\n}}"
    );
    let e = small_strict(&idl, "ITest.M.q 7 why\n").unwrap_err();
    assert!(e.contains("no bound") && e.contains("ITest.M.p, S.b"), "{e}");
    assert!(!e.contains("ITest.M.q"), "{e}");
    let m = small_strict(&idl, "ITest.M.q 7 why\nITest.M.p 5 why\nS.b 3 why\n").unwrap();
    assert_eq!(method(&m, "ITest", "M").bounds, [(0, 7)]);
}

#[test]
fn what_it_can_say_resolves() {
    // An [in] count named after the array, a count in [in, out], a narrow string, a struct by tag.
    let m = one(
        "typedef struct tagP { DWORD a; } P;",
        "HRESULT M([in, size_is(n)] DWORD *p, [in] DWORD n, [in, out] DWORD *io, [out, size_is(, *io)] struct tagP **pp, [in, string] char *s);",
    )
    .unwrap();
    let mm = method(&m, "ITest", "M");
    assert_eq!(mm.request[0].save, Save::None);
    assert_eq!(mm.request[1].save, Save::Int(0));
    assert_eq!(
        mm.reply[0].save,
        Save::Int(1),
        "an [in, out] count is read in the reply"
    );
    assert!(mm.context.is_empty());
    assert_eq!(array(&mm.reply[1].node).elem, Node::Struct("P".into()));
}

#[test]
fn guid_text_to_ndr_bytes() {
    assert_eq!(
        resolve::guid_bytes("F31DFDE2-07B6-11d2-B2D8-0060083BA1FB").unwrap(),
        [0xE2, 0xFD, 0x1D, 0xF3, 0xB6, 0x07, 0xD2, 0x11, 0xB2, 0xD8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB]
    );
    assert!(resolve::guid_bytes("F31DFDE2-07B6-11d2-B2D8").is_none());
    let _ = BTreeMap::<u8, u8>::new();
}

/// Declarations in the shape of Data Access 2.05a / 3.0's (structures with strings, blobs, VARIANTs
/// and nested arrays; `[unique]` in-pointers; `iid_is` after `[out]` parameters; `[in, out]` strings;
/// counts of several `[out]` arrays) resolve, with the counts, contexts and bounds they need.
#[test]
fn data_access_shaped_declarations_resolve() {
    let decls = r#"
        typedef DWORD OPCHANDLE;
        typedef enum tagOPCDATASOURCE { OPC_DS_CACHE = 1, OPC_DS_DEVICE } OPCDATASOURCE;
        typedef struct tagOPCITEMDEF { [string] LPWSTR szAccessPath; [string] LPWSTR szItemID; BOOL bActive;
            OPCHANDLE hClient; DWORD dwBlobSize; [size_is(dwBlobSize)] BYTE *pBlob; VARTYPE vtRequestedDataType;
            WORD wReserved; } OPCITEMDEF;
        typedef struct tagOPCITEMRESULT { OPCHANDLE hServer; VARTYPE vtCanonicalDataType; WORD wReserved;
            DWORD dwAccessRights; DWORD dwBlobSize; [size_is(dwBlobSize)] BYTE *pBlob; } OPCITEMRESULT;
        typedef struct tagOPCITEMSTATE { OPCHANDLE hClient; FILETIME ftTimeStamp; WORD wQuality; WORD wReserved;
            VARIANT vDataValue; } OPCITEMSTATE;
        typedef struct tagOPCITEMPROPERTY { VARTYPE vtDataType; WORD wReserved; DWORD dwPropertyID;
            [string] LPWSTR szItemID; [string] LPWSTR szDescription; VARIANT vValue; HRESULT hrErrorID;
            DWORD dwReserved; } OPCITEMPROPERTY;
        typedef struct tagOPCITEMPROPERTIES { HRESULT hrErrorID; DWORD dwNumProperties;
            [size_is(dwNumProperties)] OPCITEMPROPERTY *pItemProperties; DWORD dwReserved; } OPCITEMPROPERTIES;
        typedef struct tagOPCBROWSEELEMENT { [string] LPWSTR szName; [string] LPWSTR szItemID; DWORD dwFlagValue;
            DWORD dwReserved; OPCITEMPROPERTIES ItemProperties; } OPCBROWSEELEMENT;
    "#;
    let methods = r#"
        HRESULT AddGroup([in, string] LPCWSTR szName, [in] BOOL bActive, [in] DWORD dwRequestedUpdateRate,
            [in] OPCHANDLE hClientGroup, [unique, in] LONG *pTimeBias, [in, unique] FLOAT *pPercentDeadband,
            [in] DWORD dwLCID, [out] OPCHANDLE *phServerGroup, [out] DWORD *pRevisedUpdateRate,
            [in] REFIID riid, [out, iid_is(riid)] LPUNKNOWN *ppUnk);
        HRESULT AddItems([in] DWORD dwCount, [in, size_is(dwCount)] OPCITEMDEF *pItemArray,
            [out, size_is(, dwCount)] OPCITEMRESULT **ppAddResults, [out, size_is(, dwCount)] HRESULT **ppErrors);
        HRESULT Read([in] OPCDATASOURCE dwSource, [in] DWORD dwCount, [in, size_is(dwCount)] OPCHANDLE *phServer,
            [out, size_is(, dwCount)] OPCITEMSTATE **ppItemValues, [out, size_is(, dwCount)] HRESULT **ppErrors);
        HRESULT Write([in] DWORD dwCount, [in, size_is(dwCount)] OPCHANDLE *phServer,
            [in, size_is(dwCount)] VARIANT *pItemValues, [out, size_is(, dwCount)] HRESULT **ppErrors);
        HRESULT QueryAvailableProperties([in] LPWSTR szItemID, [out] DWORD *pdwCount,
            [out, size_is(, *pdwCount)] DWORD **ppPropertyIDs, [out, size_is(, *pdwCount)] LPWSTR **ppDescriptions,
            [out, size_is(, *pdwCount)] VARTYPE **ppvtDataTypes);
        HRESULT Browse([in, string] LPWSTR szItemID, [in, out, string] LPWSTR *pszContinuationPoint,
            [in] DWORD dwMaxElementsReturned, [in] DWORD dwPropertyCount,
            [in, size_is(dwPropertyCount)] DWORD *pdwPropertyIDs, [out] BOOL *pbMoreElements,
            [out] DWORD *pdwCount, [out, size_is(, *pdwCount)] OPCBROWSEELEMENT **ppBrowseElements);
        HRESULT BrowseOPCItemIDs([in, string] LPCWSTR szFilterCriteria, [in] VARTYPE vtDataTypeFilter,
            [out] LPENUMSTRING *ppIEnumString);
    "#;
    let m = one(decls, methods).unwrap();
    let add = method(&m, "ITest", "AddGroup");
    assert_eq!(
        add.context,
        [Save::Guid(0)],
        "the reply's interface is the request's riid"
    );
    assert!(matches!(&add.request[4].node, Node::Pointer(true, b) if **b == Node::Base(4)));
    let items = method(&m, "ITest", "AddItems");
    assert_eq!(items.context, [Save::Int(0)]);
    assert_eq!(items.bounds, [(0, resolve::DEFAULT_BOUND)]);
    assert!(m.structs["OPCITEMDEF"].deferred && m.structs["OPCITEMSTATE"].deferred);
    assert_eq!(
        m.structs["OPCITEMSTATE"].size, 20,
        "hClient, FILETIME, two WORDs, the VARIANT's prefix"
    );
    let read = method(&m, "ITest", "Read");
    assert!(read.reply_align8, "a VARIANT");
    assert_eq!(read.request[0].node, Node::Enum16);
    let q = method(&m, "ITest", "QueryAvailableProperties");
    assert!(q.context.is_empty());
    assert!(q.reply[1..4]
        .iter()
        .all(|p| array(&p.node).size == Extent::Conformant(Corr::Slot(0))));
    let b = method(&m, "ITest", "Browse");
    assert_eq!(b.request[1].node, b.reply[0].node, "an [in, out] string both ways");
    assert_eq!(
        m.structs["OPCITEMPROPERTIES"].fields[2].1,
        Node::Pointer(
            true,
            Box::new(Node::Array(Box::new(resolve::ArrayNode {
                elem: Node::Struct("OPCITEMPROPERTY".into()),
                size: Extent::Conformant(Corr::Field(1)),
                length: None,
                bound: resolve::DEFAULT_BOUND,
            })))
        )
    );
    let e = method(&m, "ITest", "BrowseOPCItemIDs");
    assert!(
        matches!(&e.reply[0].node, Node::Pointer(false, i) if matches!(&**i, Node::Interface(n, Some(_), _) if n == "IEnumString"))
    );
}
