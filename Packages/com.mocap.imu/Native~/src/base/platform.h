/* Threads, locks, clocks and atomics behind one small interface: POSIX (platform_posix.c) and
 * Win32 (platform_win32.c). */
#ifndef MOCAP_PLATFORM_H
#define MOCAP_PLATFORM_H

#include <stdint.h>
#include <stdio.h>

#if defined(__cplusplus) && !(defined(_MSC_VER) && !defined(__clang__))
/* C++ (the tests) has no <stdatomic.h> before C++23. std::atomic<T> has the size, alignment and
 * representation of _Atomic T on GCC and Clang, so structs holding these fields keep one layout
 * in C and C++. Included outside extern "C" because it declares templates. */
#include <atomic>
#endif

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_MSC_VER) && !defined(__clang__)
/* MSVC's C11 atomics need /experimental:c11atomics; use Interlocked intrinsics instead. */
#include <intrin.h>
typedef volatile long long mocap_atomic_u64;
typedef volatile long mocap_atomic_int;
#define mocap_atomic_load_u64(p) ((uint64_t)_InterlockedOr64((p), 0))
#define mocap_atomic_store_u64(p, v) ((void)_InterlockedExchange64((p), (long long)(v)))
#define mocap_atomic_add_u64(p, v) ((uint64_t)_InterlockedExchangeAdd64((p), (long long)(v)))
#define mocap_atomic_load_int(p) ((int)_InterlockedOr((p), 0))
#define mocap_atomic_store_int(p, v) ((void)_InterlockedExchange((p), (long)(v)))
#define mocap_atomic_exchange_int(p, v) ((int)_InterlockedExchange((p), (long)(v)))
#elif defined(__cplusplus)
typedef std::atomic<uint64_t> mocap_atomic_u64;
typedef std::atomic<int> mocap_atomic_int;
#define mocap_atomic_load_u64(p) std::atomic_load_explicit((p), std::memory_order_acquire)
#define mocap_atomic_store_u64(p, v) std::atomic_store_explicit((p), (uint64_t)(v), std::memory_order_release)
#define mocap_atomic_add_u64(p, v) std::atomic_fetch_add_explicit((p), (uint64_t)(v), std::memory_order_acq_rel)
#define mocap_atomic_load_int(p) std::atomic_load_explicit((p), std::memory_order_acquire)
#define mocap_atomic_store_int(p, v) std::atomic_store_explicit((p), (int)(v), std::memory_order_release)
#define mocap_atomic_exchange_int(p, v) std::atomic_exchange_explicit((p), (int)(v), std::memory_order_acq_rel)
#else
#include <stdatomic.h>
typedef _Atomic uint64_t mocap_atomic_u64;
typedef _Atomic int mocap_atomic_int;
#define mocap_atomic_load_u64(p) atomic_load_explicit((p), memory_order_acquire)
#define mocap_atomic_store_u64(p, v) atomic_store_explicit((p), (v), memory_order_release)
#define mocap_atomic_add_u64(p, v) atomic_fetch_add_explicit((p), (v), memory_order_acq_rel)
#define mocap_atomic_load_int(p) atomic_load_explicit((p), memory_order_acquire)
#define mocap_atomic_store_int(p, v) atomic_store_explicit((p), (v), memory_order_release)
#define mocap_atomic_exchange_int(p, v) atomic_exchange_explicit((p), (v), memory_order_acq_rel)
#endif

typedef struct mocap_thread mocap_thread;
typedef struct mocap_mutex mocap_mutex;

typedef void (*mocap_thread_fn)(void *arg);

int mocap_thread_start(mocap_thread **out, mocap_thread_fn fn, void *arg, const char *name);
void mocap_thread_join(mocap_thread *t);

int mocap_mutex_create(mocap_mutex **out);
void mocap_mutex_destroy(mocap_mutex *m);
void mocap_mutex_lock(mocap_mutex *m);
void mocap_mutex_unlock(mocap_mutex *m);

/* Monotonic clock in nanoseconds (arbitrary origin). */
int64_t mocap_monotonic_ns(void);
/* Sleeps about ms milliseconds: ~1 ms resolution on Windows too (a high-resolution waitable
 * timer; plain Sleep(1) lasts a whole 15.6 ms scheduler tick there). */
void mocap_sleep_ms(int ms);

/* Files by UTF-8 path (the API's paths are UTF-8; Windows' narrow calls would read them in the
 * ANSI code page). NULL / nonzero with errno set on failure. mocap_fopen's files are not
 * inherited by programs the process starts (O_CLOEXEC; "N" on Windows). */
FILE *mocap_fopen(const char *path, const char *mode);
/* A file descriptor (binary, not inherited by started programs) for the capture files, which
 * write raw descriptors: read-only, or write-only created/truncated. -1 with errno set. */
int mocap_open_descriptor(const char *path, int for_writing);
int mocap_remove_file(const char *path);
/* Moves from over to in one step, replacing an existing to (rename(); MoveFileEx on Windows,
 * where rename() refuses to replace): at every moment one of the two files is complete.
 * 0 or an errno value. */
int mocap_replace_file(const char *from, const char *to);
/* The file a save that replaces `path` (a temporary renamed over it) must write: `path`, or the
 * file a symbolic link there points to, so that the link stays a link. 0; -1 when an existing
 * target is not a regular file (a device such as /dev/full, a pipe, a folder), which a rename
 * would replace; an errno value (a dangling or looping link, a name too long for resolved). */
int mocap_replace_target(const char *path, char *resolved, size_t resolved_cap);
/* fflush, then ask the OS to put the file's data on the disk (fsync / _commit), so that a
 * rename that follows never exposes an empty file after a power loss. 0 or an errno value. */
int mocap_flush_to_disk(FILE *f);
/* Shared libraries by UTF-8 path (dlopen; LoadLibraryExW on Windows, where a path with a
 * folder also finds the DLLs that library needs beside it, e.g. ONNX Runtime's
 * onnxruntime_providers_shared.dll; a bare name is searched for the usual way). NULL on failure,
 * with the system's reason in why. Loaded libraries are reference counted by the OS: opening
 * one already loaded returns the same module. */
void *mocap_library_open(const char *path, char *why, size_t why_cap);
void *mocap_library_symbol(void *library, const char *name);
void mocap_library_close(void *library);
/* This process's id (for names that must not collide between processes). */
unsigned long mocap_process_id(void);

#if defined(_WIN32)
#include <wchar.h>
/* A UTF-8 string as UTF-16 for Windows' wide calls: 0, or -1 with errno EINVAL (not UTF-8) or
 * ENAMETOOLONG (more than cap units with the terminator). */
int mocap_utf8_to_wide(const char *utf8, wchar_t *out, int cap);
#endif

#ifdef __cplusplus
}
#endif
#endif
