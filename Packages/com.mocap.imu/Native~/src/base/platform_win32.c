/* Win32 implementation of platform.h: _beginthreadex, SRW locks, QueryPerformanceCounter. */
#ifndef WIN32_LEAN_AND_MEAN
#define WIN32_LEAN_AND_MEAN
#endif
#ifndef _WIN32_WINNT
#define _WIN32_WINNT 0x0601 /* CreateWaitableTimerExW */
#endif
#include <windows.h>
#include <fcntl.h>
#include <io.h>
#include <process.h>
#include <sys/stat.h>

#include "platform.h"

#include "error.h"

#include <errno.h>
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

#if defined(_MSC_VER)
#define MOCAP_THREAD_LOCAL __declspec(thread)
#else
#define MOCAP_THREAD_LOCAL _Thread_local
#endif
#ifndef CREATE_WAITABLE_TIMER_HIGH_RESOLUTION
#define CREATE_WAITABLE_TIMER_HIGH_RESOLUTION 0x00000002
#endif

/* One high-resolution timer per sleeping thread (Windows 10 1803 and later; NULL before). */
static MOCAP_THREAD_LOCAL HANDLE sleep_timer;
static MOCAP_THREAD_LOCAL int sleep_timer_tried;

static void release_sleep_timer(void)
{
    if (sleep_timer) CloseHandle(sleep_timer);
    sleep_timer = NULL;
    sleep_timer_tried = 0;
}

static unsigned __stdcall thread_trampoline(void *arg)
{
    mocap_thread *t = (mocap_thread *)arg;
    name_current_thread(t->name);
    t->fn(t->arg);
    release_sleep_timer();
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
    if (!sleep_timer_tried) {
        sleep_timer_tried = 1;
        sleep_timer = CreateWaitableTimerExW(NULL, NULL, CREATE_WAITABLE_TIMER_HIGH_RESOLUTION,
                                             TIMER_ALL_ACCESS);
    }
    if (sleep_timer) {
        LARGE_INTEGER due;
        due.QuadPart = -(LONGLONG)ms * 10000; /* relative, 100 ns units */
        if (SetWaitableTimer(sleep_timer, &due, 0, NULL, NULL, FALSE) &&
            WaitForSingleObject(sleep_timer, INFINITE) == WAIT_OBJECT_0)
            return;
    }
    Sleep((DWORD)ms);
}

#define WIDE_PATH_MAX 4096

int mocap_utf8_to_wide(const char *utf8, wchar_t *out, int cap)
{
    if (MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, utf8, -1, out, cap) > 0) return 0;
    errno = GetLastError() == ERROR_INSUFFICIENT_BUFFER ? ENAMETOOLONG : EINVAL;
    return -1;
}

FILE *mocap_fopen(const char *path, const char *mode)
{
    /* _wopen with _O_NOINHERIT, then _fdopen: not inherited by processes the host starts (the
     * Unity editor runs tools), the same as O_CLOEXEC on POSIX and capture_file.c's files. */
    wchar_t wpath[WIDE_PATH_MAX];
    int flags;
    switch (mode[0]) {
    case 'r': flags = strchr(mode, '+') ? _O_RDWR : _O_RDONLY; break;
    case 'w': flags = (strchr(mode, '+') ? _O_RDWR : _O_WRONLY) | _O_CREAT | _O_TRUNC; break;
    case 'a': flags = (strchr(mode, '+') ? _O_RDWR : _O_WRONLY) | _O_CREAT | _O_APPEND; break;
    default: errno = EINVAL; return NULL;
    }
    flags |= strchr(mode, 'b') ? _O_BINARY : _O_TEXT;
    if (mocap_utf8_to_wide(path, wpath, WIDE_PATH_MAX) != 0) return NULL;
    int fd = _wopen(wpath, flags | _O_NOINHERIT, _S_IREAD | _S_IWRITE);
    if (fd < 0) return NULL;
    FILE *f = _fdopen(fd, mode);
    if (!f) {
        int e = errno;
        _close(fd);
        errno = e;
    }
    return f;
}

int mocap_replace_target(const char *path, char *resolved, size_t resolved_cap)
{
    wchar_t wpath[WIDE_PATH_MAX];
    if (mocap_utf8_to_wide(path, wpath, WIDE_PATH_MAX) != 0) return errno;
    if ((size_t)snprintf(resolved, resolved_cap, "%s", path) >= resolved_cap) return ENAMETOOLONG;
    DWORD attributes = GetFileAttributesW(wpath);
    if (attributes == INVALID_FILE_ATTRIBUTES) return 0; /* a new file (or one we cannot see) */
    if (attributes & (FILE_ATTRIBUTE_DIRECTORY | FILE_ATTRIBUTE_DEVICE)) return -1;
    /* A symbolic link (reparse point) is replaced by MoveFileEx itself; Windows' links to files
     * are rare enough here that the link is not followed. */
    return 0;
}

int mocap_open_descriptor(const char *path, int for_writing)
{
    wchar_t wpath[WIDE_PATH_MAX];
    if (mocap_utf8_to_wide(path, wpath, WIDE_PATH_MAX) != 0) return -1;
    if (for_writing)
        return _wopen(wpath, _O_WRONLY | _O_CREAT | _O_TRUNC | _O_BINARY | _O_NOINHERIT,
                      _S_IREAD | _S_IWRITE);
    return _wopen(wpath, _O_RDONLY | _O_BINARY | _O_NOINHERIT);
}

void *mocap_library_open(const char *path, char *why, size_t why_cap)
{
    wchar_t wpath[WIDE_PATH_MAX];
    if (mocap_utf8_to_wide(path, wpath, WIDE_PATH_MAX) != 0) {
        if (why && why_cap) snprintf(why, why_cap, "%s: not a valid UTF-8 path", path);
        return NULL;
    }
    /* With a folder in the path, the DLL's own folder is searched for its dependencies; the
     * flags need an absolute path, so a relative one falls back to the standard search. */
    int has_folder = wcspbrk(wpath, L"\\/") != NULL;
    DWORD flags = has_folder ? LOAD_LIBRARY_SEARCH_DLL_LOAD_DIR | LOAD_LIBRARY_SEARCH_DEFAULT_DIRS : 0;
    wchar_t full[WIDE_PATH_MAX];
    const wchar_t *name = wpath;
    if (has_folder) {
        DWORD n = GetFullPathNameW(wpath, WIDE_PATH_MAX, full, NULL);
        if (n > 0 && n < WIDE_PATH_MAX) name = full;
    }
    HMODULE library = LoadLibraryExW(name, NULL, flags);
    if (!library && why && why_cap) {
        DWORD code = GetLastError();
        char text[256] = "";
        DWORD len = FormatMessageA(FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS, NULL,
                                   code, 0, text, (DWORD)sizeof text, NULL);
        while (len > 0 && (text[len - 1] == '\n' || text[len - 1] == '\r' || text[len - 1] == ' '))
            text[--len] = '\0';
        snprintf(why, why_cap, "%s: Windows error %lu%s%s", path, (unsigned long)code,
                 len ? ": " : "", text);
    }
    return (void *)library;
}

void *mocap_library_symbol(void *library, const char *name)
{
    return (void *)(intptr_t)GetProcAddress((HMODULE)library, name);
}

void mocap_library_close(void *library)
{
    if (library) (void)FreeLibrary((HMODULE)library);
}

int mocap_remove_file(const char *path)
{
    wchar_t wpath[WIDE_PATH_MAX];
    if (mocap_utf8_to_wide(path, wpath, WIDE_PATH_MAX) != 0) return -1;
    return _wremove(wpath);
}

int mocap_flush_to_disk(FILE *f)
{
    if (fflush(f) != 0) return errno ? errno : EIO;
    return _commit(_fileno(f)) == 0 ? 0 : (errno ? errno : EIO);
}

unsigned long mocap_process_id(void) { return (unsigned long)GetCurrentProcessId(); }

int mocap_replace_file(const char *from, const char *to)
{
    wchar_t wfrom[WIDE_PATH_MAX], wto[WIDE_PATH_MAX];
    if (mocap_utf8_to_wide(from, wfrom, WIDE_PATH_MAX) != 0 || mocap_utf8_to_wide(to, wto, WIDE_PATH_MAX) != 0) return errno;
    /* Two replacements of one file at once (saves from two threads) make one of them fail for a
     * moment with a sharing violation or access denied while the other holds the target: retry
     * those for up to about a second, as a POSIX rename() would simply have succeeded. */
    DWORD error = ERROR_SUCCESS;
    for (int attempt = 0; attempt < 200; ++attempt) {
        if (MoveFileExW(wfrom, wto, MOVEFILE_REPLACE_EXISTING | MOVEFILE_WRITE_THROUGH)) return 0;
        error = GetLastError();
        if (error != ERROR_ACCESS_DENIED && error != ERROR_SHARING_VIOLATION) break;
        Sleep(attempt < 20 ? 0 : 5);
    }
    switch (error) {
    case ERROR_ACCESS_DENIED:
    case ERROR_SHARING_VIOLATION: return EACCES;
    case ERROR_FILE_NOT_FOUND:
    case ERROR_PATH_NOT_FOUND: return ENOENT;
    case ERROR_DISK_FULL: return ENOSPC;
    default: return EIO;
    }
}
