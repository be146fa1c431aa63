// A pseudo-terminal standing in for the HiPNUC receiver, for the suites that stream live bytes
// into a session (test_session.cpp, test_solver.cpp). `link` is a stable symlink to the slave, as
// udev gives /dev/serial/by-id/..., so an unplug + replug brings it back at the same path. The
// engine opens the slave by name, exactly as it opens a real serial port. POSIX only.
#pragma once
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>

#include <pty.h>
#include <termios.h>
#include <unistd.h>

struct FakeReceiver {
    int master = -1;
    std::string link;

    explicit FakeReceiver(const std::string &link_path) : link(link_path) { plug(); }
    ~FakeReceiver() { unplug(); }
    FakeReceiver(const FakeReceiver &) = delete;
    FakeReceiver &operator=(const FakeReceiver &) = delete;

    void plug()
    {
        int slave = -1;
        char name[256];
        struct termios raw;
        cfmakeraw(&raw);
        if (openpty(&master, &slave, name, &raw, nullptr) != 0) throw std::runtime_error("openpty");
        close(slave); // the engine opens it by name
        std::filesystem::remove(link);
        std::filesystem::create_symlink(name, link);
    }

    // Closing the master is what the engine sees when the receiver is pulled out.
    void unplug()
    {
        if (master >= 0) close(master);
        master = -1;
    }

    // false once the line is gone (unplugged, or the engine closed it).
    bool write_all(const uint8_t *data, size_t len)
    {
        while (len > 0) {
            ssize_t n = ::write(master, data, len);
            if (n < 0) {
                if (errno == EINTR) continue;
                if (errno == EAGAIN) {
                    std::this_thread::sleep_for(std::chrono::milliseconds(1));
                    continue;
                }
                return false;
            }
            data += n;
            len -= (size_t)n;
        }
        return true;
    }
};
