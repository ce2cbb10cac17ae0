/* opccomn.h compiles alone as strict C99 (-pedantic-errors), and its declarations link. */
#include <opccomn/opccomn.h>

int main(void) {
    LPWSTR text = 0;
    HRESULT hr = OpcGetErrorString((HRESULT)0xC0040001u, 0x0409, &text);
    int ok = hr == S_OK && text != 0 && sizeof(GUID) == 16 && sizeof(WCHAR) == 2;
    OpcTaskMemFree(text);
    return ok ? 0 : 1;
}
