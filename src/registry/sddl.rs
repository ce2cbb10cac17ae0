//! Security descriptors for DCOM AppIDs: a subset of SDDL (Security Descriptor Definition Language)
//! converted to the binary self-relative `SECURITY_DESCRIPTOR` that `AccessPermission` and
//! `LaunchPermission` hold (REG_BINARY, as dcomcnfg writes them), and back.
//!
//! The conversion is the library's own, not Windows' `ConvertStringSecurityDescriptorToSecurityDescriptorW`,
//! because registration also runs off Windows (the in-memory registry, `.reg` export). The subset is
//! what COM permissions need:
//!
//! ```text
//! [O:sid][G:sid][D:[P][AR][AI](ace)...]          in this order, each at most once, no blanks
//! ace   = (A|D ; [OI][CI][NP][IO][ID][SA][FA] ; rights ; ; ; sid)
//! rights = 0x hex | decimal | two-letter codes (CC DC LC SW RP WP DT LO CR SD RC WD WO GA GX GW GR
//!          FA FR FW FX KA KR KW KX), OR-ed
//! sid   = a well-known alias (WD AU BA SY IU NS LS AN AC ...; see ALIASES) | S-1-authority-sub-...
//! ```
//!
//! COM's rights (COM_RIGHTS_EXECUTE 1, EXECUTE_LOCAL 2, EXECUTE_REMOTE 4, ACTIVATE_LOCAL 8,
//! ACTIVATE_REMOTE 16) share their bits with the directory-service letters, so Windows shows 0xB as
//! `CCDCSW` and 0x1F as `CCDCLCSWRP`; [`to_sddl`] writes rights the same way (a whole-mask name such as
//! `FA` first, else bit letters, else hex), and SIDs by their alias when they have one.
//!
//! Not in the subset (E_INVALIDARG): a SACL (`S:`), object and conditional ACEs, a NULL DACL
//! (`NO_ACCESS_CONTROL`), domain-relative aliases (DA, DU, ...: they need the machine's domain),
//! another order of the parts, SID authorities of 2^32 and more (`S-1-0x...`). Input is bounded (`MAX_SDDL_CHARS`, `MAX_ACES`), and every input,
//! text or binary, gives a result or E_INVALIDARG: nothing panics.
//!
//! The binary layout is the one Wine's ConvertStringSecurityDescriptorToSecurityDescriptorW produces
//! (header, owner, group, DACL, in this order; byte for byte, checked by a Windows-target test under
//! Wine). Windows may place the parts in another order (dcomcnfg puts the DACL first); a self-relative
//! descriptor locates each part by its offset, so the order does not change its meaning.

use crate::com::{E_INVALIDARG, HRESULT};

/// The longest SDDL text accepted, in characters.
pub(crate) const MAX_SDDL_CHARS: usize = 8192;
/// The most ACEs a DACL may have.
pub(crate) const MAX_ACES: usize = 256;
/// The most sub-authorities of a SID (Windows' SID_MAX_SUB_AUTHORITIES).
const MAX_SUB_AUTHORITIES: usize = 15;

/// `SE_DACL_PRESENT`.
const SE_DACL_PRESENT: u16 = 0x0004;
/// `SE_DACL_AUTO_INHERIT_REQ` (`AR`).
const SE_DACL_AUTO_INHERIT_REQ: u16 = 0x0100;
/// `SE_DACL_AUTO_INHERITED` (`AI`).
const SE_DACL_AUTO_INHERITED: u16 = 0x0400;
/// `SE_DACL_PROTECTED` (`P`).
const SE_DACL_PROTECTED: u16 = 0x1000;
/// `SE_SELF_RELATIVE`.
const SE_SELF_RELATIVE: u16 = 0x8000;
/// The DACL flags of the subset, with their letters in the order SDDL writes them.
const DACL_FLAGS: [(&str, u16); 3] = [
    ("P", SE_DACL_PROTECTED),
    ("AR", SE_DACL_AUTO_INHERIT_REQ),
    ("AI", SE_DACL_AUTO_INHERITED),
];
/// `ACL_REVISION`.
const ACL_REVISION: u8 = 2;
/// The size of `SECURITY_DESCRIPTOR_RELATIVE`.
const HEADER: usize = 20;

/// `ACCESS_ALLOWED_ACE_TYPE` (`A`) and `ACCESS_DENIED_ACE_TYPE` (`D`).
const ACE_TYPES: [(&str, u8); 2] = [("A", 0), ("D", 1)];
/// ACE flags, in the order SDDL writes them.
const ACE_FLAGS: [(&str, u8); 7] = [
    ("OI", 0x01),
    ("CI", 0x02),
    ("NP", 0x04),
    ("IO", 0x08),
    ("ID", 0x10),
    ("SA", 0x40),
    ("FA", 0x80),
];
/// Rights named as a whole mask (checked first when writing).
const MASK_NAMES: [(&str, u32); 8] = [
    ("FA", 0x001F_01FF),
    ("FR", 0x0012_0089),
    ("FW", 0x0012_0116),
    ("FX", 0x0012_00A0),
    ("KA", 0x000F_003F),
    ("KR", 0x0002_0019),
    ("KW", 0x0002_0006),
    ("KX", 0x0002_0019),
];
/// Rights named per bit.
const BIT_NAMES: [(&str, u32); 17] = [
    ("CC", 0x1),
    ("DC", 0x2),
    ("LC", 0x4),
    ("SW", 0x8),
    ("RP", 0x10),
    ("WP", 0x20),
    ("DT", 0x40),
    ("LO", 0x80),
    ("CR", 0x100),
    ("SD", 0x1_0000),
    ("RC", 0x2_0000),
    ("WD", 0x4_0000),
    ("WO", 0x8_0000),
    ("GA", 0x1000_0000),
    ("GX", 0x2000_0000),
    ("GW", 0x4000_0000),
    ("GR", 0x8000_0000),
];

/// The well-known SIDs with an SDDL alias that do not depend on a domain: (alias, authority,
/// sub-authorities).
pub(crate) const ALIASES: [(&str, u64, &[u32]); 32] = [
    ("WD", 1, &[0]),
    ("CO", 3, &[0]),
    ("CG", 3, &[1]),
    ("OW", 3, &[4]),
    ("NU", 5, &[2]),
    ("IU", 5, &[4]),
    ("SU", 5, &[6]),
    ("AN", 5, &[7]),
    ("ED", 5, &[9]),
    ("PS", 5, &[10]),
    ("AU", 5, &[11]),
    ("RC", 5, &[12]),
    ("SY", 5, &[18]),
    ("LS", 5, &[19]),
    ("NS", 5, &[20]),
    ("BA", 5, &[32, 544]),
    ("BU", 5, &[32, 545]),
    ("BG", 5, &[32, 546]),
    ("PU", 5, &[32, 547]),
    ("AO", 5, &[32, 548]),
    ("SO", 5, &[32, 549]),
    ("PO", 5, &[32, 550]),
    ("BO", 5, &[32, 551]),
    ("RE", 5, &[32, 552]),
    ("RU", 5, &[32, 554]),
    ("RD", 5, &[32, 555]),
    ("NO", 5, &[32, 556]),
    ("MU", 5, &[32, 558]),
    ("LU", 5, &[32, 559]),
    ("IS", 5, &[32, 568]),
    ("ER", 5, &[32, 573]),
    ("AC", 15, &[2, 1]),
];

/// A security identifier.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sid {
    /// The identifier authority (48 bits).
    pub authority: u64,
    /// The sub-authorities (at most 15).
    pub sub_authorities: Vec<u32>,
}

/// An access-allowed or access-denied ACE.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Ace {
    /// 0 allowed (`A`), 1 denied (`D`).
    pub kind: u8,
    /// The ACE flags (`OI`, `CI`, ...).
    pub flags: u8,
    /// The access mask (COM rights for AppID permissions).
    pub mask: u32,
    /// Whom the ACE is about.
    pub sid: Sid,
}

/// A security descriptor of the subset: owner, group, DACL.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SecurityDescriptor {
    /// The owner (`O:`).
    pub owner: Option<Sid>,
    /// The primary group (`G:`).
    pub group: Option<Sid>,
    /// The DACL's control flags (`SE_DACL_PROTECTED`, ...) and ACEs, when there is a DACL (`D:`).
    pub dacl: Option<(u16, Vec<Ace>)>,
}

type Res<T> = Result<T, HRESULT>;

impl Sid {
    fn parse(text: &str) -> Res<Sid> {
        if let Some(&(_, authority, subs)) = ALIASES.iter().find(|(alias, _, _)| *alias == text) {
            return Ok(Sid {
                authority,
                sub_authorities: subs.to_vec(),
            });
        }
        let rest = text.strip_prefix("S-1-").ok_or(E_INVALIDARG)?;
        let mut parts = rest.split('-');
        // Decimal, below 2^32 (the hex form of larger authorities is outside the subset).
        let authority = decimal(parts.next().ok_or(E_INVALIDARG)?, u32::MAX as u64)?;
        let mut sub_authorities = Vec::new();
        for part in parts {
            if sub_authorities.len() == MAX_SUB_AUTHORITIES {
                return Err(E_INVALIDARG);
            }
            sub_authorities.push(decimal(part, u32::MAX as u64)? as u32);
        }
        Ok(Sid {
            authority,
            sub_authorities,
        })
    }

    fn to_text(&self) -> String {
        if let Some((alias, _, _)) = ALIASES
            .iter()
            .find(|(_, a, s)| *a == self.authority && *s == self.sub_authorities.as_slice())
        {
            return alias.to_string();
        }
        let mut text = format!("S-1-{}", self.authority);
        for sub in &self.sub_authorities {
            text.push_str(&format!("-{sub}"));
        }
        text
    }

    fn len(&self) -> usize {
        8 + 4 * self.sub_authorities.len()
    }

    fn write(&self, out: &mut Vec<u8>) {
        out.push(1);
        out.push(self.sub_authorities.len() as u8);
        out.extend_from_slice(&self.authority.to_be_bytes()[2..]);
        for sub in &self.sub_authorities {
            out.extend_from_slice(&sub.to_le_bytes());
        }
    }

    /// Reads a SID at the start of `bytes`.
    fn read(bytes: &[u8]) -> Res<Sid> {
        let head = bytes.get(..8).ok_or(E_INVALIDARG)?;
        let count = head[1] as usize;
        // Authorities of 2^32 and more (written in hex in SDDL) are outside the subset.
        if head[0] != 1 || count > MAX_SUB_AUTHORITIES || head[2] != 0 || head[3] != 0 {
            return Err(E_INVALIDARG);
        }
        let mut authority = [0u8; 8];
        authority[2..].copy_from_slice(&head[2..8]);
        let subs = bytes.get(8..8 + 4 * count).ok_or(E_INVALIDARG)?;
        Ok(Sid {
            authority: u64::from_be_bytes(authority),
            sub_authorities: subs
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect(),
        })
    }
}

/// A decimal number of 1 to 20 digits, at most `max`, without sign or leading zeros.
fn decimal(text: &str, max: u64) -> Res<u64> {
    if text.is_empty()
        || text.len() > 20
        || !text.bytes().all(|b| b.is_ascii_digit())
        || (text.len() > 1 && text.starts_with('0'))
    {
        return Err(E_INVALIDARG);
    }
    text.parse::<u64>().ok().filter(|v| *v <= max).ok_or(E_INVALIDARG)
}

/// The rights of an ACE: `0x` and 1 to 8 hex digits, a decimal number, or two-letter codes.
fn parse_rights(text: &str) -> Res<u32> {
    if let Some(hex) = text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        if hex.is_empty() || hex.len() > 8 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(E_INVALIDARG);
        }
        return u32::from_str_radix(hex, 16).map_err(|_| E_INVALIDARG);
    }
    if text.bytes().next().is_some_and(|b| b.is_ascii_digit()) {
        return decimal(text, u32::MAX as u64).map(|v| v as u32);
    }
    if text.len() % 2 != 0 || !text.is_ascii() {
        return Err(E_INVALIDARG);
    }
    let mut mask = 0;
    for i in (0..text.len()).step_by(2) {
        let code = &text[i..i + 2];
        let bits = BIT_NAMES
            .iter()
            .chain(MASK_NAMES.iter())
            .find(|(name, _)| *name == code)
            .ok_or(E_INVALIDARG)?
            .1;
        mask |= bits;
    }
    Ok(mask)
}

fn rights_text(mask: u32) -> String {
    if mask == 0 {
        return String::new();
    }
    if let Some((name, _)) = MASK_NAMES.iter().find(|(_, m)| *m == mask) {
        return name.to_string();
    }
    let named: u32 = BIT_NAMES.iter().map(|(_, b)| b).fold(0, |a, b| a | b);
    if mask & !named != 0 {
        return format!("0x{mask:x}");
    }
    BIT_NAMES
        .iter()
        .filter(|(_, b)| mask & b != 0)
        .map(|(name, _)| *name)
        .collect()
}

/// Letters from `table` at the start of `text`, as many as follow each other (each at most once).
fn flags<T: Copy + core::ops::BitOr<Output = T> + PartialEq>(text: &mut &str, table: &[(&str, T)], zero: T) -> Res<T> {
    let mut value = zero;
    let mut seen = vec![false; table.len()];
    'next: loop {
        for (i, (name, bits)) in table.iter().enumerate() {
            if let Some(rest) = text.strip_prefix(name) {
                if seen[i] {
                    return Err(E_INVALIDARG);
                }
                seen[i] = true;
                value = value | *bits;
                *text = rest;
                continue 'next;
            }
        }
        return Ok(value);
    }
}

fn parse_ace(text: &str) -> Res<Ace> {
    let fields: Vec<&str> = text.split(';').collect();
    let [kind, ace_flags, rights, object, inherited_object, sid] = fields.as_slice() else {
        return Err(E_INVALIDARG);
    };
    let kind = ACE_TYPES.iter().find(|(n, _)| n == kind).ok_or(E_INVALIDARG)?.1;
    let mut rest = *ace_flags;
    let ace_flags = flags(&mut rest, &ACE_FLAGS, 0u8)?;
    if !rest.is_empty() || !object.is_empty() || !inherited_object.is_empty() {
        return Err(E_INVALIDARG);
    }
    Ok(Ace {
        kind,
        flags: ace_flags,
        mask: parse_rights(rights)?,
        sid: Sid::parse(sid)?,
    })
}

/// Takes a SID's text off the front of `text`: `S-1-...` up to the first character that cannot be
/// part of it, else two characters (an alias).
fn take_sid<'a>(text: &mut &'a str) -> Res<&'a str> {
    let end = match text.strip_prefix("S-") {
        Some(rest) => {
            2 + rest
                .find(|c: char| !(c.is_ascii_digit() || c == '-'))
                .unwrap_or(rest.len())
        }
        None => 2,
    };
    let sid = text.get(..end).ok_or(E_INVALIDARG)?;
    *text = &text[end..];
    Ok(sid)
}

impl SecurityDescriptor {
    /// Parses SDDL text of the subset (see the module documentation).
    pub fn parse(sddl: &str) -> Res<SecurityDescriptor> {
        if sddl.is_empty() || sddl.chars().count() > MAX_SDDL_CHARS {
            return Err(E_INVALIDARG);
        }
        let mut text = sddl;
        let mut sd = SecurityDescriptor::default();
        if let Some(rest) = text.strip_prefix("O:") {
            text = rest;
            sd.owner = Some(Sid::parse(take_sid(&mut text)?)?);
        }
        if let Some(rest) = text.strip_prefix("G:") {
            text = rest;
            sd.group = Some(Sid::parse(take_sid(&mut text)?)?);
        }
        if let Some(rest) = text.strip_prefix("D:") {
            text = rest;
            let control = flags(&mut text, &DACL_FLAGS, 0u16)?;
            let mut aces = Vec::new();
            while let Some(rest) = text.strip_prefix('(') {
                let end = rest.find(')').ok_or(E_INVALIDARG)?;
                if aces.len() == MAX_ACES {
                    return Err(E_INVALIDARG);
                }
                aces.push(parse_ace(&rest[..end])?);
                text = &rest[end + 1..];
            }
            sd.dacl = Some((control, aces));
        }
        if !text.is_empty() {
            return Err(E_INVALIDARG);
        }
        Ok(sd)
    }

    /// The SDDL text of this descriptor, as Windows writes it (aliases and right letters where they
    /// exist).
    pub fn to_sddl(&self) -> String {
        let mut text = String::new();
        if let Some(owner) = &self.owner {
            text.push_str(&format!("O:{}", owner.to_text()));
        }
        if let Some(group) = &self.group {
            text.push_str(&format!("G:{}", group.to_text()));
        }
        if let Some((control, aces)) = &self.dacl {
            text.push_str("D:");
            for (name, bit) in DACL_FLAGS {
                if control & bit != 0 {
                    text.push_str(name);
                }
            }
            for ace in aces {
                let kind = ACE_TYPES.iter().find(|(_, k)| *k == ace.kind).map_or("", |(n, _)| n);
                let ace_flags: String = ACE_FLAGS
                    .iter()
                    .filter(|(_, b)| ace.flags & b != 0)
                    .map(|(n, _)| *n)
                    .collect();
                text.push_str(&format!(
                    "({kind};{ace_flags};{};;;{})",
                    rights_text(ace.mask),
                    ace.sid.to_text()
                ));
            }
        }
        text
    }

    /// The binary self-relative form (`SECURITY_DESCRIPTOR_RELATIVE`): header, owner, group, DACL.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = vec![0u8; HEADER];
        out[0] = 1; // SECURITY_DESCRIPTOR_REVISION
        let mut control = SE_SELF_RELATIVE;
        let mut offsets = [0u32; 4]; // owner, group, SACL, DACL
        for (i, sid) in [(0, &self.owner), (1, &self.group)] {
            if let Some(sid) = sid {
                offsets[i] = out.len() as u32;
                sid.write(&mut out);
            }
        }
        if let Some((flags, aces)) = &self.dacl {
            control |= SE_DACL_PRESENT | flags;
            offsets[3] = out.len() as u32;
            // Bounded by MAX_ACES entries of at most 8 + 68 bytes: fits the ACL's 16-bit size.
            let size = 8 + aces.iter().map(|a| 8 + a.sid.len()).sum::<usize>();
            out.extend_from_slice(&[ACL_REVISION, 0]);
            out.extend_from_slice(&(size as u16).to_le_bytes());
            out.extend_from_slice(&(aces.len() as u16).to_le_bytes());
            out.extend_from_slice(&[0, 0]);
            for ace in aces {
                out.extend_from_slice(&[ace.kind, ace.flags]);
                out.extend_from_slice(&((8 + ace.sid.len()) as u16).to_le_bytes());
                out.extend_from_slice(&ace.mask.to_le_bytes());
                ace.sid.write(&mut out);
            }
        }
        out[2..4].copy_from_slice(&control.to_le_bytes());
        for (i, offset) in offsets.iter().enumerate() {
            out[4 + 4 * i..8 + 4 * i].copy_from_slice(&offset.to_le_bytes());
        }
        out
    }

    /// Reads a binary self-relative descriptor of the subset (any layout of its parts; no SACL, no
    /// NULL DACL, only access-allowed and access-denied ACEs; not empty).
    pub fn from_bytes(bytes: &[u8]) -> Res<SecurityDescriptor> {
        let header = bytes.get(..HEADER).ok_or(E_INVALIDARG)?;
        let word = |i: usize| u32::from_le_bytes([header[i], header[i + 1], header[i + 2], header[i + 3]]) as usize;
        let control = u16::from_le_bytes([header[2], header[3]]);
        let dacl_flags = SE_DACL_PROTECTED | SE_DACL_AUTO_INHERITED | SE_DACL_AUTO_INHERIT_REQ;
        if header[0] != 1
            || control & SE_SELF_RELATIVE == 0
            || control & !(SE_SELF_RELATIVE | SE_DACL_PRESENT | dacl_flags) != 0
            || word(12) != 0
        {
            return Err(E_INVALIDARG);
        }
        let sid_at = |offset: usize| -> Res<Option<Sid>> {
            match offset {
                0 => Ok(None),
                o if o < HEADER => Err(E_INVALIDARG),
                o => Sid::read(bytes.get(o..).ok_or(E_INVALIDARG)?).map(Some),
            }
        };
        let mut sd = SecurityDescriptor {
            owner: sid_at(word(4))?,
            group: sid_at(word(8))?,
            dacl: None,
        };
        let dacl = word(16);
        if control & SE_DACL_PRESENT == 0 {
            // An empty descriptor (no owner, group or DACL) has no SDDL of the subset: refused, as
            // empty text is.
            let empty = sd.owner.is_none() && sd.group.is_none();
            return if dacl == 0 && control & dacl_flags == 0 && !empty {
                Ok(sd)
            } else {
                Err(E_INVALIDARG)
            };
        }
        if dacl < HEADER {
            return Err(E_INVALIDARG);
        }
        let acl = bytes
            .get(dacl..dacl.checked_add(8).ok_or(E_INVALIDARG)?)
            .ok_or(E_INVALIDARG)?;
        let size = u16::from_le_bytes([acl[2], acl[3]]) as usize;
        let count = u16::from_le_bytes([acl[4], acl[5]]) as usize;
        if acl[0] != ACL_REVISION || count > MAX_ACES || size < 8 {
            return Err(E_INVALIDARG);
        }
        let end = dacl.checked_add(size).ok_or(E_INVALIDARG)?;
        let body = bytes.get(dacl + 8..end).ok_or(E_INVALIDARG)?;
        let mut at = 0;
        let mut aces = Vec::with_capacity(count);
        for _ in 0..count {
            let head = body.get(at..at + 8).ok_or(E_INVALIDARG)?;
            let ace_size = u16::from_le_bytes([head[2], head[3]]) as usize;
            if !ACE_TYPES.iter().any(|(_, k)| *k == head[0])
                || ACE_FLAGS.iter().fold(head[1], |f, (_, b)| f & !b) != 0
                || ace_size < 16
            {
                return Err(E_INVALIDARG);
            }
            let ace = body.get(at..at + ace_size).ok_or(E_INVALIDARG)?;
            let sid = Sid::read(&ace[8..])?;
            if 8 + sid.len() > ace_size {
                return Err(E_INVALIDARG);
            }
            aces.push(Ace {
                kind: head[0],
                flags: head[1],
                mask: u32::from_le_bytes([head[4], head[5], head[6], head[7]]),
                sid,
            });
            at += ace_size;
        }
        sd.dacl = Some((control & dacl_flags, aces));
        Ok(sd)
    }
}

/// The binary self-relative security descriptor of SDDL text (E_INVALIDARG outside the subset).
pub fn sddl_to_bytes(sddl: &str) -> Res<Vec<u8>> {
    SecurityDescriptor::parse(sddl).map(|sd| sd.to_bytes())
}

/// The SDDL text of a binary self-relative security descriptor (E_INVALIDARG outside the subset).
pub fn bytes_to_sddl(bytes: &[u8]) -> Res<String> {
    SecurityDescriptor::from_bytes(bytes).map(|sd| sd.to_sddl())
}

#[cfg(test)]
mod tests;
