//! The SDDL codec of the AppID permissions (registry::sddl): any text and any bytes give a result or
//! E_INVALIDARG, never a panic; what parses round-trips through the binary self-relative form and
//! back to SDDL.
//!
//! Input: as UTF-8 text, parsed as SDDL; the same bytes, read as a binary security descriptor.
#![no_main]

use libfuzzer_sys::fuzz_target;
use opccomn::com::E_INVALIDARG;
use opccomn::registry::sddl::SecurityDescriptor;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        match SecurityDescriptor::parse(text) {
            Ok(sd) => {
                let bytes = sd.to_bytes();
                assert_eq!(SecurityDescriptor::from_bytes(&bytes).as_ref(), Ok(&sd));
                assert_eq!(SecurityDescriptor::parse(&sd.to_sddl()).as_ref(), Ok(&sd));
            }
            Err(hr) => assert_eq!(hr, E_INVALIDARG),
        }
    }
    match SecurityDescriptor::from_bytes(data) {
        Ok(sd) => {
            assert_eq!(SecurityDescriptor::from_bytes(&sd.to_bytes()).as_ref(), Ok(&sd));
            assert_eq!(SecurityDescriptor::parse(&sd.to_sddl()).as_ref(), Ok(&sd));
        }
        Err(hr) => assert_eq!(hr, E_INVALIDARG),
    }
});
