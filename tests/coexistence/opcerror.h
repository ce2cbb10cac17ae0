/* Stand-in for the OPC Foundation's opcerror.h: the same macros, spelled as the Foundation spells them
   (only those this test needs). Not a copy of the Foundation's file. */
#ifndef __OPCERROR_H
#define __OPCERROR_H

#define OPC_E_INVALIDHANDLE ((HRESULT)0xC0040001L)
#define OPC_E_BADTYPE ((HRESULT)0xC0040004L)
#define OPC_E_INVALIDFILTER ((HRESULT)0xC0040009L)
#define OPC_E_UNKNOWNITEMID ((HRESULT)0xC0040007L)

#endif
