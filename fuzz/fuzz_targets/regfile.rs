//! `.reg` import (OpcRegistryApply) into the in-memory registry: any text, valid UTF-16 or not, is applied
//! (S_OK) or refused with E_INVALIDARG, and a refused text changes nothing (the whole text is checked
//! before the first write). What was applied survives the round trip: exporting the registry and
//! applying that export to an empty registry gives the same export.
//!
//! Input: UTF-8 text, or (when it is not UTF-8) UTF-16LE units; cut at the first NUL.
#![no_main]

use core::ptr;

use libfuzzer_sys::fuzz_target;
use opccomn::com::alloc::OpcTaskMemFree;
use opccomn::com::{E_INVALIDARG, S_OK};
use opccomn::registry::regfile::{OpcRegistryApply, OpcRegistryExport};
use opccomn::registry::{OpcRegistry, OpcRegistryCreateMemory, OpcRegistryRelease};

fn units(data: &[u8]) -> Vec<u16> {
    let mut u: Vec<u16> = match std::str::from_utf8(data) {
        Ok(s) => s.encode_utf16().collect(),
        Err(_) => data.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect(),
    };
    u.truncate(u.iter().position(|&x| x == 0).unwrap_or(u.len()));
    u.push(0);
    u
}

/// A fresh in-memory registry, released on drop.
struct Memory(*mut OpcRegistry);

impl Memory {
    fn new() -> Memory {
        let mut reg = ptr::null_mut();
        // SAFETY: writable out-parameter.
        assert_eq!(unsafe { OpcRegistryCreateMemory(&mut reg) }, S_OK);
        Memory(reg)
    }

    fn apply(&self, text: &[u16]) -> i32 {
        // SAFETY: a live handle and a NUL-terminated text.
        unsafe { OpcRegistryApply(self.0, text.as_ptr()) }.get()
    }

    /// The whole registry as `.reg` text, NUL included.
    fn export(&self) -> Vec<u16> {
        let mut text = ptr::null_mut();
        // SAFETY: a live handle, NULL key (everything), writable out-parameter.
        assert_eq!(unsafe { OpcRegistryExport(self.0, ptr::null(), &mut text) }, S_OK);
        // SAFETY: a NUL-terminated string the library allocated; copied, then freed once.
        unsafe {
            let len = (0..).take_while(|&i| *text.add(i) != 0).count();
            let copy = core::slice::from_raw_parts(text, len + 1).to_vec();
            OpcTaskMemFree(text.cast());
            copy
        }
    }
}

impl Drop for Memory {
    fn drop(&mut self) {
        // SAFETY: released once.
        unsafe { OpcRegistryRelease(self.0) };
    }
}

fuzz_target!(|data: &[u8]| {
    let text = units(data);
    let reg = Memory::new();
    let empty = reg.export();
    match reg.apply(&text) {
        S_OK => {
            let exported = reg.export();
            let copy = Memory::new();
            assert_eq!(copy.apply(&exported), S_OK, "the export of an applied text applies");
            assert_eq!(
                String::from_utf16_lossy(&copy.export()),
                String::from_utf16_lossy(&exported),
                "export, apply, export"
            );
        }
        E_INVALIDARG => assert_eq!(reg.export(), empty, "a refused text changed the registry"),
        hr => panic!("OpcRegistryApply returned {hr:#x}"),
    }
});
