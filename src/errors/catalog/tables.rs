//! The facts the error catalog is built from, each stated once: the specifications (with the server
//! kind that selects each), the languages, and the hash of the code index.
//!
//! The build script compiles this same file (`buildscript/catalog.rs` includes it), so the tables it
//! generates from `catalog/<language>.txt` and the library that reads them cannot disagree. It
//! depends on nothing else in the crate for that reason.

/// The kind of OPC server asking for a text; it decides which specification's text a colliding code
/// gets (other codes get their text whatever the kind).
#[repr(u32)]
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub enum OpcServerKind {
    /// Data Access (and Complex Data): the default.
    #[default]
    DataAccess = 0,
    /// Alarms & Events.
    AlarmsEvents = 1,
    /// Historical Data Access.
    HistoricalData = 2,
    /// Batch.
    Batch = 3,
    /// Data eXchange.
    DataExchange = 4,
    /// Command Execution.
    CommandExecution = 5,
}

/// One specification: its name in the SPEC column of the catalog files and the server kind whose
/// texts it holds (`None`: no kind of server selects it, its codes collide with no other's).
pub(crate) struct SpecInfo {
    pub spec: Spec,
    #[allow(dead_code)] // read by the build script
    pub name: &'static str,
    pub kind: Option<OpcServerKind>,
}

/// Declares [`Spec`] and [`SPECS`] from one list.
macro_rules! specifications {
    ($($(#[$doc:meta])* $variant:ident $name:literal $($kind:ident)?;)*) => {
        /// The specification that defines a code (the SPEC column of the catalog files).
        #[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Debug)]
        pub(crate) enum Spec {
            $($(#[$doc])* $variant,)*
        }

        /// Every specification, in the order in which colliding codes are preferred when the kind of
        /// server asking has no text of its own.
        pub(crate) const SPECS: &[SpecInfo] = &[
            $(SpecInfo { spec: Spec::$variant, name: $name, kind: specifications!(@kind $($kind)?) },)*
        ];
    };
    (@kind) => { None };
    (@kind $kind:ident) => { Some(OpcServerKind::$kind) };
}

specifications! {
    DataAccess "DA" DataAccess;
    AlarmsEvents "AE" AlarmsEvents;
    HistoricalData "HDA" HistoricalData;
    Security "SEC";
    Batch "BAT" Batch;
    DataExchange "DX" DataExchange;
    CommandExecution "CMD" CommandExecution;
    /// COM codes of the OPC Common interfaces that the system has no (or a misleading) text for.
    Connection "COM";
    /// COM, RPC and Win32 codes; on Windows the system's own text is preferred.
    System "SYS";
}

impl OpcServerKind {
    /// The kind for a raw value from C; `None` for values this version does not know.
    pub fn from_raw(v: u32) -> Option<OpcServerKind> {
        SPECS.iter().filter_map(|s| s.kind).find(|k| *k as u32 == v)
    }

    /// The specification whose texts this kind of server means.
    pub(crate) fn spec(self) -> Spec {
        // Every kind has its line in SPECS (a unit test checks); Data Access is the default anyway.
        SPECS
            .iter()
            .find(|s| s.kind == Some(self))
            .map_or(Spec::DataAccess, |s| s.spec)
    }
}

/// One language of the catalog.
pub(crate) struct CatalogLanguage {
    /// `catalog/<file>.txt`.
    #[allow(dead_code)] // read by the build script
    pub file: &'static str,
    /// The locale the DLL's message table files the texts under; its primary language picks them.
    pub lcid: u32,
    /// The language's name in the message compiler's LanguageNames.
    #[allow(dead_code)] // read by the build script
    pub windmc: &'static str,
}

/// The languages the catalog ships. English comes first: it is complete, and every other language falls
/// back to it text by text. Adding a language is a line here and its text file.
pub(crate) const LANGUAGES: &[CatalogLanguage] = &[
    CatalogLanguage {
        file: "en",
        lcid: 0x0409,
        windmc: "English",
    },
    CatalogLanguage {
        file: "de",
        lcid: 0x0407,
        windmc: "German",
    },
];

/// The primary language ID (`PRIMARYLANGID`) of a locale.
pub(crate) const fn primary_language(lcid: u32) -> u16 {
    (lcid & 0x3FF) as u16
}

/// Slots of the code index: a power of two, well above the number of codes.
pub(crate) const INDEX_BITS: u32 = 10;

/// The slot of the code index where the search for `code` starts (open addressing, linear probing).
pub(crate) const fn slot_of(code: u32) -> usize {
    (code.wrapping_mul(0x9E37_79B1) >> (32 - INDEX_BITS)) as usize
}
