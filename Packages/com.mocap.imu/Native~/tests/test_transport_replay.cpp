// Replay transport: fast replay returns the records with their recorded times, realtime replay
// paces them on the live clock, small read buffers split records without losing bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "capture_file.h"
#include "test_support.h"

// platform.h uses C11 _Atomic, which C++ cannot include: declare the two clock functions used.
extern "C" {
int64_t mocap_monotonic_ns(void);
void mocap_sleep_ms(int ms);
}
#include "transport.h"

namespace {

struct Rec {
    int64_t ns;
    std::vector<uint8_t> bytes;
};

std::vector<Rec> make_records(uint32_t seed, size_t count, size_t max_len, int64_t t0,
                              int64_t step_ns)
{
    std::mt19937 rng(seed);
    std::vector<Rec> recs;
    for (size_t i = 0; i < count; i++) {
        Rec rec{t0 + static_cast<int64_t>(i) * step_ns, std::vector<uint8_t>(1 + rng() % max_len)};
        for (auto &b : rec.bytes) b = static_cast<uint8_t>(rng());
        recs.push_back(std::move(rec));
    }
    return recs;
}

void write_capture(const std::string &path, const std::vector<Rec> &recs)
{
    capture_writer *w = nullptr;
    ASSERT_EQ(capture_writer_open(path.c_str(), &w), MOCAP_OK) << mocap_last_error();
    for (const auto &rec : recs)
        ASSERT_EQ(capture_writer_append(w, rec.ns, rec.bytes.data(), rec.bytes.size()), MOCAP_OK);
    ASSERT_EQ(capture_writer_close(w), MOCAP_OK);
}

} // namespace

TEST(TransportReplay, FastReplayReturnsRecordsWithOriginalTimesThenEnd)
{
    const std::string path = test_temp_path("fast.mcap");
    auto recs = make_records(3, 500, CAPTURE_MAX_RECORD, 123456789, 2500000);
    write_capture(path, recs);
    transport *t = nullptr;
    ASSERT_EQ(transport_open_replay(path.c_str(), 0, 1.0, &t), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(std::string(t->description), "capture file " + path);
    std::vector<uint8_t> buf(CAPTURE_MAX_RECORD);
    for (size_t i = 0; i < recs.size(); i++) {
        size_t got = 0;
        int64_t ns = 0;
        ASSERT_EQ(transport_read(t, buf.data(), buf.size(), 0, &got, &ns), MOCAP_OK) << i;
        ASSERT_EQ(ns, recs[i].ns) << i;
        ASSERT_EQ(std::vector<uint8_t>(buf.begin(), buf.begin() + got), recs[i].bytes) << i;
    }
    size_t got = 99;
    int64_t ns;
    EXPECT_EQ(transport_read(t, buf.data(), buf.size(), 0, &got, &ns), MOCAP_ERR_END_OF_STREAM);
    EXPECT_EQ(got, 0u);
    EXPECT_EQ(transport_read(t, buf.data(), buf.size(), 0, &got, &ns), MOCAP_ERR_END_OF_STREAM);
    EXPECT_EQ(transport_reopen(t), MOCAP_ERR_END_OF_STREAM);
    transport_close(t);
}

TEST(TransportReplay, RealtimeReplayIsPacedAndKeepsRecordedTimes)
{
    const std::string path = test_temp_path("realtime.mcap");
    // 101 records 10 ms apart: one second of capture, replayed at speed 10.
    auto recs = make_records(5, 101, 64, 77000000000LL, 10000000);
    write_capture(path, recs);
    const int64_t before_open = mocap_monotonic_ns();
    transport *t = nullptr;
    ASSERT_EQ(transport_open_replay(path.c_str(), 1, 10.0, &t), MOCAP_OK) << mocap_last_error();
    const int64_t after_open = mocap_monotonic_ns();
    std::vector<uint8_t> buf(CAPTURE_MAX_RECORD);
    std::vector<int64_t> stamps;
    mocap_status st = MOCAP_OK;
    while (mocap_monotonic_ns() - before_open < 20000000000LL) {
        size_t got = 0;
        int64_t ns = 0;
        st = transport_read(t, buf.data(), buf.size(), 3, &got, &ns);
        if (st == MOCAP_ERR_TIMEOUT) {
            EXPECT_EQ(got, 0u);
            continue;
        }
        if (st != MOCAP_OK) break;
        // Never delivered before it is due: the recorded spacing divided by the speed.
        if (!stamps.empty()) {
            ASSERT_GE(mocap_monotonic_ns() - before_open, (ns - recs[0].ns) / 10);
        }
        size_t i = stamps.size();
        ASSERT_LT(i, recs.size());
        ASSERT_EQ(std::vector<uint8_t>(buf.begin(), buf.begin() + got), recs[i].bytes);
        stamps.push_back(ns);
    }
    const double elapsed_s = (mocap_monotonic_ns() - before_open) * 1e-9;
    EXPECT_EQ(st, MOCAP_ERR_END_OF_STREAM);
    ASSERT_EQ(stamps.size(), recs.size());
    EXPECT_GE(elapsed_s, 0.05);
    // The timestamps are the recorded ones: a replay's timeline does not depend on its pace.
    (void)after_open;
    for (size_t i = 0; i < stamps.size(); i++) EXPECT_EQ(stamps[i], recs[i].ns) << i;
    transport_close(t);
}

TEST(TransportReplay, RealtimeReadTimesOutWhileTheNextRecordIsNotDue)
{
    const std::string path = test_temp_path("gap.mcap");
    auto recs = make_records(9, 2, 16, 0, 30000000000LL); // 30 s apart
    write_capture(path, recs);
    transport *t = nullptr;
    ASSERT_EQ(transport_open_replay(path.c_str(), 1, 1.0, &t), MOCAP_OK);
    std::vector<uint8_t> buf(64);
    size_t got = 0;
    int64_t ns = 0;
    ASSERT_EQ(transport_read(t, buf.data(), buf.size(), 5, &got, &ns), MOCAP_OK);
    EXPECT_EQ(got, recs[0].bytes.size());
    for (int i = 0; i < 3; i++) {
        got = 77;
        EXPECT_EQ(transport_read(t, buf.data(), buf.size(), 5, &got, &ns), MOCAP_ERR_TIMEOUT);
        EXPECT_EQ(got, 0u);
    }
    transport_close(t);
}

// Times from either end of int64 (a damaged or hand-made capture): the pacing arithmetic must
// not overflow (UBSan checks it); a record ~580 years after the first is simply not due yet, and
// one before the first is due at once.
TEST(TransportReplay, WildTimestampsDoNotOverflowThePacing)
{
    const std::string path = test_temp_path("wild.mcap");
    std::vector<Rec> recs = make_records(10, 3, 16, 0, 0);
    recs[0].ns = -9000000000000000000LL;
    recs[1].ns = -9100000000000000000LL;  // before the first record
    recs[2].ns = 9000000000000000000LL;
    write_capture(path, recs);
    transport *t = nullptr;
    ASSERT_EQ(transport_open_replay(path.c_str(), 1, 1.0, &t), MOCAP_OK);
    std::vector<uint8_t> buf(64);
    size_t got = 0;
    int64_t ns = 0;
    ASSERT_EQ(transport_read(t, buf.data(), buf.size(), 5, &got, &ns), MOCAP_OK);
    EXPECT_EQ(ns, recs[0].ns);
    ASSERT_EQ(transport_read(t, buf.data(), buf.size(), 5, &got, &ns), MOCAP_OK);
    EXPECT_EQ(ns, recs[1].ns);
    EXPECT_EQ(transport_read(t, buf.data(), buf.size(), 5, &got, &ns), MOCAP_ERR_TIMEOUT);
    EXPECT_EQ(got, 0u);
    transport_close(t);
}

TEST(TransportReplay, SmallBufferSplitsRecordsWithoutLosingBytes)
{
    const std::string path = test_temp_path("small_cap.mcap");
    auto recs = make_records(13, 300, 200, 1000, 1000000);
    write_capture(path, recs);
    for (int realtime : {0, 1}) {
        transport *t = nullptr;
        ASSERT_EQ(transport_open_replay(path.c_str(), realtime, 1000.0, &t), MOCAP_OK);
        std::vector<Rec> pieces;
        uint8_t buf[7];
        for (;;) {
            size_t got = 0;
            int64_t ns = 0;
            mocap_status st = transport_read(t, buf, sizeof buf, 50, &got, &ns);
            if (st == MOCAP_ERR_TIMEOUT) continue;
            if (st != MOCAP_OK) {
                EXPECT_EQ(st, MOCAP_ERR_END_OF_STREAM);
                break;
            }
            ASSERT_GT(got, 0u);
            ASSERT_LE(got, sizeof buf);
            // Pieces of one record share its receive time: regroup them by it.
            if (pieces.empty() || pieces.back().ns != ns) pieces.push_back(Rec{ns, {}});
            pieces.back().bytes.insert(pieces.back().bytes.end(), buf, buf + got);
        }
        ASSERT_EQ(pieces.size(), recs.size()) << "realtime " << realtime;
        for (size_t i = 0; i < recs.size(); i++) {
            ASSERT_EQ(pieces[i].bytes, recs[i].bytes) << i;
            if (!realtime) {
                EXPECT_EQ(pieces[i].ns, recs[i].ns);
            }
        }
        transport_close(t);
    }
}

TEST(TransportReplay, OpenErrorsNameTheFile)
{
    transport *t = nullptr;
    const std::string missing = test_temp_path("missing.mcap");
    EXPECT_EQ(transport_open_replay(missing.c_str(), 0, 1.0, &t), MOCAP_ERR_NOT_FOUND);
    EXPECT_EQ(t, nullptr);
    EXPECT_NE(std::string(mocap_last_error()).find(missing), std::string::npos);

    const std::string text = test_temp_path("text.mcap");
    write_file_bytes(text, std::vector<uint8_t>(100, 'x'));
    EXPECT_EQ(transport_open_replay(text.c_str(), 0, 1.0, &t), MOCAP_ERR_FORMAT);
    EXPECT_NE(std::string(mocap_last_error()).find("not a mocap capture file"), std::string::npos);

    const std::string path = test_temp_path("ok.mcap");
    write_capture(path, make_records(1, 3, 10, 0, 1000));
    EXPECT_EQ(transport_open_replay(path.c_str(), 1, 0.0, &t), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(transport_open_replay(path.c_str(), 1, NAN, &t), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(t, nullptr);
}

// Pacing starts at the first read (the session's start), not at open: a UI that opens, sets up
// and starts a few hundred ms later must not get those records in one burst.
TEST(TransportReplay, RealtimePacingStartsAtTheFirstReadNotAtOpen)
{
    const std::string path = test_temp_path("late_start.mcap");
    auto recs = make_records(11, 41, 32, 5000000000LL, 10000000); // 0.4 s, 10 ms apart
    write_capture(path, recs);
    transport *t = nullptr;
    ASSERT_EQ(transport_open_replay(path.c_str(), 1, 1.0, &t), MOCAP_OK) << mocap_last_error();
    mocap_sleep_ms(300);
    std::vector<uint8_t> buf(CAPTURE_MAX_RECORD);
    int64_t first_read = 0;
    size_t delivered = 0;
    const int64_t give_up = mocap_monotonic_ns() + 10000000000LL;
    while (delivered < recs.size() && mocap_monotonic_ns() < give_up) {
        size_t got = 0;
        int64_t ns = 0;
        const int64_t asked = mocap_monotonic_ns();
        mocap_status st = transport_read(t, buf.data(), buf.size(), 5, &got, &ns);
        if (st == MOCAP_ERR_TIMEOUT) continue;
        ASSERT_EQ(st, MOCAP_OK) << mocap_last_error();
        if (delivered == 0) first_read = asked;
        ASSERT_EQ(ns, recs[delivered].ns);
        // Due at its recorded offset after the first read; 1 ms of slack for the clock reads.
        ASSERT_GE(mocap_monotonic_ns() - first_read, (ns - recs[0].ns) - 1000000) << delivered;
        ++delivered;
    }
    EXPECT_EQ(delivered, recs.size());
    transport_close(t);
}
