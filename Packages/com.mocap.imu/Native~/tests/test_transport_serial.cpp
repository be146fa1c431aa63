// Serial transport against real pseudo-terminals: the test writes into the master, the transport
// reads the slave like it would read /dev/ttyUSB0.
#include <gtest/gtest.h>

#include "test_support.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <grp.h>
#include <pty.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

extern "C" {
#include "error.h"
#include "platform.h"
#include "transport.h"
}

namespace {

struct Pty {
    int master = -1;
    int slave = -1;
    std::string path;

    Pty()
    {
        char name[256] = {0};
        if (openpty(&master, &slave, name, nullptr, nullptr) == 0) path = name;
    }
    ~Pty()
    {
        close_master();
        close_slave();
    }
    Pty(const Pty &) = delete;
    Pty &operator=(const Pty &) = delete;
    bool ok() const { return master >= 0 && slave >= 0 && !path.empty(); }
    void close_master()
    {
        if (master >= 0) ::close(master);
        master = -1;
    }
    void close_slave()
    {
        if (slave >= 0) ::close(slave);
        slave = -1;
    }
};

bool write_all(int fd, const uint8_t *data, size_t size)
{
    while (size > 0) {
        ssize_t n = ::write(fd, data, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return false;
        data += n;
        size -= static_cast<size_t>(n);
    }
    return true;
}

bool write_all(int fd, const std::string &text)
{
    return write_all(fd, reinterpret_cast<const uint8_t *>(text.data()), text.size());
}

// Reads until `want` bytes came or a read failed with anything but a timeout, or ~5 s passed.
std::vector<uint8_t> read_bytes(transport *t, size_t want, size_t chunk = 4096,
                                mocap_status *last = nullptr)
{
    std::vector<uint8_t> out;
    std::vector<uint8_t> buf(chunk);
    const int64_t give_up = mocap_monotonic_ns() + 5000000000LL;
    mocap_status status = MOCAP_OK;
    while (out.size() < want && mocap_monotonic_ns() < give_up) {
        size_t got = 0;
        int64_t when = 0;
        status = transport_read(t, buf.data(), std::min(chunk, want - out.size()), 500, &got, &when);
        if (status == MOCAP_ERR_TIMEOUT) continue;
        if (status != MOCAP_OK) break;
        out.insert(out.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(got));
    }
    if (last) *last = status;
    return out;
}

std::string text_of(const std::vector<uint8_t> &bytes) { return std::string(bytes.begin(), bytes.end()); }

std::string last_error() { return mocap_last_error(); }

// The kernel's struct termios2, to read back a custom rate (see serial_posix.c for why it is
// declared by hand).
struct KernelTermios2 {
    uint32_t c_iflag, c_oflag, c_cflag, c_lflag;
    unsigned char c_line;
    unsigned char c_cc[19];
    uint32_t c_ispeed, c_ospeed;
};

} // namespace

TEST(SerialPty, ReadsExactlyTheBytesWrittenToTheMaster)
{
    Pty pty;
    ASSERT_TRUE(pty.ok());
    transport *t = nullptr;
    ASSERT_EQ(transport_open_serial(pty.path.c_str(), 115200, &t), MOCAP_OK) << last_error();
    EXPECT_NE(std::string(t->description).find(pty.path), std::string::npos);

    // Every byte value, including the ones a cooked tty would eat or translate
    // (CR, XON/XOFF, ^C, ^D, DEL, 0xFF).
    std::vector<uint8_t> sent(256);
    for (int i = 0; i < 256; ++i) sent[static_cast<size_t>(i)] = static_cast<uint8_t>(255 - i);
    const int64_t before = mocap_monotonic_ns();
    ASSERT_TRUE(write_all(pty.master, sent.data(), sent.size()));

    std::vector<uint8_t> buf(512);
    size_t got = 0;
    int64_t receive_ns = 0;
    ASSERT_EQ(transport_read(t, buf.data(), buf.size(), 2000, &got, &receive_ns), MOCAP_OK)
        << last_error();
    const int64_t after = mocap_monotonic_ns();
    EXPECT_GE(receive_ns, before);
    EXPECT_LE(receive_ns, after);
    std::vector<uint8_t> received(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(got));
    std::vector<uint8_t> rest = read_bytes(t, sent.size() - got);
    received.insert(received.end(), rest.begin(), rest.end());
    EXPECT_EQ(received, sent);
    transport_close(t);
}

TEST(SerialPty, SmallReadCapacitySplitsWithoutLoss)
{
    Pty pty;
    ASSERT_TRUE(pty.ok());
    transport *t = nullptr;
    ASSERT_EQ(transport_open_serial(pty.path.c_str(), 921600, &t), MOCAP_OK) << last_error();
    ASSERT_TRUE(write_all(pty.master, "0123456789abcdef"));
    uint8_t buf[5];
    size_t got = 0;
    ASSERT_EQ(transport_read(t, buf, 3, 2000, &got, nullptr), MOCAP_OK) << last_error();
    ASSERT_EQ(got, 3u);
    EXPECT_EQ(std::string(reinterpret_cast<char *>(buf), 3), "012");
    EXPECT_EQ(text_of(read_bytes(t, 13, 5)), "3456789abcdef");
    transport_close(t);
}

TEST(SerialPty, PortIsNotInheritedByStartedPrograms)
{
    Pty pty;
    ASSERT_TRUE(pty.ok());
    transport *t = nullptr;
    OpenedDescriptors d = descriptors_opened_by([&] {
        ASSERT_EQ(transport_open_serial(pty.path.c_str(), 115200, &t), MOCAP_OK) << last_error();
    });
    ASSERT_NE(t, nullptr);
    EXPECT_GE(d.opened.size(), 1u);
    // A program holding the port open would keep the device busy after we close it.
    EXPECT_TRUE(d.inheritable.empty());
    transport_close(t);
}

TEST(SerialPty, PortIsRaw8N1WithoutFlowControl)
{
    Pty pty;
    ASSERT_TRUE(pty.ok());
    transport *t = nullptr;
    ASSERT_EQ(transport_open_serial(pty.path.c_str(), 460800, &t), MOCAP_OK) << last_error();
    // Settings belong to the tty, so the test's own slave fd sees what the transport applied.
    struct termios tio;
    ASSERT_EQ(tcgetattr(pty.slave, &tio), 0);
    EXPECT_EQ(tio.c_cflag & CSIZE, static_cast<tcflag_t>(CS8));
    EXPECT_EQ(tio.c_cflag & (PARENB | CSTOPB | CRTSCTS), 0u);
    EXPECT_NE(tio.c_cflag & CLOCAL, 0u);
    EXPECT_NE(tio.c_cflag & CREAD, 0u);
    EXPECT_EQ(tio.c_lflag & (ICANON | ECHO | ISIG | IEXTEN), 0u);
    EXPECT_EQ(tio.c_iflag & (IXON | IXOFF | ICRNL | INLCR | IGNCR | ISTRIP | PARMRK), 0u);
    EXPECT_EQ(tio.c_oflag & OPOST, 0u);
    EXPECT_EQ(cfgetospeed(&tio), static_cast<speed_t>(B460800));
    transport_close(t);
}

TEST(SerialPty, OneMegabyteFromAWriterThreadArrivesIntact)
{
    Pty pty;
    ASSERT_TRUE(pty.ok());
    transport *t = nullptr;
    ASSERT_EQ(transport_open_serial(pty.path.c_str(), 921600, &t), MOCAP_OK) << last_error();

    std::vector<uint8_t> sent(1 << 20);
    std::mt19937 rng(1234);
    for (auto &b : sent) b = static_cast<uint8_t>(rng());
    std::atomic<bool> writer_ok{true};
    std::thread writer([&] {
        std::mt19937 sizes(99);
        size_t offset = 0;
        while (offset < sent.size()) {
            size_t n = std::min<size_t>(1 + sizes() % 4096, sent.size() - offset);
            if (!write_all(pty.master, sent.data() + offset, n)) {
                writer_ok = false;
                return;
            }
            offset += n;
        }
    });
    mocap_status last = MOCAP_OK;
    std::vector<uint8_t> received = read_bytes(t, sent.size(), 1500, &last);
    writer.join();
    EXPECT_TRUE(writer_ok);
    EXPECT_EQ(last, MOCAP_OK) << last_error();
    ASSERT_EQ(received.size(), sent.size());
    EXPECT_TRUE(received == sent);
    transport_close(t);
}

TEST(SerialPty, StandardBaudRatesAreApplied)
{
    const struct {
        uint32_t baud;
        speed_t code;
    } rates[] = {{115200, B115200}, {460800, B460800}, {921600, B921600}};
    for (const auto &rate : rates) {
        SCOPED_TRACE(rate.baud);
        Pty pty;
        ASSERT_TRUE(pty.ok());
        transport *t = nullptr;
        ASSERT_EQ(transport_open_serial(pty.path.c_str(), rate.baud, &t), MOCAP_OK) << last_error();
        struct termios tio;
        ASSERT_EQ(tcgetattr(pty.slave, &tio), 0);
        EXPECT_EQ(cfgetospeed(&tio), rate.code);
        ASSERT_TRUE(write_all(pty.master, "rate"));
        EXPECT_EQ(text_of(read_bytes(t, 4)), "rate");
        transport_close(t);
    }
}

// Linux keeps any BOTHER rate on a pty (it has no clock divider to round to), so a non-standard
// rate must open and read back exactly through termios2.
TEST(SerialPty, NonStandardBaudRateUsesTermios2)
{
    Pty pty;
    ASSERT_TRUE(pty.ok());
    transport *t = nullptr;
    ASSERT_EQ(transport_open_serial(pty.path.c_str(), 250000, &t), MOCAP_OK) << last_error();
    KernelTermios2 t2;
    std::memset(&t2, 0, sizeof t2);
    ASSERT_EQ(ioctl(pty.slave, _IOR('T', 0x2A, KernelTermios2), &t2), 0) << std::strerror(errno);
    EXPECT_EQ(t2.c_ospeed, 250000u);
    // Raw settings survive the termios2 call.
    EXPECT_EQ(t2.c_lflag & static_cast<uint32_t>(ICANON | ECHO), 0u);
    ASSERT_TRUE(write_all(pty.master, "custom"));
    EXPECT_EQ(text_of(read_bytes(t, 6)), "custom");
    transport_close(t);
}

TEST(SerialPty, ReadTimesOutWhenNothingArrives)
{
    Pty pty;
    ASSERT_TRUE(pty.ok());
    transport *t = nullptr;
    ASSERT_EQ(transport_open_serial(pty.path.c_str(), 115200, &t), MOCAP_OK) << last_error();
    // The slave has never seen a byte and the test closes its own slave fd: neither is a hangup.
    pty.close_slave();
    uint8_t buf[16];
    for (int round = 0; round < 2; ++round) {
        size_t got = 99;
        const int64_t start = mocap_monotonic_ns();
        mocap_status status = transport_read(t, buf, sizeof buf, 200, &got, nullptr);
        const int64_t elapsed = mocap_monotonic_ns() - start;
        EXPECT_EQ(status, MOCAP_ERR_TIMEOUT) << last_error();
        EXPECT_EQ(got, 0u);
        EXPECT_GE(elapsed, 100LL * 1000000LL);
        EXPECT_LT(elapsed, 5LL * 1000000000LL);
    }
    // Still alive afterwards.
    ASSERT_TRUE(write_all(pty.master, "late"));
    EXPECT_EQ(text_of(read_bytes(t, 4)), "late");
    transport_close(t);
}

TEST(SerialPty, ClosingTheMasterIsAnUnplugReportedWithinOneSecond)
{
    Pty pty;
    ASSERT_TRUE(pty.ok());
    transport *t = nullptr;
    ASSERT_EQ(transport_open_serial(pty.path.c_str(), 115200, &t), MOCAP_OK) << last_error();
    ASSERT_TRUE(write_all(pty.master, "hi"));
    EXPECT_EQ(text_of(read_bytes(t, 2)), "hi");

    std::atomic<int64_t> closed_at{0};
    std::thread unplug([&] {
        mocap_sleep_ms(150);
        closed_at = mocap_monotonic_ns();
        pty.close_master();
    });
    uint8_t buf[64];
    mocap_status status = MOCAP_ERR_TIMEOUT;
    const int64_t give_up = mocap_monotonic_ns() + 5000000000LL;
    while (status == MOCAP_ERR_TIMEOUT && mocap_monotonic_ns() < give_up) {
        size_t got = 0;
        // Long read timeout on purpose: the hangup must end the wait, not the timeout.
        status = transport_read(t, buf, sizeof buf, 3000, &got, nullptr);
    }
    const int64_t returned_at = mocap_monotonic_ns();
    unplug.join();
    ASSERT_EQ(status, MOCAP_ERR_DISCONNECTED) << mocap_status_name(status) << " " << last_error();
    EXPECT_NE(last_error().find(pty.path), std::string::npos) << last_error();
    EXPECT_LT(returned_at - closed_at.load(), 1000000000LL);

    // The handle is gone: later reads report the disconnect at once instead of waiting.
    size_t got = 0;
    const int64_t start = mocap_monotonic_ns();
    EXPECT_EQ(transport_read(t, buf, sizeof buf, 2000, &got, nullptr), MOCAP_ERR_DISCONNECTED);
    EXPECT_LT(mocap_monotonic_ns() - start, 1000000000LL);
    transport_close(t);
}

TEST(SerialPty, ReplugThroughASymlinkReopensTheNewDevice)
{
    const std::string link = test_temp_dir() + "/usb-HiPNUC_receiver-if00";
    auto first = std::make_unique<Pty>();
    ASSERT_TRUE(first->ok());
    ASSERT_EQ(symlink(first->path.c_str(), link.c_str()), 0) << std::strerror(errno);

    transport *t = nullptr;
    ASSERT_EQ(transport_open_serial(link.c_str(), 921600, &t), MOCAP_OK) << last_error();
    ASSERT_TRUE(write_all(first->master, "before"));
    EXPECT_EQ(text_of(read_bytes(t, 6)), "before");

    // Unplug: udev removes the by-id link and the device disappears.
    ASSERT_EQ(unlink(link.c_str()), 0);
    first->close_master();
    mocap_status status = MOCAP_OK;
    read_bytes(t, 1, 64, &status);
    ASSERT_EQ(status, MOCAP_ERR_DISCONNECTED) << last_error();
    first.reset();

    // While unplugged, reopen fails with the path in the message.
    EXPECT_EQ(transport_reopen(t), MOCAP_ERR_NOT_FOUND);
    EXPECT_NE(last_error().find(link), std::string::npos) << last_error();
    uint8_t buf[8];
    size_t got = 0;
    EXPECT_EQ(transport_read(t, buf, sizeof buf, 10, &got, nullptr), MOCAP_ERR_DISCONNECTED);

    // Replug: a new device, the link points at it again.
    Pty second;
    ASSERT_TRUE(second.ok());
    ASSERT_EQ(symlink(second.path.c_str(), link.c_str()), 0) << std::strerror(errno);
    ASSERT_EQ(transport_reopen(t), MOCAP_OK) << last_error();
    ASSERT_TRUE(write_all(second.master, "after replug"));
    EXPECT_EQ(text_of(read_bytes(t, 12)), "after replug");
    // Settings were reapplied to the new device.
    struct termios tio;
    ASSERT_EQ(tcgetattr(second.slave, &tio), 0);
    EXPECT_EQ(cfgetospeed(&tio), static_cast<speed_t>(B921600));
    EXPECT_EQ(tio.c_lflag & ICANON, 0u);
    transport_close(t);
}

TEST(SerialErrors, MissingPortIsNotFoundAndNamed)
{
    const std::string path = "/dev/ttyMOCAP_does_not_exist";
    transport *t = reinterpret_cast<transport *>(0x1);
    EXPECT_EQ(transport_open_serial(path.c_str(), 115200, &t), MOCAP_ERR_NOT_FOUND);
    EXPECT_EQ(t, nullptr);
    EXPECT_NE(last_error().find(path), std::string::npos) << last_error();
}

TEST(SerialErrors, RegularFileAndDirectoryAreNotSerialPorts)
{
    const std::string file = test_temp_path("not_a_port.bin");
    write_file_bytes(file, {1, 2, 3});
    transport *t = nullptr;
    EXPECT_EQ(transport_open_serial(file.c_str(), 115200, &t), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(t, nullptr);
    EXPECT_NE(last_error().find("not a serial port"), std::string::npos) << last_error();
    EXPECT_NE(last_error().find(file), std::string::npos) << last_error();
    // The file was not opened for writing behind the caller's back.
    EXPECT_EQ(read_file_bytes(file), (std::vector<uint8_t>{1, 2, 3}));

    const std::string dir = test_temp_dir();
    EXPECT_EQ(transport_open_serial(dir.c_str(), 115200, &t), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(last_error().find("not a serial port"), std::string::npos) << last_error();
}

TEST(SerialErrors, NonTerminalCharacterDeviceIsNotASerialPort)
{
    transport *t = nullptr;
    EXPECT_EQ(transport_open_serial("/dev/null", 115200, &t), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(last_error().find("/dev/null is not a serial port"), std::string::npos) << last_error();
}

TEST(SerialErrors, InvalidArgumentsAreRejected)
{
    transport *t = nullptr;
    EXPECT_EQ(transport_open_serial(nullptr, 115200, &t), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(transport_open_serial("", 115200, &t), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(transport_open_serial("/dev/ttyUSB0", 0, &t), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(transport_open_serial("/dev/ttyUSB0", 115200, nullptr), MOCAP_ERR_INVALID_ARGUMENT);
    std::string long_path(MOCAP_PATH_MAX + 10, 'a');
    EXPECT_EQ(transport_open_serial(long_path.c_str(), 115200, &t), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(t, nullptr);
}

TEST(SerialErrors, SecondOpenOfTheSamePortIsBusy)
{
    Pty pty;
    ASSERT_TRUE(pty.ok());
    transport *first = nullptr;
    ASSERT_EQ(transport_open_serial(pty.path.c_str(), 115200, &first), MOCAP_OK) << last_error();
    transport *second = nullptr;
    EXPECT_EQ(transport_open_serial(pty.path.c_str(), 115200, &second), MOCAP_ERR_IO);
    EXPECT_EQ(second, nullptr);
    EXPECT_NE(last_error().find("busy"), std::string::npos) << last_error();
    EXPECT_NE(last_error().find(pty.path), std::string::npos) << last_error();
    transport_close(first);
    ASSERT_EQ(transport_open_serial(pty.path.c_str(), 115200, &second), MOCAP_OK) << last_error();
    transport_close(second);
}

TEST(SerialErrors, PermissionDeniedNamesThePortAndTheFix)
{
    Pty pty;
    ASSERT_TRUE(pty.ok());
    ASSERT_EQ(fchown(pty.slave, getuid(), getgid()), 0);
    ASSERT_EQ(fchmod(pty.slave, 0600), 0);
    int fds[2];
    ASSERT_EQ(pipe(fds), 0);
    pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        ::close(fds[0]);
        std::string report;
        if (setgroups(0, nullptr) != 0 || setgid(65534) != 0 || setuid(65534) != 0) {
            report = "SKIP cannot drop privileges: " + std::string(std::strerror(errno));
        } else {
            transport *t = nullptr;
            mocap_status status = transport_open_serial(pty.path.c_str(), 115200, &t);
            report = std::to_string(status) + " " + mocap_last_error();
            if (t) transport_close(t);
        }
        write_all(fds[1], report);
        ::close(fds[1]);
        _exit(0);
    }
    ::close(fds[1]);
    std::string report;
    char chunk[256];
    for (;;) {
        ssize_t n = ::read(fds[0], chunk, sizeof chunk);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        report.append(chunk, static_cast<size_t>(n));
    }
    ::close(fds[0]);
    int wstatus = 0;
    ASSERT_EQ(waitpid(child, &wstatus, 0), child);
    ASSERT_TRUE(WIFEXITED(wstatus));
    if (report.rfind("SKIP", 0) == 0) GTEST_SKIP() << report;
    ASSERT_FALSE(report.empty());
    const std::string expected_status = std::to_string(MOCAP_ERR_PERMISSION) + " ";
    EXPECT_EQ(report.rfind(expected_status, 0), 0u) << report;
    EXPECT_NE(report.find(pty.path), std::string::npos) << report;
    EXPECT_NE(report.find("dialout"), std::string::npos) << report;
}

TEST(SerialPty, ReaderThreadStopsPromptlyWhenAsked)
{
    Pty pty;
    ASSERT_TRUE(pty.ok());
    transport *t = nullptr;
    ASSERT_EQ(transport_open_serial(pty.path.c_str(), 115200, &t), MOCAP_OK) << last_error();
    std::atomic<bool> stop{false};
    std::atomic<int> timeouts{0};
    std::atomic<int> unexpected{0};
    std::atomic<size_t> bytes{0};
    std::thread reader([&] {
        uint8_t buf[256];
        while (!stop.load()) {
            size_t got = 0;
            mocap_status status = transport_read(t, buf, sizeof buf, 100, &got, nullptr);
            if (status == MOCAP_ERR_TIMEOUT) ++timeouts;
            else if (status == MOCAP_OK) bytes += got;
            else ++unexpected;
        }
    });
    ASSERT_TRUE(write_all(pty.master, "x"));
    mocap_sleep_ms(350);
    const int64_t asked = mocap_monotonic_ns();
    stop = true;
    reader.join();
    const int64_t stopped = mocap_monotonic_ns();
    EXPECT_LT(stopped - asked, 2000000000LL);
    EXPECT_GE(timeouts.load(), 1);
    EXPECT_EQ(bytes.load(), 1u);
    EXPECT_EQ(unexpected.load(), 0);
    transport_close(t);
}
