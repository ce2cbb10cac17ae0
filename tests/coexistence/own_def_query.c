/* Prints the InprocServer32 path registered for the class of own_def_server.c, or "absent", reading
 * HKEY_CLASSES_ROOT through the registry API in the view of its own architecture (build it for the
 * server's). scripts/test-coexistence.sh runs it after regsvr32 and regsvr32 /u. */
#include <windows.h>
#include <stdio.h>

int main(void) {
    HKEY key;
    WCHAR path[MAX_PATH + 1];
    DWORD size = sizeof path - sizeof(WCHAR);
    LONG status = RegOpenKeyExW(HKEY_CLASSES_ROOT, L"CLSID\\{6C1E0B57-3A2D-4F7E-9B14-2E8D5A1C7F30}\\InprocServer32",
                                0, KEY_READ, &key);
    if (status != ERROR_SUCCESS) {
        printf("absent\n");
        return 0;
    }
    status = RegQueryValueExW(key, NULL, NULL, NULL, (BYTE *)path, &size);
    RegCloseKey(key);
    if (status != ERROR_SUCCESS) {
        printf("no path (%ld)\n", status);
        return 1;
    }
    path[size / sizeof(WCHAR)] = 0;
    printf("%ls\n", path);
    return 0;
}
