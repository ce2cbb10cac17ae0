/* The plumbing example's DLL server (dll_server.c): what its check (check_dll_server.c) needs to know. */
#ifndef OPCCOMN_EXAMPLE_DLL_SERVER_H
#define OPCCOMN_EXAMPLE_DLL_SERVER_H

#include <windows.h>

#include <opccomn/opccomn.h>

/* {5EC0A7B1-6C1D-4E51-9B0C-2D4F61A3C7E8} */
static const CLSID CLSID_PlumbingServer = {0x5EC0A7B1, 0x6C1D, 0x4E51, {0x9B, 0x0C, 0x2D, 0x4F, 0x61, 0xA3, 0xC7, 0xE8}};
#define PLUMBING_PROGID L"OpcComn.PlumbingExample.1"

/* How many server objects the factory lets exist at the same time (its licence). */
#define PLUMBING_MAX_CLIENTS 2

#endif
