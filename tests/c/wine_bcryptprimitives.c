/* For the tests under wine only, never shipped: Debian 12's wine 8 has no
 * bcryptprimitives.dll, which every Windows 10 or newer has and Rust's standard library
 * (1.78 and newer) imports for ProcessPrng. Placed beside the test host's .exe (the first
 * folder Windows searches), it answers with wine's BCryptGenRandom. Wine 10 has its own. */
#include <windows.h>
#include <bcrypt.h>

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length) {
    return BCryptGenRandom(NULL, data, (ULONG)length, BCRYPT_USE_SYSTEM_PREFERRED_RNG) == 0;
}
