/* For the tests under wine only: Wine 8.0 (Debian 12) has no bcryptprimitives.dll, but Rust's
 * standard library on Windows imports ProcessPrng from it (Windows 10 and later ship it). This
 * stand-in fills the buffer from RtlGenRandom (advapi32's SystemFunction036), which Wine has. */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length) {
    while (length > 0) {
        ULONG chunk = length > 0x10000000 ? 0x10000000 : (ULONG)length;
        if (!SystemFunction036(data, chunk)) return FALSE;
        data += chunk;
        length -= chunk;
    }
    return TRUE;
}
