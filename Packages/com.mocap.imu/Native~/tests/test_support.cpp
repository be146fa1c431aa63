#include "test_support.h"

#include <gtest/gtest.h>

#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <array>
#include <cstdlib>

#if defined(_WIN32)
#include <process.h>
#define getpid _getpid
#define popen _popen
#define pclose _pclose
#else
#include <csignal>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <dirent.h>
#include <fcntl.h>
#endif

#include <algorithm>
#include <set>

// Outside a test (e.g. in SetUpTestSuite) there is no test name; ctest runs each test in its own
// process, possibly in parallel, so the fallback must be unique per process or one process would
// wipe another's files.
static std::string current_test_name()
{
    const auto *info = ::testing::UnitTest::GetInstance()->current_test_info();
    if (info) return std::string(info->test_suite_name()) + "." + info->name();
    return "process-" + std::to_string(static_cast<long>(getpid()));
}

std::string test_temp_dir()
{
    std::string name = current_test_name();
    for (char &c : name)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.') c = '_';
    std::filesystem::path dir = std::filesystem::path(MOCAP_TEST_TMPDIR) / name;
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir.string();
}

std::string test_temp_path(const std::string &name)
{
    std::string test = current_test_name();
    for (char &c : test)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.') c = '_';
    std::filesystem::path dir = std::filesystem::path(MOCAP_TEST_TMPDIR) / test;
    std::filesystem::create_directories(dir);
    return (dir / name).string();
}

std::vector<uint8_t> hex_bytes(const std::string &hex)
{
    std::vector<uint8_t> out;
    std::string digits;
    for (char c : hex)
        if (std::isxdigit(static_cast<unsigned char>(c))) digits.push_back(c);
    if (digits.size() % 2) throw std::invalid_argument("odd number of hex digits");
    for (size_t i = 0; i < digits.size(); i += 2)
        out.push_back(static_cast<uint8_t>(std::stoul(digits.substr(i, 2), nullptr, 16)));
    return out;
}

std::vector<uint8_t> read_file_bytes(const std::string &path)
{
    std::ifstream in(path, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_file_bytes(const std::string &path, const std::vector<uint8_t> &bytes)
{
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char *>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

CommandResult run_shell(const std::string &cmd)
{
    CommandResult r;
    FILE *p = popen((cmd + " 2>&1").c_str(), "r");
    if (!p) return r;
    std::array<char, 8192> buf;
    size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
    int status = pclose(p);
#if defined(_WIN32)
    r.exit_code = status; // _pclose returns the command's exit code
#else
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
#endif
    return r;
}

std::string python_with_numpy()
{
    std::vector<std::string> candidates;
    if (const char *env = std::getenv("MOCAP_PYTHON")) candidates.push_back(env);
    candidates.push_back("/usr/bin/python3");
    candidates.push_back("python3");
    for (const auto &p : candidates)
#if defined(_WIN32)
        if (std::system(("\"" + p + "\" -c \"import numpy\" >NUL 2>&1").c_str()) == 0) return p;
#else
        if (std::system(("\"" + p + "\" -c \"import numpy\" >/dev/null 2>&1").c_str()) == 0) return p;
#endif
    return "";
}

#if !defined(_WIN32)
// POSIX only (fork, RLIMIT_FSIZE, /proc/self/fd): the suites that use these are not built for
// Windows (tests/CMakeLists.txt says why).
int exit_code_with_file_size_limit(uint64_t max_file_bytes, const std::function<int()> &child)
{
    pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid == 0) {
        struct rlimit limit = {(rlim_t)max_file_bytes, (rlim_t)max_file_bytes};
        signal(SIGXFSZ, SIG_IGN);
        if (setrlimit(RLIMIT_FSIZE, &limit) != 0) _exit(120);
        _exit(child());
    }
    int status = 0;
    if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status)) return -1;
    return WEXITSTATUS(status) == 120 ? -1 : WEXITSTATUS(status);
}

static std::set<int> open_descriptors()
{
    std::set<int> fds;
    DIR *d = opendir("/proc/self/fd");
    if (!d) return fds;
    const int own = dirfd(d);
    while (const struct dirent *e = readdir(d)) {
        if (e->d_name[0] == '.') continue;
        const int fd = std::atoi(e->d_name);
        if (fd != own) fds.insert(fd);
    }
    closedir(d);
    return fds;
}

OpenedDescriptors descriptors_opened_by(const std::function<void()> &action)
{
    const std::set<int> before = open_descriptors();
    action();
    OpenedDescriptors out;
    for (int fd : open_descriptors()) {
        if (before.count(fd)) continue;
        out.opened.push_back(fd);
        const int flags = fcntl(fd, F_GETFD);
        if (flags >= 0 && !(flags & FD_CLOEXEC)) out.inheritable.push_back(fd);
    }
    return out;
}
#endif

static void put_u32(std::vector<uint8_t> &b, uint32_t v)
{
    for (int i = 0; i < 4; ++i) b.push_back((uint8_t)(v >> (8 * i)));
}

static uint32_t get_u32(const std::vector<uint8_t> &b, size_t at)
{
    return (uint32_t)b[at] | (uint32_t)b[at + 1] << 8 | (uint32_t)b[at + 2] << 16 |
           (uint32_t)b[at + 3] << 24;
}

std::vector<uint8_t> tensor_bundle_bytes(const std::vector<BundleTensor> &tensors)
{
    std::vector<uint8_t> b = {'M', 'O', 'C', 'A', 'P', 'T', 'N', 'S'};
    put_u32(b, 1);
    put_u32(b, (uint32_t)tensors.size());
    for (const BundleTensor &t : tensors) {
        char n[32] = {0};
        std::snprintf(n, sizeof n, "%s", t.name.c_str());
        b.insert(b.end(), n, n + 32);
        put_u32(b, (uint32_t)t.dims.size());
        for (uint32_t d : t.dims) put_u32(b, d);
        const uint8_t *p = reinterpret_cast<const uint8_t *>(t.data.data());
        b.insert(b.end(), p, p + t.data.size() * 4); // little-endian host (x86, ARM)
    }
    return b;
}

std::vector<float> tensor_bundle_get(const std::vector<uint8_t> &b, const std::string &want)
{
    if (b.size() < 16 || std::memcmp(b.data(), "MOCAPTNS", 8) != 0) return {};
    size_t pos = 16;
    for (uint32_t i = 0, count = get_u32(b, 12); i < count; ++i) {
        std::string name(reinterpret_cast<const char *>(&b[pos]));
        uint32_t rank = get_u32(b, pos + 32);
        size_t n = 1;
        for (uint32_t d = 0; d < rank; ++d) n *= get_u32(b, pos + 36 + 4 * d);
        pos += 36 + 4 * rank;
        if (name == want) {
            std::vector<float> out(n);
            std::memcpy(out.data(), &b[pos], n * 4);
            return out;
        }
        pos += n * 4;
    }
    return {};
}
