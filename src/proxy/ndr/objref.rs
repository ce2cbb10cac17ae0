//! Interface pointers: `MInterfacePointer` (MS-DCOM 2.2.14) and the OBJREF inside it (MS-DCOM 2.2.18).
//!
//! Two runtimes lay an interface pointer out differently ([`Dialect`]): NDR's, as MS-DCOM defines
//! `PMInterfacePointer` and Windows' rpcrt4 writes and reads it (a unique pointer's referent ID, then
//! the conformant structure: its conformance, `ulCntData` equal to it, and that many bytes of
//! OBJREF), or Wine's (`dlls/rpcrt4/ndr_ole.c`: a byte count, then the OBJREF). The message says which
//! it is in: a NULL pointer is a zero in both; otherwise the OBJREF's signature `MEOW` follows the
//! first 32 bits in Wine's layout and the first 96 in NDR's, and no message is well-formed in both
//! (NDR's would need a conformance equal to the signature, 0x574F454D, so `ulCntData` equal to it
//! too, which read as Wine's OBJREF is its flavour, none of the four). Either way the count must lie
//! inside the message and the OBJREF inside the count, with the signature, one of the four flavours,
//! the IID the method declares (what MS-DCOM 3.2.4.1.2 has a client refuse; Wine's rpcrt4 unmarshals
//! with IID_NULL, so would hand the caller an object of whatever interface the OBJREF names) and its
//! flavour's fixed part and string bindings inside the count. What a message cannot say is which
//! runtime will read it: that is the process's, and a pointer in the other runtime's layout is
//! refused, as that runtime would misread it.

use super::layout::Iid;
use super::{Check, Dialect, Walk, BAD_STUB_DATA};

/// `OBJREF.signature`, "MEOW" (MS-DCOM 2.2.18).
pub(crate) const OBJREF_SIGNATURE: u32 = 0x574F_454D;
/// `OBJREF_EXTENDED.Signature1` (MS-DCOM 2.2.18.7).
pub(crate) const OBJREF_EXTENDED_SIGNATURE: u32 = 0x4E53_5956;
/// `OBJREF.flags`: the four flavours (MS-DCOM 2.2.18).
pub(crate) const OBJREF_STANDARD: u32 = 1;
pub(crate) const OBJREF_HANDLER: u32 = 2;
pub(crate) const OBJREF_CUSTOM: u32 = 4;
pub(crate) const OBJREF_EXTENDED: u32 = 8;
/// `STDOBJREF`: flags, cPublicRefs, OXID, OID, IPID (MS-DCOM 2.2.18.1).
const STDOBJREF_SIZE: usize = 40;

/// Reads bytes that NDR carries as an opaque block (an OBJREF), unaligned, never past its end.
struct Bytes<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Bytes<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], crate::com::HRESULT> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&e| e <= self.buf.len())
            .ok_or(BAD_STUB_DATA)?;
        let b = &self.buf[self.pos..end];
        self.pos = end;
        Ok(b)
    }

    fn skip(&mut self, n: usize) -> Check {
        self.take(n).map(|_| ())
    }

    fn u16(&mut self) -> Result<u16, crate::com::HRESULT> {
        let b = self.take(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    fn u32(&mut self) -> Result<u32, crate::com::HRESULT> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A DUALSTRINGARRAY (MS-DCOM 2.2.19.1): `wNumEntries` 16-bit units after the header, the
    /// security bindings' offset among them. (Wine writes an empty one: 0 and 0.)
    fn dual_string_array(&mut self) -> Check {
        let entries = self.u16()?;
        let security_offset = self.u16()?;
        if security_offset > entries {
            return Err(BAD_STUB_DATA);
        }
        self.skip(usize::from(entries) * 2)
    }
}

/// The OBJREF of an interface pointer, exactly `bytes` (MS-DCOM 2.2.18): the signature, one of the
/// four flavours, the IID `iid` (as NDR writes a GUID), and the flavour's fixed part and string
/// bindings inside `bytes`. The rest (OXID, IPID, bindings, a custom marshaller's data) is COM's to
/// read, within `bytes`.
pub(crate) fn objref(bytes: &[u8], iid: &[u8; 16]) -> Check {
    let mut r = Bytes { buf: bytes, pos: 0 };
    if r.u32()? != OBJREF_SIGNATURE {
        return Err(BAD_STUB_DATA);
    }
    let flags = r.u32()?;
    if r.take(16)? != iid {
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
            if r.u32()? != OBJREF_EXTENDED_SIGNATURE {
                return Err(BAD_STUB_DATA);
            }
            r.dual_string_array()
        }
        _ => Err(BAD_STUB_DATA),
    }
}

impl Walk<'_> {
    /// An interface pointer whose OBJREF must carry `iid`, in the layout of the message, which must
    /// be the reading runtime's.
    pub(super) fn interface_pointer(&self, at: &mut usize, iid: Iid) -> Check {
        let iid = match iid {
            Iid::Fixed(bytes) => bytes,
            Iid::Slot(s) => {
                let mut bytes = [0u8; 16];
                for (i, chunk) in bytes.chunks_exact_mut(4).enumerate() {
                    let slot = usize::from(s) + i;
                    if slot >= super::MAX_SLOTS || self.known & (1 << slot) == 0 {
                        return Err(BAD_STUB_DATA);
                    }
                    chunk.copy_from_slice(&self.slots[slot].to_le_bytes());
                }
                bytes
            }
        };
        let first = self.u32(at)?;
        if first == 0 {
            return Ok(());
        }
        let mut ahead = *at;
        let signature_next = self.u32(&mut ahead).ok() == Some(OBJREF_SIGNATURE);
        let (layout, count) = if signature_next {
            (Dialect::Wine, first)
        } else {
            // The referent ID (any value but 0), then MInterfacePointer: conformance, ulCntData.
            let max = self.u32(at)?;
            if self.u32(at)? != max {
                return Err(BAD_STUB_DATA);
            }
            (Dialect::Ndr, max)
        };
        objref(self.bytes(at, count as usize)?, &iid)?;
        if layout != self.dialect {
            return Err(BAD_STUB_DATA);
        }
        Ok(())
    }
}
