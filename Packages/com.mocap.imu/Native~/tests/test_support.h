// Helpers shared by the GoogleTest suites.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

// A fresh, empty directory under the build tree for this test (named after the running test).
std::string test_temp_dir();
// Path of a file inside test_temp_dir().
std::string test_temp_path(const std::string &name);
std::vector<uint8_t> hex_bytes(const std::string &hex); // whitespace ignored
std::vector<uint8_t> read_file_bytes(const std::string &path);
void write_file_bytes(const std::string &path, const std::vector<uint8_t> &bytes);

// A tensor bundle file of float tensors, in order (mocapctl infer's format, cmd_infer.c).
struct BundleTensor {
    std::string name;
    std::vector<uint32_t> dims;
    std::vector<float> data;
};
std::vector<uint8_t> tensor_bundle_bytes(const std::vector<BundleTensor> &tensors);
// The named tensor's data in a bundle (empty if absent or not a bundle).
std::vector<float> tensor_bundle_get(const std::vector<uint8_t> &bundle, const std::string &name);

// A shell command's exit code and its stdout and stderr together.
struct CommandResult {
    int exit_code = -1;
    std::string output;
};
CommandResult run_shell(const std::string &cmd);
// A Python that imports numpy: $MOCAP_PYTHON, /usr/bin/python3, then python3 on PATH; "" if none.
std::string python_with_numpy();

#if !defined(_WIN32)
// Runs child in a forked process whose files may not grow past max_file_bytes (writes beyond
// fail with EFBIG, as on a full disk; SIGXFSZ ignored) and returns its return value as the exit
// code, or -1 when the fork or the limit failed or the child died. The child must not use gtest
// assertions: it returns a code that says what went wrong.
int exit_code_with_file_size_limit(uint64_t max_file_bytes, const std::function<int()> &child);

// The descriptors opened while action ran and still open after it, and those of them that a
// program started with exec would inherit (no FD_CLOEXEC). Reads /proc/self/fd (Linux).
struct OpenedDescriptors {
    std::vector<int> opened;
    std::vector<int> inheritable;
};
OpenedDescriptors descriptors_opened_by(const std::function<void()> &action);
#endif
