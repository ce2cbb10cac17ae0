//! The access list of `OpcSecurityOptions::access_sddl` as CoInitializeSecurity wants it: SDDL
//! converted by ConvertStringSecurityDescriptorToSecurityDescriptorW (a self-relative descriptor),
//! checked (an owner, a group, no SACL), then made absolute with MakeAbsoluteSD.

use core::ffi::c_void;
use core::ptr;

use windows_sys::Win32::Foundation::{GetLastError, LocalFree};
use windows_sys::Win32::Security::Authorization::{
    ConvertStringSecurityDescriptorToSecurityDescriptorW, SDDL_REVISION_1,
};
use windows_sys::Win32::Security::{
    GetSecurityDescriptorGroup, GetSecurityDescriptorOwner, GetSecurityDescriptorSacl, MakeAbsoluteSD, ACL,
    PSECURITY_DESCRIPTOR, PSID,
};

use crate::com::ffi::{Fail, FfiResult};
use crate::com::{E_INVALIDARG, HRESULT};

/// The last Win32 error as an HRESULT (`HRESULT_FROM_WIN32`); E_INVALIDARG when there is none.
fn last_error() -> HRESULT {
    // SAFETY: no preconditions.
    let e = unsafe { GetLastError() };
    if e == 0 {
        E_INVALIDARG
    } else {
        ((e & 0xFFFF) | 0x8007_0000) as HRESULT
    }
}

/// A self-relative descriptor from LocalAlloc, freed on drop.
struct SelfRelative(PSECURITY_DESCRIPTOR);

impl Drop for SelfRelative {
    fn drop(&mut self) {
        // SAFETY: allocated by ConvertStringSecurityDescriptorToSecurityDescriptorW with LocalAlloc.
        unsafe { LocalFree(self.0) };
    }
}

/// An absolute security descriptor and the buffers it points into (8-byte aligned, as the
/// descriptor's pointers, ACLs and SIDs need).
pub(super) struct AbsoluteDescriptor {
    descriptor: Vec<u64>,
    dacl: Vec<u64>,
    sacl: Vec<u64>,
    owner: Vec<u64>,
    group: Vec<u64>,
}

/// A zeroed buffer of at least `bytes` bytes.
fn buffer(bytes: u32) -> Vec<u64> {
    vec![0; (bytes as usize).div_ceil(8).max(1)]
}

impl AbsoluteDescriptor {
    /// Converts `sddl` (UTF-16 without the NUL). E_INVALIDARG (or the conversion's error) for text
    /// Windows does not accept, a descriptor without owner or group, or one with a SACL.
    pub(super) fn from_sddl(sddl: &[u16]) -> FfiResult<AbsoluteDescriptor> {
        let text: Vec<u16> = sddl.iter().copied().chain([0]).collect();
        let mut relative: PSECURITY_DESCRIPTOR = ptr::null_mut();
        // SAFETY: `text` is NUL-terminated; `relative` is writable.
        let ok = unsafe {
            ConvertStringSecurityDescriptorToSecurityDescriptorW(
                text.as_ptr(),
                SDDL_REVISION_1,
                &mut relative,
                ptr::null_mut(),
            )
        };
        if ok == 0 || relative.is_null() {
            return Err(Fail::Code(last_error()));
        }
        let relative = SelfRelative(relative);
        check_parts(relative.0)?;
        let (mut sd_size, mut dacl_size, mut sacl_size, mut owner_size, mut group_size) =
            (0u32, 0u32, 0u32, 0u32, 0u32);
        // SAFETY: a valid self-relative descriptor; the sizes are writable; with every size 0 the
        // call only reports the sizes it needs (and fails with ERROR_INSUFFICIENT_BUFFER).
        unsafe {
            MakeAbsoluteSD(
                relative.0,
                ptr::null_mut(),
                &mut sd_size,
                ptr::null_mut(),
                &mut dacl_size,
                ptr::null_mut(),
                &mut sacl_size,
                ptr::null_mut(),
                &mut owner_size,
                ptr::null_mut(),
                &mut group_size,
            )
        };
        if sd_size == 0 {
            return Err(Fail::Code(last_error()));
        }
        let mut d = AbsoluteDescriptor {
            descriptor: buffer(sd_size),
            dacl: buffer(dacl_size),
            sacl: buffer(sacl_size),
            owner: buffer(owner_size),
            group: buffer(group_size),
        };
        // SAFETY: every buffer has at least the size MakeAbsoluteSD asked for, and 8-byte alignment.
        let ok = unsafe {
            MakeAbsoluteSD(
                relative.0,
                d.descriptor.as_mut_ptr().cast(),
                &mut sd_size,
                d.dacl.as_mut_ptr().cast::<ACL>(),
                &mut dacl_size,
                d.sacl.as_mut_ptr().cast::<ACL>(),
                &mut sacl_size,
                d.owner.as_mut_ptr().cast(),
                &mut owner_size,
                d.group.as_mut_ptr().cast(),
                &mut group_size,
            )
        };
        if ok == 0 {
            return Err(Fail::Code(last_error()));
        }
        Ok(d)
    }

    /// The descriptor, for CoInitializeSecurity.
    pub(super) fn as_ptr(&self) -> *const c_void {
        self.descriptor.as_ptr().cast()
    }
}

/// What CoInitializeSecurity requires of a descriptor: an owner, a group, and no SACL.
fn check_parts(sd: PSECURITY_DESCRIPTOR) -> FfiResult<()> {
    let (mut owner, mut group): (PSID, PSID) = (ptr::null_mut(), ptr::null_mut());
    let (mut defaulted, mut sacl_present) = (0, 0);
    let mut sacl: *mut ACL = ptr::null_mut();
    // SAFETY: `sd` is a valid descriptor; every out-pointer is writable.
    let ok = unsafe {
        GetSecurityDescriptorOwner(sd, &mut owner, &mut defaulted) != 0
            && GetSecurityDescriptorGroup(sd, &mut group, &mut defaulted) != 0
            && GetSecurityDescriptorSacl(sd, &mut sacl_present, &mut sacl, &mut defaulted) != 0
    };
    if !ok || owner.is_null() || group.is_null() || sacl_present != 0 {
        return Err(E_INVALIDARG.into());
    }
    Ok(())
}
