// HID transport: no HID receiver exists on the test machine, so these cover argument checks and
// the "not there" paths, which must name the device the user asked for.
#include <gtest/gtest.h>

#include "test_support.h"

#include <string>
#include <thread>
#include <vector>

extern "C" {
#include "error.h"
#include "transport.h"
}

namespace {

// Without hidapi every open reports that clearly; the remaining checks need hidapi.
bool hid_compiled_out(mocap_status status)
{
    if (status != MOCAP_ERR_UNSUPPORTED) return false;
    EXPECT_NE(std::string(mocap_last_error()).find("without hidapi"), std::string::npos)
        << mocap_last_error();
    return true;
}

} // namespace

TEST(TransportHid, AbsentVendorProductIsNotFoundAndNamesTheIds)
{
    transport *t = reinterpret_cast<transport *>(0x1);
    mocap_status status = transport_open_hid("", 0x1234, 0xabcd, &t);
    EXPECT_EQ(t, nullptr);
    if (hid_compiled_out(status)) GTEST_SKIP() << "engine built without hidapi";
    EXPECT_EQ(status, MOCAP_ERR_NOT_FOUND) << mocap_last_error();
    EXPECT_NE(std::string(mocap_last_error()).find("HID device 1234:abcd"), std::string::npos)
        << mocap_last_error();
}

TEST(TransportHid, AbsentHidrawPathIsNotFoundAndNamesThePath)
{
    const std::string path = "/dev/hidraw_mocap_missing";
    transport *t = nullptr;
    mocap_status status = transport_open_hid(path.c_str(), 0, 0, &t);
    EXPECT_EQ(t, nullptr);
    if (hid_compiled_out(status)) GTEST_SKIP() << "engine built without hidapi";
    EXPECT_EQ(status, MOCAP_ERR_NOT_FOUND) << mocap_last_error();
    EXPECT_NE(std::string(mocap_last_error()).find(path), std::string::npos) << mocap_last_error();
}

TEST(TransportHid, RegularFileIsNotAHidDevice)
{
    const std::string file = test_temp_path("fake_hidraw");
    write_file_bytes(file, {0x5a, 0xa5});
    transport *t = nullptr;
    mocap_status status = transport_open_hid(file.c_str(), 0, 0, &t);
    EXPECT_EQ(t, nullptr);
    if (hid_compiled_out(status)) GTEST_SKIP() << "engine built without hidapi";
    EXPECT_EQ(status, MOCAP_ERR_INVALID_ARGUMENT) << mocap_last_error();
    EXPECT_NE(std::string(mocap_last_error()).find(file), std::string::npos) << mocap_last_error();
}

TEST(TransportHid, MissingDeviceSelectionIsRejected)
{
    transport *t = nullptr;
    EXPECT_EQ(transport_open_hid("", 0, 0, &t), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(transport_open_hid(nullptr, 0, 0, &t), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(t, nullptr);
}

TEST(TransportHid, ConcurrentOpensFromSeveralThreadsAllReportNotFound)
{
    // hid_init runs once however many threads open at the same time.
    std::vector<mocap_status> results(4, MOCAP_OK);
    std::vector<std::string> messages(results.size());
    std::vector<std::thread> threads;
    for (size_t i = 0; i < results.size(); ++i) {
        threads.emplace_back([&, i] {
            transport *t = nullptr;
            results[i] = transport_open_hid("", 0x1234, static_cast<uint16_t>(0xab00 + i), &t);
            messages[i] = mocap_last_error();
            if (t) transport_close(t);
        });
    }
    for (auto &th : threads) th.join();
    for (size_t i = 0; i < results.size(); ++i) {
        if (results[i] == MOCAP_ERR_UNSUPPORTED) GTEST_SKIP() << "engine built without hidapi";
        EXPECT_EQ(results[i], MOCAP_ERR_NOT_FOUND) << messages[i];
        char ids[16];
        snprintf(ids, sizeof ids, "1234:ab%02x", static_cast<unsigned>(i));
        EXPECT_NE(messages[i].find(ids), std::string::npos) << messages[i];
    }
}
