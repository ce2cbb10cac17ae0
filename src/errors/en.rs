//! English texts, exactly as published in the OPC Foundation's headers (typos included).

use super::OpcServerKind;

/// Data Access 1-3 and Complex Data (opcerror.h).
static DATA_ACCESS: &[(u32, &str)] = &[
    (0xC0040001, "The value of the handle is invalid."),
    (0xC0040004, "The server cannot convert the data between the specified format and/or requested data type and the canonical data type."),
    (0xC0040005, "The requested operation cannot be done on a public group."),
    (0xC0040006, "The item's access rights do not allow the operation."),
    (0xC0040007, "The item ID is not defined in the server address space or no longer exists in the server address space."),
    (0xC0040008, "The item ID does not conform to the server's syntax."),
    (0xC0040009, "The filter string was not valid."),
    (0xC004000A, "The item's access path is not known to the server."),
    (0xC004000B, "The value was out of range."),
    (0xC004000C, "Duplicate name not allowed."),
    (0x0004000D, "The server does not support the requested data rate but will use the closest available rate."),
    (0x0004000E, "A value passed to write was accepted but the output was clamped."),
    (0x0004000F, "The operation cannot be performed because the object is bering referenced."),
    (0xC0040010, "The server's configuration file is an invalid format."),
    (0xC0040011, "The requested object (e.g. a public group) was not found."),
    (0xC0040203, "The specified property ID is not valid for the item."),
    (0xC0040400, "The item deadband has not been set for this item."),
    (0xC0040401, "The item does not support deadband."),
    (0xC0040402, "The server does not support buffering of data items that are collected at a faster rate than the group update rate."),
    (0xC0040403, "The continuation point is not valid."),
    (0x00040404, "Not every detected change has been returned since the server's buffer reached its limit and had to purge out the oldest data."),
    (0xC0040405, "There is no sampling rate set for the specified item."),
    (0xC0040406, "The server does not support writing of quality and/or timestamp."),
    (0xC0040407, "The dictionary and/or type description for the item has changed."),
    (0xC0040408, "A data filter item with the specified name already exists."),
    (0xC0040409, "The data filter value does not conform to the server's syntax."),
    (0xC004040A, "An error occurred when the filter value was applied to the source data."),
    (0x0004040B, "The item value is empty because the data filter has excluded all fields."),
];

/// COM codes the OPC Common interfaces return (winerror.h texts).
static COM: &[(u32, &str)] = &[
    (0x80004001, "Not implemented"),
    (0x80004002, "No such interface supported"),
    (0x80004003, "Invalid pointer"),
    (0x80004005, "Unspecified error"),
    (0x8000FFFF, "Catastrophic failure"),
    (
        0x8007000E,
        "Not enough memory resources are available to complete this operation.",
    ),
    (0x80070057, "The parameter is incorrect."),
    (0x8002000C, "Unknown language."),
    (0x80040004, "There is no connection for this connection ID"),
    (
        0x80040110,
        "Class does not support aggregation (or class object is remote)",
    ),
    (0x80040111, "ClassFactory cannot supply requested class"),
    (0x80040154, "Class not registered"),
    (0x800401F3, "Invalid class string"),
    (0x80040200, "No connection for this connection ID"),
    (0x80040201, "Limit on the number of connections has been reached"),
    (0x80040202, "Cannot connect"),
];

fn find(table: &[(u32, &'static str)], code: u32) -> Option<&'static str> {
    table.iter().find(|(c, _)| *c == code).map(|(_, t)| *t)
}

/// The English text for `code` as the given kind of server means it.
pub fn text(code: u32, kind: OpcServerKind) -> Option<&'static str> {
    let _ = kind; // Alarms & Events and HDA tables are added with the full catalog
    find(DATA_ACCESS, code).or_else(|| find(COM, code))
}
