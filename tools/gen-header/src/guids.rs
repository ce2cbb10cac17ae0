//! The GUID facts: `idl/opcguids.txt` (categories and classes) and the `uuid()` of every interface in
//! the IDL files, with what is derived from them.

use crate::idl::Interface;

/// How the C header declares an identifier.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Form {
    /// An empty interface whose IID is the value, and `#define NAME IID_<interface>` (opcda.h's,
    /// opchda.h's and opc_ae.h's form). The interface is named NAME (`interface` in the table) or
    /// otherwise (`interface=OPCEventServerCATID`, as opc_ae.h names the Alarms & Events category).
    Interface,
    /// `EXTERN_C const CATID NAME;`.
    Constant,
    /// Only the Rust code uses it.
    Internal,
}

#[derive(Debug, Clone)]
pub struct Entry {
    pub kind: String,
    pub form: Form,
    pub name: String,
    pub guid: String,
    pub note: String,
    /// The interface's name when the form is `interface=NAME`.
    pub interface: Option<String>,
}

impl Entry {
    /// The name of the empty interface of the interface form (`CATID_OPCDAServer20`,
    /// `OPCEventServerCATID`).
    pub fn interface_name(&self) -> &str {
        self.interface.as_deref().unwrap_or(&self.name)
    }

    /// The data symbol the C API exports (IID_CATID_OPCDAServer20, IID_OPCEventServerCATID for the
    /// interface form).
    pub fn symbol(&self) -> String {
        match self.form {
            Form::Interface => format!("IID_{}", self.interface_name()),
            _ => self.name.clone(),
        }
    }
}

pub fn parse_table(text: &str) -> Result<Vec<Entry>, String> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut parts = line.split_whitespace();
        let mut field = |what: &str| {
            parts
                .next()
                .map(str::to_string)
                .ok_or_else(|| format!("idl/opcguids.txt:{}: missing {what}", n + 1))
        };
        let kind = field("kind")?;
        let form_field = field("form")?;
        let (form_name, interface) = match form_field.split_once('=') {
            Some((f, i)) => (f, Some(i.to_string())),
            None => (form_field.as_str(), None),
        };
        let form = match form_name {
            "interface" => Form::Interface,
            "constant" if interface.is_none() => Form::Constant,
            "internal" if interface.is_none() => Form::Internal,
            _ => return Err(format!("idl/opcguids.txt:{}: unknown form {form_field}", n + 1)),
        };
        let name = field("name")?;
        let guid = field("GUID")?;
        // The description may contain single spaces; the columns are separated by runs of them.
        let rest = line.split_once(&guid).map_or("", |x| x.1).trim().to_string();
        parse_guid(&guid).ok_or_else(|| format!("idl/opcguids.txt:{}: bad GUID {guid}", n + 1))?;
        if !matches!(kind.as_str(), "category" | "class" | "iid") {
            return Err(format!("idl/opcguids.txt:{}: unknown kind {kind}", n + 1));
        }
        out.push(Entry {
            kind,
            form,
            name,
            guid,
            note: rest,
            interface,
        });
    }
    Ok(out)
}

/// `F31DFDE2-07B6-11d2-B2D8-0060083BA1FB` → its 128-bit value.
pub fn parse_guid(text: &str) -> Option<u128> {
    let groups: Vec<&str> = text.split('-').collect();
    if groups.len() != 5 || [8, 4, 4, 4, 12].iter().zip(&groups).any(|(n, g)| g.len() != *n) {
        return None;
    }
    u128::from_str_radix(&groups.concat(), 16).ok()
}

/// The C initialiser `{0xF31DFDE2, 0x07B6, 0x11D2, {0xB2, 0xD8, ...}}`.
pub fn c_initializer(guid: &str) -> String {
    let v = parse_guid(guid).expect("checked GUID");
    let d4: Vec<String> = (0..8).map(|i| format!("0x{:02X}", (v >> (56 - 8 * i)) as u8)).collect();
    format!(
        "{{0x{:08X}, 0x{:04X}, 0x{:04X}, {{{}}}}}",
        (v >> 96) as u32,
        (v >> 80) as u16,
        (v >> 64) as u16,
        d4.join(", ")
    )
}

/// The `__CRT_UUID_DECL` arguments `0xf31dfde2, 0x07b6, 0x11d2, 0xb2,0xd8, ...` (as widl writes them).
pub fn crt_uuid_args(guid: &str) -> String {
    let v = parse_guid(guid).expect("checked GUID");
    let d4: Vec<String> = (0..8).map(|i| format!("0x{:02x}", (v >> (56 - 8 * i)) as u8)).collect();
    format!(
        "0x{:08x}, 0x{:04x}, 0x{:04x}, {}",
        (v >> 96) as u32,
        (v >> 80) as u16,
        (v >> 64) as u16,
        d4.join(",")
    )
}

/// The Rust expression `GUID::from_u128(0xF31DFDE2_07B6_11D2_B2D8_0060083BA1FB)`.
fn rust_value(guid: &str) -> String {
    format!("GUID::from_u128(0x{})", guid.to_uppercase().replace('-', "_"))
}

/// What a generated identifier is for, in the Rust and C comments.
fn describe(e: &Entry) -> String {
    match e.kind.as_str() {
        "category" => format!("`{}` {{{}}}: {}.", e.name, e.guid, e.note.trim_end_matches('.')),
        "class" => format!("`{}` {{{}}}: the class `{}`.", e.name, e.guid, e.note),
        _ => format!("`{}` {{{}}}.", e.name, e.guid),
    }
}

/// One exported data item: the symbol, its value, its comment, and whether only non-Windows systems
/// export it (the standard COM IIDs, which Windows' uuid.lib provides).
pub struct Datum {
    pub symbol: String,
    pub guid: String,
    pub comment: String,
    pub unix_only: bool,
}

/// Every data symbol the C API exports, in a fixed order: OPC interface IIDs, then the table, then the
/// standard COM IIDs.
pub fn exported_data(opc: &[Interface], base: &[Interface], table: &[Entry]) -> Vec<Datum> {
    let mut out = Vec::new();
    for i in opc {
        out.push(Datum {
            symbol: format!("IID_{}", i.name),
            guid: i.uuid.clone(),
            comment: format!("IID of `{}` {{{}}}.", i.name, i.uuid),
            unix_only: false,
        });
    }
    for e in table.iter().filter(|e| e.form != Form::Internal) {
        out.push(Datum {
            symbol: e.symbol(),
            guid: e.guid.clone(),
            comment: describe(e),
            unix_only: false,
        });
    }
    // The identifiers earlier versions of the header declared as constants under their own name, and
    // that programs built with those headers import: still exported (the header now declares them as
    // the Foundation's header does, e.g. CATID_OPCAEServer10 as IID_OPCEventServerCATID).
    for e in table.iter().filter(|e| e.interface.is_some()) {
        out.push(Datum {
            symbol: e.name.clone(),
            guid: e.guid.clone(),
            comment: format!(
                "{} (the symbol of earlier versions of the header)",
                describe(e).trim_end_matches('.')
            ),
            unix_only: false,
        });
    }
    for i in base {
        out.push(Datum {
            symbol: format!("IID_{}", i.name),
            guid: i.uuid.clone(),
            comment: format!(
                "IID of `{}` {{{}}} (exported on systems without uuid.lib).",
                i.name, i.uuid
            ),
            unix_only: true,
        });
    }
    out
}

/// `src/com/guids.rs`: every identifier as a Rust constant (the library's private copies) and, in a
/// module cbindgen skips, the exported data symbols of the shared library.
pub fn rust_module(opc: &[Interface], base: &[Interface], table: &[Entry]) -> String {
    let mut s = String::from(
        "// Generated by tools/gen-header from idl/opccomn.idl, idl/combase.idl and idl/opcguids.txt: do not\n\
         // edit. Run `cargo run -p gen-header`.\n\
         //! Every interface, class and category identifier the library knows, derived from the IDL and\n\
         //! idl/opcguids.txt. The constants are the library's own copies; `exported` holds the data\n\
         //! symbols of the shared library (the static library built by CMake takes them from one object\n\
         //! file per symbol instead, see src/c/opccomn_guids.c).\n\n\
         #![allow(non_upper_case_globals)]\n\n\
         use super::types::GUID;\n\n",
    );
    for i in base.iter().chain(opc) {
        s += &format!(
            "/// IID of `{}` {{{}}}.\npub const IID_{}: GUID = {};\n",
            i.name,
            i.uuid,
            i.name,
            rust_value(&i.uuid)
        );
    }
    for e in table {
        s += &format!(
            "/// {}\npub const {}: GUID = {};\n",
            describe(e),
            e.name,
            rust_value(&e.guid)
        );
    }
    s += "\n/// The standard English descriptions of the OPC component categories.\npub const CATEGORY_DESCRIPTIONS: &[(GUID, &str)] = &[\n";
    for e in table.iter().filter(|e| e.kind == "category") {
        s += &format!("    ({}, {:?}),\n", e.name, e.note);
    }
    s += "];\n\n/// The exported data symbols (`opccomn_i.c` and `opc_cats.c` provide the same to OPC programs).\n\
          /// cbindgen:ignore\npub mod exported {\n    use super::*;\n";
    for d in exported_data(opc, base, table) {
        let value = table
            .iter()
            .find(|e| e.symbol() == d.symbol)
            .map_or_else(|| d.symbol.clone(), |e| e.name.clone());
        let cfg = if d.unix_only { "    #[cfg(not(windows))]\n" } else { "" };
        s += &format!(
            "\n    /// {}\n{cfg}    #[export_name = \"{}\"]\n    pub static EXPORTED_{}: GUID = {};\n",
            d.comment, d.symbol, d.symbol, value
        );
    }
    s += "}\n";
    s
}

/// `src/c/opccomn_guids.c`: the same data as C definitions, one per `OPCCOMN_GUID_ONLY` value, so a
/// build can compile one object file per symbol.
pub fn c_data(opc: &[Interface], base: &[Interface], table: &[Entry]) -> String {
    let data = exported_data(opc, base, table);
    let mut s = format!(
        "/* Generated by tools/gen-header from idl/opccomn.idl, idl/combase.idl and idl/opcguids.txt: do not edit.\n\
         \n\
         The data symbols of the opccomn C API (interface, class and category identifiers), for static\n\
         libraries and import libraries. Compile it as C, once per symbol, with -DOPCCOMN_GUID_ONLY=n\n\
         (n = 1 .. OPCCOMN_GUID_COUNT), and put each object into the library as its own member: a program\n\
         that also links the OPC Foundation's opccomn_i.c (or another definition of the same symbol) then\n\
         takes that definition, the linker never pulls the library's copy, and nothing is defined twice.\n\
         Compiled without OPCCOMN_GUID_ONLY it defines them all. The standard COM IIDs (marked \"not\n\
         _WIN32\") are left out on Windows, where programs get them from uuid.lib.\n\
         \n\
         Self-contained (no system header), so any C compiler for the target builds it, MSVC's included;\n\
         the type has the layout of GUID. */\n\
         #define OPCCOMN_GUID_COUNT {}\n\n\
         typedef struct opccomn_guid {{\n    unsigned int Data1;\n    unsigned short Data2;\n    unsigned short Data3;\n    unsigned char Data4[8];\n}} opccomn_guid;\n\n\
         #if !defined(OPCCOMN_GUID_ONLY)\n#define OPCCOMN_GUID_ALL 1\n#define OPCCOMN_GUID_ONLY 0\n#else\n#define OPCCOMN_GUID_ALL 0\n#endif\n",
        data.len()
    );
    for (n, d) in data.iter().enumerate() {
        let cond = if d.unix_only {
            " && !defined(_WIN32) /* not _WIN32 */"
        } else {
            ""
        };
        s += &format!(
            "\n/* {} */\n#if (OPCCOMN_GUID_ALL || OPCCOMN_GUID_ONLY == {}){cond}\nconst opccomn_guid {} = {};\n#endif\n",
            d.comment,
            n + 1,
            d.symbol,
            c_initializer(&d.guid)
        );
    }
    s += "\n/* ISO C forbids an empty translation unit. */\ntypedef int opccomn_guids_translation_unit;\n";
    s
}
