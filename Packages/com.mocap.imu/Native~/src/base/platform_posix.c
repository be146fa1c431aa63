/* POSIX implementation of platform.h: pthreads, CLOCK_MONOTONIC, nanosleep. */
#if defined(__linux__) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* pthread_setname_np */
#endif

#include "platform.h"

#include "error.h"

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <sys/stat.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#if defined(__FreeBSD__) || defined(__OpenBSD__)
#include <pthread_np.h>
#endif

/* Linux limits thread names to 15 characters plus the terminator. */
#define THREAD_NAME_CAP 16

struct mocap_thread {
    pthread_t handle;
    mocap_thread_fn fn;
    void *arg;
    char name[THREAD_NAME_CAP];
};

struct mocap_mutex {
    pthread_mutex_t handle;
};

static void name_current_thread(const char *name)
{
    if (!name[0]) return;
    /* Naming is cosmetic (debuggers, top -H): failures are ignored. macOS can only name the
     * calling thread, so every platform names the thread from inside it. */
#if defined(__APPLE__)
    (void)pthread_setname_np(name);
#elif defined(__linux__) || defined(__NetBSD__)
#if defined(__NetBSD__)
    (void)pthread_setname_np(pthread_self(), "%s", (void *)name);
#else
    (void)pthread_setname_np(pthread_self(), name);
#endif
#elif defined(__FreeBSD__) || defined(__OpenBSD__)
    pthread_set_name_np(pthread_self(), name);
#endif
}

static void *thread_trampoline(void *arg)
{
    mocap_thread *t = (mocap_thread *)arg;
    name_current_thread(t->name);
    t->fn(t->arg);
    return NULL;
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
        /* Truncate rather than fail: Linux rejects longer names with ERANGE. */
        size_t len = strlen(name);
        if (len >= sizeof t->name) len = sizeof t->name - 1;
        memcpy(t->name, name, len);
        t->name[len] = '\0';
    }
    int err = pthread_create(&t->handle, NULL, thread_trampoline, t);
    if (err != 0) {
        char text[128];
        free(t);
        return mocap_fail(err == EAGAIN ? MOCAP_ERR_NO_MEMORY : MOCAP_ERR_IO,
                          "cannot start thread '%s': %s", name ? name : "",
                          mocap_errno_text(err, text, sizeof text));
    }
    *out = t;
    return MOCAP_OK;
}

void mocap_thread_join(mocap_thread *t)
{
    if (!t) return;
    (void)pthread_join(t->handle, NULL);
    free(t);
}

int mocap_mutex_create(mocap_mutex **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mutex create: NULL argument");
    *out = NULL;
    mocap_mutex *m = (mocap_mutex *)calloc(1, sizeof *m);
    if (!m) return mocap_fail(MOCAP_ERR_NO_MEMORY, "mutex create: out of memory");
    int err = pthread_mutex_init(&m->handle, NULL);
    if (err != 0) {
        char text[128];
        free(m);
        return mocap_fail(MOCAP_ERR_IO, "mutex create: %s", mocap_errno_text(err, text, sizeof text));
    }
    *out = m;
    return MOCAP_OK;
}

void mocap_mutex_destroy(mocap_mutex *m)
{
    if (!m) return;
    (void)pthread_mutex_destroy(&m->handle);
    free(m);
}

void mocap_mutex_lock(mocap_mutex *m) { (void)pthread_mutex_lock(&m->handle); }

void mocap_mutex_unlock(mocap_mutex *m) { (void)pthread_mutex_unlock(&m->handle); }

int64_t mocap_monotonic_ns(void)
{
    struct timespec ts;
    /* CLOCK_MONOTONIC cannot fail with a valid pointer on any supported system. */
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + (int64_t)ts.tv_nsec;
}

FILE *mocap_fopen(const char *path, const char *mode)
{
    /* open() with O_CLOEXEC, then fdopen(): a program the host starts (the Unity editor runs
     * tools) must not inherit a BVH or calibration file we hold open. fopen's "e" flag does the
     * same but is not POSIX, and a separate fcntl() would leave a window for a fork. */
    int flags;
    switch (mode[0]) {
    case 'r': flags = strchr(mode, '+') ? O_RDWR : O_RDONLY; break;
    case 'w': flags = (strchr(mode, '+') ? O_RDWR : O_WRONLY) | O_CREAT | O_TRUNC; break;
    case 'a': flags = (strchr(mode, '+') ? O_RDWR : O_WRONLY) | O_CREAT | O_APPEND; break;
    default: errno = EINVAL; return NULL;
    }
    int fd = open(path, flags | O_CLOEXEC, 0666);
    if (fd < 0) return NULL;
    FILE *f = fdopen(fd, mode);
    if (!f) {
        int e = errno;
        (void)close(fd);
        errno = e;
    }
    return f;
}

int mocap_open_descriptor(const char *path, int for_writing)
{
    int fd;
    do {
        fd = for_writing ? open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666)
                         : open(path, O_RDONLY | O_CLOEXEC);
    } while (fd < 0 && errno == EINTR);
    return fd;
}

int mocap_remove_file(const char *path) { return remove(path); }

void *mocap_library_open(const char *path, char *why, size_t why_cap)
{
    void *library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!library && why && why_cap) {
        const char *e = dlerror();
        snprintf(why, why_cap, "%s", e ? e : "unknown dlopen error");
    }
    return library;
}

void *mocap_library_symbol(void *library, const char *name) { return dlsym(library, name); }

void mocap_library_close(void *library)
{
    if (library) (void)dlclose(library);
}

int mocap_replace_target(const char *path, char *resolved, size_t resolved_cap)
{
    struct stat st;
    if (lstat(path, &st) != 0) {
        if (errno != ENOENT) return errno;
        if ((size_t)snprintf(resolved, resolved_cap, "%s", path) >= resolved_cap) return ENAMETOOLONG;
        return 0; /* a new file */
    }
    if (S_ISLNK(st.st_mode)) {
        char target[PATH_MAX];
        if (!realpath(path, target)) return errno;
        if (stat(target, &st) != 0) return errno;
        if ((size_t)snprintf(resolved, resolved_cap, "%s", target) >= resolved_cap) return ENAMETOOLONG;
    } else if ((size_t)snprintf(resolved, resolved_cap, "%s", path) >= resolved_cap) {
        return ENAMETOOLONG;
    }
    return S_ISREG(st.st_mode) ? 0 : -1;
}

int mocap_replace_file(const char *from, const char *to)
{
    return rename(from, to) == 0 ? 0 : (errno ? errno : EIO);
}

int mocap_flush_to_disk(FILE *f)
{
    if (fflush(f) != 0) return errno ? errno : EIO;
    return fsync(fileno(f)) == 0 ? 0 : (errno ? errno : EIO);
}

unsigned long mocap_process_id(void) { return (unsigned long)getpid(); }

void mocap_sleep_ms(int ms)
{
    if (ms <= 0) return;
    struct timespec req;
    req.tv_sec = ms / 1000;
    req.tv_nsec = (long)(ms % 1000) * 1000000L;
    struct timespec rem;
    /* A signal must not shorten the sleep: continue with what is left. */
    while (nanosleep(&req, &rem) != 0 && errno == EINTR) req = rem;
}
