/* The OPC error texts as the OPC Foundation publishes them, transcribed from the specifications'
   headers (opcerror.h, opcae_er.h, OpcHda_Error.h, OpcErrSec.h, OpcBatchError.h, OpcDxError.h,
   OpcCmdError.h), typos included. test_error_strings.c checks the library against this list; it is
   kept apart from the library's catalog on purpose, so that a wrong catalog text cannot make its own
   expectation. Strings are UTF-8 ("\xE2\x80\x99" is the right single quotation mark of the DX texts).

   kind: the OpcServerKind to ask with (the code's own specification where codes collide). */
#ifndef OPCCOMN_PUBLISHED_ERROR_TEXTS_H
#define OPCCOMN_PUBLISHED_ERROR_TEXTS_H

#include <stdint.h>

struct published_text {
    uint32_t code;
    uint32_t kind;
    const char *symbol;
    const char *text;
};

#define K_DA 0u
#define K_AE 1u
#define K_HDA 2u
#define K_BATCH 3u
#define K_DX 4u
#define K_CMD 5u

static const struct published_text PUBLISHED_TEXTS[] = {
    /* opcerror.h */
    {0xC0040001u, K_DA, "OPC_E_INVALIDHANDLE", "The value of the handle is invalid."},
    {0xC0040004u, K_DA, "OPC_E_BADTYPE", "The server cannot convert the data between the specified format and/or requested data type and the canonical data type."},
    {0xC0040005u, K_DA, "OPC_E_PUBLIC", "The requested operation cannot be done on a public group."},
    {0xC0040006u, K_DA, "OPC_E_BADRIGHTS", "The item's access rights do not allow the operation."},
    {0xC0040007u, K_DA, "OPC_E_UNKNOWNITEMID", "The item ID is not defined in the server address space or no longer exists in the server address space."},
    {0xC0040008u, K_DA, "OPC_E_INVALIDITEMID", "The item ID does not conform to the server's syntax."},
    {0xC0040009u, K_DA, "OPC_E_INVALIDFILTER", "The filter string was not valid."},
    {0xC004000Au, K_DA, "OPC_E_UNKNOWNPATH", "The item's access path is not known to the server."},
    {0xC004000Bu, K_DA, "OPC_E_RANGE", "The value was out of range."},
    {0xC004000Cu, K_DA, "OPC_E_DUPLICATENAME", "Duplicate name not allowed."},
    {0x0004000Du, K_DA, "OPC_S_UNSUPPORTEDRATE", "The server does not support the requested data rate but will use the closest available rate."},
    {0x0004000Eu, K_DA, "OPC_S_CLAMP", "A value passed to write was accepted but the output was clamped."},
    {0x0004000Fu, K_DA, "OPC_S_INUSE", "The operation cannot be performed because the object is bering referenced."},
    {0xC0040010u, K_DA, "OPC_E_INVALIDCONFIGFILE", "The server's configuration file is an invalid format."},
    {0xC0040011u, K_DA, "OPC_E_NOTFOUND", "The requested object (e.g. a public group) was not found."},
    {0xC0040203u, K_DA, "OPC_E_INVALID_PID", "The specified property ID is not valid for the item."},
    {0xC0040400u, K_DA, "OPC_E_DEADBANDNOTSET", "The item deadband has not been set for this item."},
    {0xC0040401u, K_DA, "OPC_E_DEADBANDNOTSUPPORTED", "The item does not support deadband."},
    {0xC0040402u, K_DA, "OPC_E_NOBUFFERING", "The server does not support buffering of data items that are collected at a faster rate than the group update rate."},
    {0xC0040403u, K_DA, "OPC_E_INVALIDCONTINUATIONPOINT", "The continuation point is not valid."},
    {0x00040404u, K_DA, "OPC_S_DATAQUEUEOVERFLOW", "Not every detected change has been returned since the server's buffer reached its limit and had to purge out the oldest data."},
    {0xC0040405u, K_DA, "OPC_E_RATENOTSET", "There is no sampling rate set for the specified item."},
    {0xC0040406u, K_DA, "OPC_E_NOTSUPPORTED", "The server does not support writing of quality and/or timestamp."},
    {0xC0040407u, K_DA, "OPCCPX_E_TYPE_CHANGED", "The dictionary and/or type description for the item has changed."},
    {0xC0040408u, K_DA, "OPCCPX_E_FILTER_DUPLICATE", "A data filter item with the specified name already exists."},
    {0xC0040409u, K_DA, "OPCCPX_E_FILTER_INVALID", "The data filter value does not conform to the server's syntax."},
    {0xC004040Au, K_DA, "OPCCPX_E_FILTER_ERROR", "An error occurred when the filter value was applied to the source data."},
    {0x0004040Bu, K_DA, "OPCCPX_S_FILTER_NO_DATA", "The item value is empty because the data filter has excluded all fields."},
    /* opcae_er.h */
    {0x00040200u, K_AE, "OPC_S_ALREADYACKED", "The condition has already been acknowleged."},
    {0x00040201u, K_AE, "OPC_S_INVALIDBUFFERTIME", "The buffer time parameter was invalid."},
    {0x00040202u, K_AE, "OPC_S_INVALIDMAXSIZE", "The max size parameter was invalid."},
    {0x00040203u, K_AE, "OPC_S_INVALIDKEEPALIVETIME", "The KeepAliveTime parameter was invalid."},
    {0xC0040203u, K_AE, "OPC_E_INVALIDBRANCHNAME", "The string was not recognized as an area name."},
    {0xC0040204u, K_AE, "OPC_E_INVALIDTIME", "The time does not match the latest active time."},
    {0xC0040205u, K_AE, "OPC_E_BUSY", "A refresh is currently in progress."},
    {0xC0040206u, K_AE, "OPC_E_NOINFO", "Information is not available."},
    /* OpcHda_Error.h */
    {0xC0041001u, K_HDA, "OPC_E_MAXEXCEEDED", "The maximum number of values requested exceeds the server's limit."},
    {0x40041002u, K_HDA, "OPC_S_NODATA", "There is no data within the specified parameters."},
    {0x40041003u, K_HDA, "OPC_S_MOREDATA", "There is more data satisfying the query than was returned."},
    {0xC0041004u, K_HDA, "OPC_E_INVALIDAGGREGATE", "The aggregate requested is not valid."},
    {0x40041005u, K_HDA, "OPC_S_CURRENTVALUE", "The server only returns current values for the requested item attributes."},
    {0x40041006u, K_HDA, "OPC_S_EXTRADATA", "Additional data satisfying the query was found."},
    {0x80041007u, K_HDA, "OPC_W_NOFILTER", "The server does not support this filter."},
    {0xC0041008u, K_HDA, "OPC_E_UNKNOWNATTRID", "The server does not support this attribute."},
    {0xC0041009u, K_HDA, "OPC_E_NOT_AVAIL", "The requested aggregate is not available for the specified item."},
    {0xC004100Au, K_HDA, "OPC_E_INVALIDDATATYPE", "The supplied value for the attribute is not a correct data type."},
    {0xC004100Bu, K_HDA, "OPC_E_DATAEXISTS", "Unable to insert - data already present."},
    {0xC004100Cu, K_HDA, "OPC_E_INVALIDATTRID", "The supplied attribute ID is not valid."},
    {0xC004100Du, K_HDA, "OPC_E_NODATAEXISTS", "The server has no value for the specified time and item ID."},
    {0x4004100Eu, K_HDA, "OPC_S_INSERTED", "The requested insert occurred."},
    {0x4004100Fu, K_HDA, "OPC_S_REPLACED", "The requested replace occurred."},
    /* OpcErrSec.h (OPC_S_LOW_AUTHN_LEVEL: C0040303 in the official header, 00040303 in others) */
    {0xC0040301u, K_DA, "OPC_E_PRIVATE_ACTIVE", "A session using private OPC credentials is already active."},
    {0xC0040302u, K_DA, "OPC_E_LOW_IMPERS_LEVEL", "Server requires higher impersonation level to access secured data."},
    {0xC0040303u, K_DA, "OPC_S_LOW_AUTHN_LEVEL", "Server expected higher level of package privacy."},
    {0x00040303u, K_DA, "OPC_S_LOW_AUTHN_LEVEL", "Server expected higher level of package privacy."},
    /* OpcBatchError.h */
    {0xC0040300u, K_BATCH, "OPCB_E_NOT_MEANINGFUL", "The data is not meaningful at the present time."},
    /* OpcDxError.h */
    {0xC0040700u, K_DX, "OPCDX_E_PERSISTING", "Could not process request because the configuration is currently being persisted."},
    {0xC0040701u, K_DX, "OPCDX_E_NOITEMLIST", "No item list was passed in the request."},
    {0xC0040702u, K_DX, "OPCDX_E_SERVER_STATE", "The operation failed because the server is in the wrong state."},
    {0xC0040703u, K_DX, "OPCDX_E_VERSION_MISMATCH", "The current object version does not match the specified version."},
    {0xC0040704u, K_DX, "OPCDX_E_UNKNOWN_ITEM_PATH", "The specified item path no longer exists in the DX server's address space."},
    {0xC0040705u, K_DX, "OPCDX_E_UNKNOWN_ITEM_NAME", "The specified item name no longer exists in the DX server's address space."},
    {0xC0040706u, K_DX, "OPCDX_E_INVALID_ITEM_PATH", "The specified item path does not conform to the DX server syntax."},
    {0xC0040707u, K_DX, "OPCDX_E_INVALID_ITEM_NAME", "The specified item name does not conform to the DX server syntax."},
    {0xC0040708u, K_DX, "OPCDX_E_INVALID_NAME", "The source server name or connection name does not conform to the server syntax."},
    {0xC0040709u, K_DX, "OPCDX_E_DUPLICATE_NAME", "The connection name or source server name is already in use."},
    {0xC004070Au, K_DX, "OPCDX_E_INVALID_BROWSE_PATH", "The browse path does not conform to the DX server syntax or it cannot be modified."},
    {0xC004070Bu, K_DX, "OPCDX_E_INVALID_SERVER_URL", "The syntax of the source server URL is not correct."},
    {0xC004070Cu, K_DX, "OPCDX_E_INVALID_SERVER_TYPE", "The source server type is not recognized."},
    {0xC004070Du, K_DX, "OPCDX_E_UNSUPPORTED_SERVER_TYPE", "The source server does not support the specified server type."},
    {0xC004070Eu, K_DX, "OPCDX_E_CONNECTIONS_EXIST", "The source server cannot be deleted because connections exist."},
    {0xC004070Fu, K_DX, "OPCDX_E_TOO_MANY_CONNECTIONS", "The total number of connections would exceed the maximum supported by the DX server."},
    {0xC0040710u, K_DX, "OPCDX_E_OVERRIDE_BADTYPE", "The override value is not valid and overridden flag is set to true."},
    {0xC0040711u, K_DX, "OPCDX_E_OVERRIDE_RANGE", "The override value is outside of the target item\xE2\x80\x99s range and overridden flag is set to true."},
    {0xC0040712u, K_DX, "OPCDX_E_SUBSTITUTE_BADTYPE", "The substitute  value is not valid and the enable substitute value flag is set to true."},
    {0xC0040713u, K_DX, "OPCDX_E_SUBSTITUTE_RANGE", "The substitute value is outside of the target item\xE2\x80\x99s range the enable substitute value flag is set to true."},
    {0xC0040714u, K_DX, "OPCDX_E_INVALID_TARGET_ITEM", "The target item does not conform to the DX server syntax or the item cannot be used as a target."},
    {0xC0040715u, K_DX, "OPCDX_E_UNKNOWN_TARGET_ITEM", "The target item no longer exists in the DX server\xE2\x80\x99s address space."},
    {0xC0040716u, K_DX, "OPCDX_E_TARGET_ALREADY_CONNECTED", "The target item is already connected or may not be changed in the method."},
    {0xC0040717u, K_DX, "OPCDX_E_UNKNOWN_SERVER_NAME", "The specified source server does not exist."},
    {0xC0040718u, K_DX, "OPCDX_E_UNKNOWN_SOURCE_ITEM", "The source item is no longer in the source server\xE2\x80\x99s address space."},
    {0xC0040719u, K_DX, "OPCDX_E_INVALID_SOURCE_ITEM", "The source item does not confirm to the source server\xE2\x80\x99s syntax."},
    {0xC004071Au, K_DX, "OPCDX_E_INVALID_QUEUE_SIZE", "The update queue size is not valid."},
    {0xC004071Bu, K_DX, "OPCDX_E_INVALID_DEADBAND", "The deadband is not valid."},
    {0xC004071Cu, K_DX, "OPCDX_E_INVALID_CONFIG_FILE", "The DX server configuration file is not acessable."},
    {0xC004071Du, K_DX, "OPCDX_E_PERSIST_FAILED", "Could not save the DX server configuration."},
    {0xC004071Eu, K_DX, "OPCDX_E_TARGET_FAULT", "Target is online, but cannot service any request due to being in a fault state."},
    {0xC004071Fu, K_DX, "OPCDX_E_TARGET_NO_ACCESS", "Target is not online and may not be accessed."},
    {0xC0040720u, K_DX, "OPCDX_E_SOURCE_SERVER_FAULT", "Source server is online, but cannot service any request due to being in a fault state."},
    {0xC0040721u, K_DX, "OPCDX_E_SOURCE_SERVER_NO_ACCESS", "Source server is not online and may not be accessed."},
    {0xC0040722u, K_DX, "OPCDX_E_SUBSCRIPTION_FAULT", "Source server is connected, however it could not create a subscription for the connection."},
    {0xC0040723u, K_DX, "OPCDX_E_SOURCE_ITEM_BADRIGHTS", "The source items access rights ddo not permit the operation."},
    {0xC0040724u, K_DX, "OPCDX_E_SOURCE_ITEM_BAD_QUALITY", "The source item value could be used because it has bad quality."},
    {0xC0040725u, K_DX, "OPCDX_E_SOURCE_ITEM_BADTYPE", "The source item cannot be converted to the target\xE2\x80\x99s data type. This error reported by the source server."},
    {0xC0040726u, K_DX, "OPCDX_E_SOURCE_ITEM_RANGE", "The source item is out of the  range for the requested type. This error reported by the source server."},
    {0xC0040727u, K_DX, "OPCDX_E_SOURCE_SERVER_NOT_CONNECTED", "The source server is not connected."},
    {0xC0040728u, K_DX, "OPCDX_E_SOURCE_SERVER_TIMEOUT", "The source server was disconnected because to failed to respond to pings."},
    {0xC0040729u, K_DX, "OPCDX_E_TARGET_ITEM_DISCONNECTED", "The target item is disconnected."},
    {0xC004072Au, K_DX, "OPCDX_E_TARGET_NO_WRITES_ATTEMPTED", "The DX server has not attempted to write to the target."},
    {0xC004072Bu, K_DX, "OPCDX_E_TARGET_ITEM_BADTYPE", "The target item cannot be converted to the target\xE2\x80\x99s data type."},
    {0xC004072Cu, K_DX, "OPCDX_E_TARGET_ITEM_RANGE", "The target item is outside the value range for the item."},
    {0x00040780u, K_DX, "OPCDX_S_TARGET_SUBSTITUTED", "The substitute value was written to the target."},
    {0x00040781u, K_DX, "OPCDX_S_TARGET_OVERRIDEN", "The override value was written to the target."},
    {0x00040782u, K_DX, "OPCDX_S_CLAMP", "Value written was accepted but the output was clamped."},
    /* OpcCmdError.h */
    {0xC0040900u, K_CMD, "OPCCMD_E_INVALIDBRANCH", "The Target ID specified in the request is not a valid branch."},
    {0xC0040901u, K_CMD, "OPCCMD_E_INVALIDNAMESPACE", "The specified namespace is not a valid namespace for this server."},
    {0xC0040902u, K_CMD, "OPCCMD_E_INVALIDCOMMANDNAME", "The specified command name is not valid for this server."},
    {0xC0040903u, K_CMD, "OPCCMD_E_BUSY", "The server is currently not able to process this command."},
    {0xC0040904u, K_CMD, "OPCCMD_E_EVENTFILTER_NOTSUPPORTED", "The server does not support filtering of events."},
    {0xC0040905u, K_CMD, "OPCCMD_E_NO_SUCH_COMMAND", "A command with the specified UUID is neither executing nor completed (and still stored in the cache)."},
    {0xC0040906u, K_CMD, "OPCCMD_E_ALREADY_CONNECTED", "A client is already connected for the specified Invoke UUID."},
    {0xC0040907u, K_CMD, "OPCCMD_E_NOT_CONNECTED", "No Callback ID is currently connected for the specified command."},
    {0xC0040908u, K_CMD, "OPCCMD_E_CONTROL_NOTSUPPORTED", "The server does not support the specified control for this command."},
    {0xC0040909u, K_CMD, "OPCCMD_E_INVALID_CONTROL", "The specified control is not possible in the current state of execution."},
};

#define PUBLISHED_TEXT_COUNT (sizeof(PUBLISHED_TEXTS) / sizeof(PUBLISHED_TEXTS[0]))

#endif
