//! The hand-written checks of the five OPC Common interfaces that the generated layouts replaced, kept
//! word for word as the reference the interpreter is compared with: on every message the tests and
//! the `wire` fuzz target make, `check_request` and `check_reply` of the generated layouts and these
//! give the same answer (so the generated checks are the same checks). Not part of the library.
#![allow(dead_code)]

use crate::com::guids::{IID_IEnumGUID, IID_IOPCEnumGUID};
use crate::com::{GUID, HRESULT};

use super::{
    Dialect as IpLayout, Interface as Iface, BAD_STUB_DATA, INVALID_BOUND, MAX_ELEMENTS, PROCNUM_OUT_OF_RANGE,
};

/// `NDR_LOCAL_DATA_REPRESENTATION`: little-endian integers, ASCII, IEEE floating point.
const LOCAL_DATA_REPRESENTATION: u32 = 0x10;

/// `OBJREF.signature`, "MEOW" (MS-DCOM 2.2.18).
const OBJREF_SIGNATURE: u32 = 0x574F_454D;
/// `OBJREF_EXTENDED.Signature1` (MS-DCOM 2.2.18.7).
const OBJREF_EXTENDED_SIGNATURE: u32 = 0x4E53_5956;
/// `OBJREF.flags`: the four flavours (MS-DCOM 2.2.18).
const OBJREF_STANDARD: u32 = 1;
const OBJREF_HANDLER: u32 = 2;
const OBJREF_CUSTOM: u32 = 4;
const OBJREF_EXTENDED: u32 = 8;
/// `STDOBJREF`: flags, cPublicRefs, OXID, OID, IPID (MS-DCOM 2.2.18.1).
const STDOBJREF_SIZE: usize = 40;

/// A GUID as NDR and an OBJREF carry it: `Data1` to `Data3` little-endian, then `Data4`.
fn guid_bytes(g: &GUID) -> [u8; 16] {
    let mut b = [0; 16];
    b[..4].copy_from_slice(&g.Data1.to_le_bytes());
    b[4..6].copy_from_slice(&g.Data2.to_le_bytes());
    b[6..8].copy_from_slice(&g.Data3.to_le_bytes());
    b[8..].copy_from_slice(&g.Data4);
    b
}

/// Reads NDR 2.0 little-endian data, never past the end.
struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
}

type Check = Result<(), HRESULT>;

impl<'a> Reader<'a> {
    fn new(buf: &'a [u8]) -> Self {
        Reader { buf, pos: 0 }
    }

    fn skip(&mut self, n: usize) -> Check {
        let end = self.pos.checked_add(n).ok_or(BAD_STUB_DATA)?;
        if end > self.buf.len() {
            return Err(BAD_STUB_DATA);
        }
        self.pos = end;
        Ok(())
    }

    fn align4(&mut self) -> Check {
        let pad = (4 - self.pos % 4) % 4;
        self.skip(pad)
    }

    fn u32(&mut self) -> Result<u32, HRESULT> {
        self.align4()?;
        let at = self.pos;
        self.skip(4)?;
        let b = &self.buf[at..at + 4];
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// `n` GUIDs (NDR aligns a GUID to 4).
    fn guids(&mut self, n: u32) -> Check {
        self.align4()?;
        self.skip((n as usize).checked_mul(16).ok_or(BAD_STUB_DATA)?)
    }

    /// A count chosen by the caller: at most [`MAX_ELEMENTS`].
    fn bounded(n: u32) -> Result<u32, HRESULT> {
        if n > MAX_ELEMENTS {
            Err(INVALID_BOUND)
        } else {
            Ok(n)
        }
    }

    /// `[in, size_is(count)] GUID array[]`: its conformance, equal to `count`, and the GUIDs.
    fn guid_array(&mut self, count: u32) -> Check {
        let count = Self::bounded(count)?;
        if self.u32()? != count {
            return Err(BAD_STUB_DATA);
        }
        self.guids(count)
    }

    /// A `[string]` wide string (conformant and varying): maximum count = actual count >= 1, offset 0,
    /// every unit present, the last one NUL. MIDL and widl marshal a string so; anything else would let
    /// the maximum size an allocation the bytes do not back.
    fn string(&mut self) -> Check {
        let max = self.u32()?;
        let offset = self.u32()?;
        let actual = self.u32()?;
        if max != actual || offset != 0 || actual == 0 {
            return Err(BAD_STUB_DATA);
        }
        let bytes = (actual as usize).checked_mul(2).ok_or(BAD_STUB_DATA)?;
        let at = self.pos;
        self.skip(bytes)?;
        if self.buf[at + bytes - 2..at + bytes] != [0, 0] {
            return Err(BAD_STUB_DATA);
        }
        Ok(())
    }

    /// `[out, string] LPWSTR *`: a unique pointer, then the string when not NULL.
    fn unique_string(&mut self) -> Check {
        if self.u32()? != 0 {
            self.string()?;
        }
        Ok(())
    }

    /// The next 32 bits, not consumed; None at the end.
    fn peek_u32(&self) -> Option<u32> {
        let mut ahead = Reader {
            buf: self.buf,
            pos: self.pos,
        };
        ahead.u32().ok()
    }

    /// `n` bytes.
    fn take(&mut self, n: usize) -> Result<&'a [u8], HRESULT> {
        let at = self.pos;
        self.skip(n)?;
        Ok(&self.buf[at..at + n])
    }

    /// A little-endian 16-bit value, unaligned (inside an OBJREF, which is bytes to NDR).
    fn u16_unaligned(&mut self) -> Result<u16, HRESULT> {
        let b = self.take(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    /// A little-endian 32-bit value, unaligned.
    fn u32_unaligned(&mut self) -> Result<u32, HRESULT> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// `[out] I **` whose OBJREF must carry `iid`, in the layout of the message, which must be `reader`'s.
    ///
    /// NULL is a zero in both layouts. Otherwise the layout is the message's: Wine's when the OBJREF
    /// signature follows the first 32 bits, NDR's when not. No message is well-formed in both: NDR's
    /// would need a conformance equal to the signature (0x574F454D), so `ulCntData` equal to it too,
    /// which read as Wine's OBJREF is its flavour, none of the four.
    fn interface_pointer(&mut self, reader: IpLayout, iid: &GUID) -> Check {
        let first = self.u32()?;
        if first == 0 {
            return Ok(());
        }
        let (layout, count) = if self.peek_u32() == Some(OBJREF_SIGNATURE) {
            (IpLayout::Wine, first)
        } else {
            // The referent ID (any value but 0), then MInterfacePointer: conformance, ulCntData.
            let max = self.u32()?;
            if self.u32()? != max {
                return Err(BAD_STUB_DATA);
            }
            (IpLayout::Ndr, max)
        };
        objref(self.take(count as usize)?, iid)?;
        if layout != reader {
            return Err(BAD_STUB_DATA);
        }
        Ok(())
    }

    /// A DUALSTRINGARRAY (MS-DCOM 2.2.19.1): `wNumEntries` 16-bit units after the header, the security
    /// bindings' offset among them. (Wine writes an empty one: 0 and 0.)
    fn dual_string_array(&mut self) -> Check {
        let entries = self.u16_unaligned()?;
        let security_offset = self.u16_unaligned()?;
        if security_offset > entries {
            return Err(BAD_STUB_DATA);
        }
        self.skip(usize::from(entries) * 2)
    }

    /// The HRESULT every reply ends with.
    fn hresult(&mut self) -> Check {
        self.u32().map(|_| ())
    }
}

/// The OBJREF of an interface pointer, exactly `bytes` (MS-DCOM 2.2.18): the signature, one of the
/// four flavours, the IID the method declares (what MS-DCOM 3.2.4.1.2 has a client refuse; Wine's
/// rpcrt4 unmarshals with IID_NULL, so would hand the caller an object of whatever interface the
/// OBJREF names), and the flavour's fixed part and string bindings inside `bytes`. The rest (OXID,
/// IPID, bindings, a custom marshaller's data) is COM's to read, within `bytes`.
fn objref(bytes: &[u8], iid: &GUID) -> Check {
    let mut r = Reader::new(bytes);
    if r.u32_unaligned()? != OBJREF_SIGNATURE {
        return Err(BAD_STUB_DATA);
    }
    let flags = r.u32_unaligned()?;
    if r.take(16)? != guid_bytes(iid) {
        return Err(BAD_STUB_DATA);
    }
    match flags {
        OBJREF_STANDARD => {
            r.skip(STDOBJREF_SIZE)?;
            r.dual_string_array()
        }
        // The handler's CLSID between them.
        OBJREF_HANDLER => {
            r.skip(STDOBJREF_SIZE + 16)?;
            r.dual_string_array()
        }
        // The marshaller's CLSID, cbExtension, reserved; its data is the rest.
        OBJREF_CUSTOM => r.skip(16 + 4 + 4),
        OBJREF_EXTENDED => {
            r.skip(STDOBJREF_SIZE)?;
            if r.u32_unaligned()? != OBJREF_EXTENDED_SIGNATURE {
                return Err(BAD_STUB_DATA);
            }
            r.dual_string_array()
        }
        _ => Err(BAD_STUB_DATA),
    }
}

fn local_data_representation(drep: u32) -> Check {
    if drep & 0xFFFF == LOCAL_DATA_REPRESENTATION {
        Ok(())
    } else {
        Err(BAD_STUB_DATA)
    }
}

fn method_exists(interface: Iface, method: u32) -> Check {
    let methods = match interface {
        Iface::IOPCShutdown => 4,
        Iface::IOPCCommon => 8,
        Iface::IOPCServerList | Iface::IOPCServerList2 => 6,
        Iface::IOPCEnumGUID => 7,
        // The hand-written checks knew only the OPC Common interfaces.
        _ => 3,
    };
    if (3..methods).contains(&method) {
        Ok(())
    } else {
        Err(PROCNUM_OUT_OF_RANGE)
    }
}

/// Checks a request for `method` (its vtable index) of `interface` before the stub unmarshals it.
pub fn check_request(interface: Iface, method: u32, buf: &[u8], drep: u32) -> Check {
    method_exists(interface, method)?;
    local_data_representation(drep)?;
    let mut r = Reader::new(buf);
    match (interface, method) {
        // ShutdownRequest(szReason), SetClientName(szName)
        (Iface::IOPCShutdown, 3) | (Iface::IOPCCommon, 7) => r.string(),
        // SetLocaleID(dwLcid), GetErrorString(dwError, ...), Skip(celt)
        (Iface::IOPCCommon, 3 | 6) | (Iface::IOPCEnumGUID, 4) => r.u32().map(|_| ()),
        // GetLocaleID, QueryAvailableLocaleIDs, Reset, Clone: nothing in.
        (Iface::IOPCCommon, 4 | 5) | (Iface::IOPCEnumGUID, 5 | 6) => Ok(()),
        // EnumClassesOfCategories(cImplemented, rgcatidImpl, cRequired, rgcatidReq, ...)
        (Iface::IOPCServerList | Iface::IOPCServerList2, 3) => {
            let implemented = r.u32()?;
            r.guid_array(implemented)?;
            let required = r.u32()?;
            r.guid_array(required)
        }
        // GetClassDetails(clsid, ...)
        (Iface::IOPCServerList | Iface::IOPCServerList2, 4) => r.guids(1),
        // CLSIDFromProgID(szProgId, ...)
        (Iface::IOPCServerList | Iface::IOPCServerList2, 5) => r.string(),
        // Next(celt, ...): the stub allocates celt GUIDs before the server runs.
        (Iface::IOPCEnumGUID, 3) => Reader::bounded(r.u32()?).map(|_| ()),
        _ => Err(PROCNUM_OUT_OF_RANGE),
    }
}

/// What a reply check needs to know of the request the proxy sent: `IOPCEnumGUID::Next`'s `celt`
/// (the size of the caller's buffer); 0 for every other method. `request` is the proxy's own request.
pub fn reply_context(interface: Iface, method: u32, request: &[u8]) -> u32 {
    match (interface, method) {
        (Iface::IOPCEnumGUID, 3) => Reader::new(request).u32().unwrap_or(0),
        _ => 0,
    }
}

/// Checks a reply to `method` of `interface` before the proxy unmarshals it into the caller's memory.
/// `context` is [`reply_context`] of the request; `reader` the layout of interface pointers the
/// process's runtime reads (the one thing a message cannot say).
pub fn check_reply(interface: Iface, method: u32, context: u32, buf: &[u8], drep: u32, reader: IpLayout) -> Check {
    method_exists(interface, method)?;
    local_data_representation(drep)?;
    let mut r = Reader::new(buf);
    match (interface, method) {
        // HRESULT only.
        (Iface::IOPCShutdown, 3) | (Iface::IOPCCommon, 3 | 7) | (Iface::IOPCEnumGUID, 4 | 5) => {}
        // GetLocaleID(*pdwLcid)
        (Iface::IOPCCommon, 4) => {
            r.u32()?;
        }
        // QueryAvailableLocaleIDs(*pdwCount, *pdwLcid): the count sizes the array the caller walks.
        (Iface::IOPCCommon, 5) => {
            let count = r.u32()?;
            if r.u32()? != 0 {
                let count = Reader::bounded(count)?;
                if r.u32()? != count {
                    return Err(BAD_STUB_DATA);
                }
                r.skip(count as usize * 4)?;
            } else if count != 0 {
                // A count with no array would have the caller walk NULL.
                return Err(BAD_STUB_DATA);
            }
        }
        // GetErrorString(*ppString)
        (Iface::IOPCCommon, 6) => r.unique_string()?,
        // EnumClassesOfCategories(*ppenumClsid): IEnumGUID in IOPCServerList, IOPCEnumGUID in IOPCServerList2.
        (Iface::IOPCServerList, 3) => r.interface_pointer(reader, &IID_IEnumGUID)?,
        (Iface::IOPCServerList2, 3) => r.interface_pointer(reader, &IID_IOPCEnumGUID)?,
        // Clone(*ppenum)
        (Iface::IOPCEnumGUID, 6) => r.interface_pointer(reader, &IID_IOPCEnumGUID)?,
        // GetClassDetails: ProgID, user type (and, in IOPCServerList2, the version-independent ProgID).
        (Iface::IOPCServerList, 4) => {
            r.unique_string()?;
            r.unique_string()?;
        }
        (Iface::IOPCServerList2, 4) => {
            r.unique_string()?;
            r.unique_string()?;
            r.unique_string()?;
        }
        // CLSIDFromProgID(*clsid)
        (Iface::IOPCServerList | Iface::IOPCServerList2, 5) => r.guids(1)?,
        // Next(rgelt[celt], *pceltFetched): conformance = the caller's celt, offset 0, actual count =
        // *pceltFetched <= celt, and the GUIDs all present. Nothing more may land in the caller's buffer.
        (Iface::IOPCEnumGUID, 3) => {
            let celt = context;
            let max = r.u32()?;
            let offset = r.u32()?;
            let actual = r.u32()?;
            if max != celt || offset != 0 || actual > max {
                return Err(BAD_STUB_DATA);
            }
            r.guids(actual)?;
            if r.u32()? != actual {
                return Err(BAD_STUB_DATA);
            }
        }
        _ => return Err(PROCNUM_OUT_OF_RANGE),
    }
    r.hresult()
}
