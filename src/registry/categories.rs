//! The OPC component categories (specification section 6.1) with their standard descriptions, exported
//! as data as `opc_cats.c` provides them.

use crate::com::{CATID, GUID};

/// `CATID_OPCDAServer10` {63D5F430-CFE4-11d1-B2C8-0060083BA1FB}: OPC Data Access 1.0 servers.
#[no_mangle]
pub static CATID_OPCDAServer10: CATID = GUID::from_u128(0x63D5F430_CFE4_11D1_B2C8_0060083BA1FB);
/// `CATID_OPCDAServer20` {63D5F432-CFE4-11d1-B2C8-0060083BA1FB}: OPC Data Access 2.0 servers.
#[no_mangle]
pub static CATID_OPCDAServer20: CATID = GUID::from_u128(0x63D5F432_CFE4_11D1_B2C8_0060083BA1FB);
/// `CATID_OPCDAServer30` {CC603642-66D7-48f1-B69A-B625E73652D7}: OPC Data Access 3.0 servers.
#[no_mangle]
pub static CATID_OPCDAServer30: CATID = GUID::from_u128(0xCC603642_66D7_48F1_B69A_B625E73652D7);
/// `CATID_XMLDAServer10` {3098EDA4-A006-48b2-A27F-247453959408}: OPC XML Data Access 1.0 servers.
#[no_mangle]
pub static CATID_XMLDAServer10: CATID = GUID::from_u128(0x3098EDA4_A006_48B2_A27F_247453959408);
/// `CATID_OPCAEServer10` {58E13251-AC87-11d1-84D5-00608CB8A7E9}: OPC Alarms & Events 1.0 servers.
#[no_mangle]
pub static CATID_OPCAEServer10: CATID = GUID::from_u128(0x58E13251_AC87_11D1_84D5_00608CB8A7E9);
/// `CATID_OPCHDAServer10` {7DE5B060-E089-11d2-A5E6-000086339399}: OPC Historical Data Access 1.0 servers.
#[no_mangle]
pub static CATID_OPCHDAServer10: CATID = GUID::from_u128(0x7DE5B060_E089_11D2_A5E6_000086339399);
/// `CATID_OPCBatchServer10` {A8080DA0-E23E-11D2-AFA7-00C04F539421}: OPC Batch 1.0 servers.
#[no_mangle]
pub static CATID_OPCBatchServer10: CATID = GUID::from_u128(0xA8080DA0_E23E_11D2_AFA7_00C04F539421);
/// `CATID_OPCBatchServer20` {843DE67B-B0C9-11d4-A0B7-000102A980B1}: OPC Batch 2.0 servers.
#[no_mangle]
pub static CATID_OPCBatchServer20: CATID = GUID::from_u128(0x843DE67B_B0C9_11D4_A0B7_000102A980B1);
/// `CATID_OPCDXServer10` {A0C85BB8-4161-4fd6-8655-BB584601C9E0}: OPC Data eXchange 1.0 servers.
#[no_mangle]
pub static CATID_OPCDXServer10: CATID = GUID::from_u128(0xA0C85BB8_4161_4FD6_8655_BB584601C9E0);
/// `CATID_OPCCMDServer10` {2D869D5C-3B05-41fb-851A-642FB2B801A0}: OPC Command Execution 1.0 servers.
#[no_mangle]
pub static CATID_OPCCMDServer10: CATID = GUID::from_u128(0x2D869D5C_3B05_41FB_851A_642FB2B801A0);

/// The Data Access 1.0 category, whose servers may also be registered the old way (an `OPC` key under
/// their ProgID).
pub(crate) const DA10: GUID = GUID::from_u128(0x63D5F430_CFE4_11D1_B2C8_0060083BA1FB);

/// The standard English (0x409) descriptions of the OPC categories, as the OPC Foundation's headers
/// define them.
const STANDARD: [(u128, &str); 10] = [
    (
        0x63D5F430_CFE4_11D1_B2C8_0060083BA1FB,
        "OPC Data Access Servers Version 1.0",
    ),
    (
        0x63D5F432_CFE4_11D1_B2C8_0060083BA1FB,
        "OPC Data Access Servers Version 2.0",
    ),
    (
        0xCC603642_66D7_48F1_B69A_B625E73652D7,
        "OPC Data Access Servers Version 3.0",
    ),
    (
        0x3098EDA4_A006_48B2_A27F_247453959408,
        "OPC XML Data Access Servers Version 1.0",
    ),
    (
        0x58E13251_AC87_11D1_84D5_00608CB8A7E9,
        "OPC Alarm & Event Server Version 1.0",
    ),
    (
        0x7DE5B060_E089_11D2_A5E6_000086339399,
        "OPC History Data Access Servers Version 1.0",
    ),
    (0xA8080DA0_E23E_11D2_AFA7_00C04F539421, "OPC Batch Server Version 1.0"),
    (0x843DE67B_B0C9_11D4_A0B7_000102A980B1, "OPC Batch Server Version 2.0"),
    (
        0xA0C85BB8_4161_4FD6_8655_BB584601C9E0,
        "OPC Data Exchange Servers Version 1.0",
    ),
    (
        0x2D869D5C_3B05_41FB_851A_642FB2B801A0,
        "OPC Command Execution Servers Version 1.0",
    ),
];

/// The standard description of an OPC category, `None` for other categories.
pub fn standard_description(catid: &GUID) -> Option<&'static str> {
    STANDARD
        .iter()
        .find(|(id, _)| GUID::from_u128(*id) == *catid)
        .map(|(_, text)| *text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exported_catids_have_their_standard_texts() {
        assert_eq!(
            standard_description(&CATID_OPCDAServer10),
            Some("OPC Data Access Servers Version 1.0")
        );
        assert_eq!(
            standard_description(&CATID_OPCAEServer10),
            Some("OPC Alarm & Event Server Version 1.0")
        );
        assert_eq!(
            standard_description(&CATID_OPCCMDServer10),
            Some("OPC Command Execution Servers Version 1.0")
        );
        assert_eq!(standard_description(&GUID::default()), None);
        assert_eq!(DA10, CATID_OPCDAServer10);
    }
}
