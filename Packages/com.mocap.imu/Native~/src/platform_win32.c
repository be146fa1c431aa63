/* Win32 implementation of platform.h: _beginthreadex, SRW locks, QueryPerformanceCounter. */
#ifndef WIN32_LEAN_AND_MEAN
#define WIN32_LEAN_AND_MEAN
#endif
#include <windows.h>
#include <process.h>

#include "platform.h"

#include "error.h"

#include <stdlib.h>
#include <string.h>

struct mocap_thread {
    HANDLE handle;
    mocap_thread_fn fn;
    void *arg;
    char name[64];
};

struct mocap_mutex {
    SRWLOCK lock;
};

/* SetThreadDescription exists from Windows 10 1607 on; look it up so older systems still load
 * the library. */
typedef HRESULT(WINAPI *set_thread_description_fn)(HANDLE, PCWSTR);

static void name_current_thread(const char *name)
{
    if (!name[0]) return;
    HMODULE kernel = GetModuleHandleW(L"kernel32.dll");
    if (!kernel) return;
    FARPROC proc = GetProcAddress(kernel, "SetThreadDescription");
    if (!proc) return;
    set_thread_description_fn set_description = (set_thread_description_fn)(void (*)(void))proc;
    wchar_t wide[64];
    if (MultiByteToWideChar(CP_UTF8, 0, name, -1, wide, (int)(sizeof wide / sizeof wide[0])) <= 0)
        return;
    (void)set_description(GetCurrentThread(), wide);
}

static unsigned __stdcall thread_trampoline(void *arg)
{
    mocap_thread *t = (mocap_thread *)arg;
    name_current_thread(t->name);
    t->fn(t->arg);
    return 0;
}

int mocap_thread_start(mocap_thread **out, mocap_thread_fn fn, void *arg, const char *name)
{
    if (out) *out = NULL;
    if (!out || !fn) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "thread start: NULL argument");
    mocap_thread *t = (mocap_thread *)calloc(1, sizeof *t);
    if (!t) return mocap_fail(MOCAP_ERR_NO_MEMORY, "thread start: out of memory");
    t->fn = fn;
    t->arg = arg;
    if (name) {
        size_t len = strlen(name);
        if (len >= sizeof t->name) len = sizeof t->name - 1;
        memcpy(t->name, name, len);
        t->name[len] = '\0';
    }
    /* _beginthreadex rather than CreateThread so the C runtime's per-thread state is set up. */
    uintptr_t handle = _beginthreadex(NULL, 0, thread_trampoline, t, 0, NULL);
    if (handle == 0) {
        free(t);
        return mocap_fail(MOCAP_ERR_IO, "cannot start thread '%s' (error %lu)", name ? name : "",
                          (unsigned long)GetLastError());
    }
    t->handle = (HANDLE)handle;
    *out = t;
    return MOCAP_OK;
}

void mocap_thread_join(mocap_thread *t)
{
    if (!t) return;
    (void)WaitForSingleObject(t->handle, INFINITE);
    CloseHandle(t->handle);
    free(t);
}

int mocap_mutex_create(mocap_mutex **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mutex create: NULL argument");
    *out = NULL;
    mocap_mutex *m = (mocap_mutex *)calloc(1, sizeof *m);
    if (!m) return mocap_fail(MOCAP_ERR_NO_MEMORY, "mutex create: out of memory");
    InitializeSRWLock(&m->lock);
    *out = m;
    return MOCAP_OK;
}

void mocap_mutex_destroy(mocap_mutex *m) { free(m); } /* SRW locks need no cleanup */

void mocap_mutex_lock(mocap_mutex *m) { AcquireSRWLockExclusive(&m->lock); }

void mocap_mutex_unlock(mocap_mutex *m) { ReleaseSRWLockExclusive(&m->lock); }

int64_t mocap_monotonic_ns(void)
{
    LARGE_INTEGER frequency, counter;
    /* Both calls always succeed on Windows XP and later. The frequency is fixed at boot. */
    QueryPerformanceFrequency(&frequency);
    QueryPerformanceCounter(&counter);
    /* Split into whole seconds and remainder so counter * 1e9 cannot overflow. */
    int64_t seconds = counter.QuadPart / frequency.QuadPart;
    int64_t remainder = counter.QuadPart % frequency.QuadPart;
    return seconds * 1000000000LL + remainder * 1000000000LL / frequency.QuadPart;
}

void mocap_sleep_ms(int ms)
{
    if (ms <= 0) return;
    Sleep((DWORD)ms);
}
