// Threads, mutexes, the monotonic clock and the files of platform.h.
#include <gtest/gtest.h>

#include <atomic> // before platform.h: g++ needs it for _Atomic in C++ mode
#include <cstring>
#include <string>
#include <cerrno>
#include <cstdio>
#include <vector>

#include "test_support.h"

extern "C" {
#include "error.h"
#include "platform.h"
}

#if defined(__linux__)
#include <pthread.h>
#elif defined(_WIN32)
#include <windows.h>
#endif

namespace {

struct ThreadProbe {
    int input = 0;
    int output = 0;
    char name[128] = {0};
};

#if defined(_WIN32)
// GetThreadDescription (Windows 10 1607 and later) as UTF-8; looked up like the engine does.
void current_thread_description(char *out, int cap)
{
    typedef HRESULT(WINAPI * get_description_fn)(HANDLE, PWSTR *);
    HMODULE kernel = GetModuleHandleW(L"kernel32.dll");
    FARPROC proc = kernel ? GetProcAddress(kernel, "GetThreadDescription") : nullptr;
    if (!proc) return;
    PWSTR wide = nullptr;
    if (FAILED(reinterpret_cast<get_description_fn>(reinterpret_cast<void (*)()>(proc))(GetCurrentThread(), &wide)))
        return;
    WideCharToMultiByte(CP_UTF8, 0, wide, -1, out, cap, nullptr, nullptr);
    LocalFree(wide);
}
#endif

void probe_fn(void *arg)
{
    auto *probe = static_cast<ThreadProbe *>(arg);
    probe->output = probe->input * 3;
#if defined(__linux__)
    pthread_getname_np(pthread_self(), probe->name, sizeof probe->name);
#elif defined(_WIN32)
    current_thread_description(probe->name, (int)sizeof probe->name);
#endif
}

struct CounterShared {
    mocap_mutex *mutex = nullptr;
    long counter = 0; // deliberately not atomic: only the mutex protects it
    int iterations = 0;
};

void counter_fn(void *arg)
{
    auto *shared = static_cast<CounterShared *>(arg);
    for (int i = 0; i < shared->iterations; ++i) {
        mocap_mutex_lock(shared->mutex);
        long value = shared->counter;
        shared->counter = value + 1;
        mocap_mutex_unlock(shared->mutex);
    }
}

} // namespace

TEST(Platform, ThreadRunsWithArgumentAndJoins)
{
    ThreadProbe probe;
    probe.input = 14;
    mocap_thread *thread = nullptr;
    ASSERT_EQ(mocap_thread_start(&thread, probe_fn, &probe, "mocap-probe"), MOCAP_OK);
    ASSERT_NE(thread, nullptr);
    mocap_thread_join(thread);
    EXPECT_EQ(probe.output, 42);
#if defined(__linux__) || defined(_WIN32)
    EXPECT_STREQ(probe.name, "mocap-probe");
#endif
}

#if defined(__linux__) || defined(_WIN32)
TEST(Platform, LongThreadNameIsTruncatedNotRefused)
{
    // Linux keeps 15 bytes of a thread name; the engine keeps 63 for Windows' descriptions.
#if defined(_WIN32)
    const std::string name = "mocap-reader-thread-" + std::string(80, 'x');
    const size_t kept = 63;
#else
    const std::string name = "mocap-reader-thread-long-name";
    const size_t kept = 15;
#endif
    ThreadProbe probe;
    mocap_thread *thread = nullptr;
    ASSERT_EQ(mocap_thread_start(&thread, probe_fn, &probe, name.c_str()), MOCAP_OK);
    mocap_thread_join(thread);
    EXPECT_EQ(std::string(probe.name), name.substr(0, kept));
}
#endif

TEST(Platform, ThreadStartRejectsNullFunction)
{
    mocap_thread *thread = reinterpret_cast<mocap_thread *>(0x1);
    EXPECT_NE(mocap_thread_start(&thread, nullptr, nullptr, "x"), MOCAP_OK);
    EXPECT_EQ(thread, nullptr);
    EXPECT_STRNE(mocap_last_error(), "");
}

TEST(Platform, MutexExcludesConcurrentIncrements)
{
    CounterShared shared;
    shared.iterations = 50000;
    ASSERT_EQ(mocap_mutex_create(&shared.mutex), MOCAP_OK);
    const int thread_count = 4;
    std::vector<mocap_thread *> threads(thread_count, nullptr);
    for (auto &t : threads) ASSERT_EQ(mocap_thread_start(&t, counter_fn, &shared, "counter"), MOCAP_OK);
    for (auto *t : threads) mocap_thread_join(t);
    EXPECT_EQ(shared.counter, static_cast<long>(thread_count) * shared.iterations);
    mocap_mutex_destroy(shared.mutex);
}

TEST(Platform, MonotonicClockAdvancesAcrossSleep)
{
    const int64_t before = mocap_monotonic_ns();
    mocap_sleep_ms(30);
    const int64_t after = mocap_monotonic_ns();
    // The sleep is a lower bound; scheduling can only make it longer.
    EXPECT_GE(after - before, 30LL * 1000000LL);
    EXPECT_LT(after - before, 5LL * 1000000000LL);
}

TEST(Platform, MonotonicClockNeverGoesBackwards)
{
    int64_t previous = mocap_monotonic_ns();
    EXPECT_GT(previous, 0);
    for (int i = 0; i < 100000; ++i) {
        const int64_t now = mocap_monotonic_ns();
        ASSERT_GE(now, previous);
        previous = now;
    }
}

TEST(Platform, SleepOfZeroOrLessReturnsImmediately)
{
    const int64_t before = mocap_monotonic_ns();
    mocap_sleep_ms(0);
    mocap_sleep_ms(-5);
    EXPECT_LT(mocap_monotonic_ns() - before, 1000000000LL);
}

#if !defined(_WIN32) // Windows: reads /proc/self/fd
// The Unity editor starts tools while a session runs: they must not inherit the files the engine
// holds (a BVH being written, a calibration being read), which would also keep them locked.
TEST(Platform, OpenedFilesAreNotInheritedByStartedPrograms)
{
    const std::string path = test_temp_path("file.txt");
    const struct {
        const char *mode;
        const char *write;
        const char *expect_after; // file content after the write, "" for a read
    } cases[] = {{"w", "one\n", "one\n"}, {"r", nullptr, "one\n"},   {"a", "two\n", "one\ntwo\n"},
                 {"rb", nullptr, "one\ntwo\n"}, {"r+", "ONE", "ONE\ntwo\n"}, {"wb+", "new", "new"},
                 {"a+", "!", "new!"}};
    for (const auto &c : cases) {
        SCOPED_TRACE(c.mode);
        FILE *f = nullptr;
        OpenedDescriptors d = descriptors_opened_by([&] { f = mocap_fopen(path.c_str(), c.mode); });
        ASSERT_NE(f, nullptr) << std::strerror(errno);
        EXPECT_EQ(d.opened.size(), 1u);
        EXPECT_TRUE(d.inheritable.empty()) << "the descriptor is inherited by exec";
        if (c.write) {
            EXPECT_GE(std::fputs(c.write, f), 0);
        }
        ASSERT_EQ(std::fclose(f), 0);
        FILE *check = std::fopen(path.c_str(), "rb");
        ASSERT_NE(check, nullptr);
        char buf[64] = {0};
        const size_t n = std::fread(buf, 1, sizeof buf - 1, check);
        std::fclose(check);
        EXPECT_EQ(std::string(buf, n), c.expect_after);
    }
    errno = 0;
    EXPECT_EQ(mocap_fopen(path.c_str(), "x"), nullptr);
    EXPECT_EQ(errno, EINVAL);
    errno = 0;
    EXPECT_EQ(mocap_fopen(test_temp_path("absent.txt").c_str(), "r"), nullptr);
    EXPECT_EQ(errno, ENOENT);
}
#endif
