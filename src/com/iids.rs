//! Interface and class identifiers under the names the library's code uses. The values are written
//! once, in the IDL (`idl/opccomn.idl`, `idl/combase.idl`, `idl/internal.idl`) and `idl/opcguids.txt`;
//! `guids.rs` and `interfaces.rs` are generated from them by tools/gen-header, with the exported data
//! symbols.

pub use super::guids::{
    CLSID_OPCServerList, IID_IConnectionPoint as IID_ICONNECTIONPOINT,
    IID_IConnectionPointContainer as IID_ICONNECTIONPOINTCONTAINER,
    IID_IEnumConnectionPoints as IID_IENUMCONNECTIONPOINTS, IID_IEnumConnections as IID_IENUMCONNECTIONS,
    IID_IEnumGUID as IID_IENUMGUID, IID_IOPCCommon, IID_IOPCEnumGUID, IID_IOPCServerList, IID_IOPCServerList2,
    IID_IOPCShutdown, IID_IUnknown as IID_IUNKNOWN,
};

/// `IID_IClassFactory` (idl/internal.idl).
pub const IID_ICLASSFACTORY: super::GUID = super::interfaces::IClassFactory::IID;
