//! The OPC component categories (specification section 6.1) with their standard descriptions. Values and
//! descriptions are written once, in idl/opcguids.txt (see `com::guids`, generated from it).

use crate::com::GUID;

pub use crate::com::guids::{
    CATID_OPCAEServer10, CATID_OPCBatchServer10, CATID_OPCBatchServer20, CATID_OPCCMDServer10, CATID_OPCDAServer10,
    CATID_OPCDAServer20, CATID_OPCDAServer30, CATID_OPCDXServer10, CATID_OPCHDAServer10, CATID_XMLDAServer10,
};

/// The Data Access 1.0 category, whose servers may also be registered the old way (an `OPC` key under
/// their ProgID).
pub(crate) const DA10: GUID = CATID_OPCDAServer10;

/// The standard description of an OPC category, `None` for other categories.
pub fn standard_description(catid: &GUID) -> Option<&'static str> {
    crate::com::guids::CATEGORY_DESCRIPTIONS
        .iter()
        .find(|(id, _)| id == catid)
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
