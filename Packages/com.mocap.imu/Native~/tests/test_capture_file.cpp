// Capture files: exact round trip, chunking by size and by age, crash safety under SIGKILL,
// recovery from damaged chunks and truncated tails, and clear errors (docs/capture-format.md).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "capture_file.h"
#include "crc.h"
#include "error.h"
#include "test_support.h"

// platform.h uses C11 _Atomic, which C++ cannot include: declare the two clock functions used.
extern "C" {
int64_t mocap_monotonic_ns(void);
void mocap_sleep_ms(int ms);
}

#if !defined(_WIN32)
#include <csignal>
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#endif

namespace {

struct Rec {
    int64_t ns;
    std::vector<uint8_t> bytes;
    bool operator==(const Rec &o) const { return ns == o.ns && bytes == o.bytes; }
};

struct ReadResult {
    mocap_status open_status = MOCAP_OK;
    mocap_status end_status = MOCAP_OK; // status that stopped the iteration
    std::vector<Rec> recs;
    int tail = -1;
    uint64_t chunks = 0;
    uint64_t skipped = 0;
    std::string error;
};

ReadResult read_capture(const std::string &path)
{
    ReadResult res;
    capture_reader *r = nullptr;
    res.open_status = capture_reader_open(path.c_str(), &r);
    if (res.open_status != MOCAP_OK) {
        res.error = mocap_last_error();
        EXPECT_EQ(r, nullptr);
        return res;
    }
    for (;;) {
        int64_t ns;
        const uint8_t *data;
        size_t len;
        mocap_status st = capture_reader_next(r, &ns, &data, &len);
        if (st != MOCAP_OK) {
            res.end_status = st;
            if (st != MOCAP_ERR_END_OF_STREAM) res.error = mocap_last_error();
            break;
        }
        res.recs.push_back(Rec{ns, std::vector<uint8_t>(data, data + len)});
    }
    res.tail = capture_reader_tail(r);
    res.chunks = capture_reader_chunks(r);
    res.skipped = capture_reader_skipped(r);
    capture_reader_close(r);
    return res;
}

std::vector<Rec> random_records(uint32_t seed, size_t count, size_t max_len, int64_t t0)
{
    std::mt19937 rng(seed);
    std::vector<Rec> recs;
    int64_t ns = t0;
    for (size_t i = 0; i < count; i++) {
        size_t len = 1 + rng() % max_len;
        Rec rec{ns, std::vector<uint8_t>(len)};
        for (auto &b : rec.bytes) b = static_cast<uint8_t>(rng());
        recs.push_back(std::move(rec));
        ns += static_cast<int64_t>(rng() % 3000000); // 0..3 ms, repeats allowed
    }
    return recs;
}

// Writes groups of records, one chunk per group; returns the file offset where each chunk
// starts (plus the file size at the end).
std::vector<uint64_t> write_chunks(const std::string &path,
                                   const std::vector<std::vector<Rec>> &groups)
{
    std::vector<uint64_t> offsets;
    capture_writer *w = nullptr;
    EXPECT_EQ(capture_writer_open(path.c_str(), &w), MOCAP_OK) << mocap_last_error();
    if (!w) return offsets;
    offsets.push_back(capture_writer_bytes_written(w));
    for (const auto &group : groups) {
        for (const auto &rec : group)
            EXPECT_EQ(capture_writer_append(w, rec.ns, rec.bytes.data(), rec.bytes.size()),
                      MOCAP_OK);
        EXPECT_EQ(capture_writer_flush(w), MOCAP_OK);
        offsets.push_back(capture_writer_bytes_written(w));
    }
    EXPECT_EQ(capture_writer_close(w), MOCAP_OK);
    return offsets;
}

std::vector<Rec> concat(const std::vector<std::vector<Rec>> &groups, size_t skip_group = SIZE_MAX)
{
    std::vector<Rec> all;
    for (size_t g = 0; g < groups.size(); g++)
        if (g != skip_group) all.insert(all.end(), groups[g].begin(), groups[g].end());
    return all;
}

std::vector<std::vector<Rec>> make_groups(uint32_t seed, size_t groups, size_t per_group,
                                          size_t max_len)
{
    std::vector<Rec> recs = random_records(seed, groups * per_group, max_len, 1000000000LL);
    std::vector<std::vector<Rec>> out(groups);
    for (size_t i = 0; i < recs.size(); i++) out[i / per_group].push_back(recs[i]);
    return out;
}

bool contains(const std::string &text, const std::string &part)
{
    return text.find(part) != std::string::npos;
}

// A stretch of n fake chunk headers that each look plausible (magic, a 64 KiB payload, one
// record) so that the reader must read and CRC a whole payload before rejecting each.
std::vector<uint8_t> fake_chunk_headers(size_t n)
{
    std::vector<uint8_t> bytes;
    for (size_t i = 0; i < n; i++) {
        uint8_t h[36] = {'M', 'C', 'H', 'K'};
        const uint32_t payload = 65536, count = 1;
        std::memcpy(h + 4, &payload, 4);  // little-endian host, as the format
        std::memcpy(h + 8, &count, 4);
        h[20] = static_cast<uint8_t>(i);  // not all alike
        bytes.insert(bytes.end(), h, h + sizeof h);
    }
    return bytes;
}

// good chunk 0, n fake headers, good chunks 1.. (written by the real writer, then spliced).
std::string capture_with_fake_headers(const std::string &name, size_t n,
                                      const std::vector<std::vector<Rec>> &groups)
{
    const std::string whole = test_temp_path(name + ".whole");
    auto offsets = write_chunks(whole, groups);
    std::vector<uint8_t> good = read_file_bytes(whole), spliced(good.begin(), good.begin() + offsets[1]);
    std::vector<uint8_t> fakes = fake_chunk_headers(n);
    spliced.insert(spliced.end(), fakes.begin(), fakes.end());
    spliced.insert(spliced.end(), good.begin() + offsets[1], good.end());
    const std::string path = test_temp_path(name);
    write_file_bytes(path, spliced);
    return path;
}

} // namespace

TEST(CaptureFile, RoundTripOfThousandsOfRandomRecords)
{
    const std::string path = test_temp_path("round_trip.mcap");
    std::vector<Rec> recs = random_records(42, 4000, CAPTURE_MAX_RECORD, -5000000000LL);
    capture_writer *w = nullptr;
    ASSERT_EQ(capture_writer_open(path.c_str(), &w), MOCAP_OK) << mocap_last_error();
    for (const auto &rec : recs)
        ASSERT_EQ(capture_writer_append(w, rec.ns, rec.bytes.data(), rec.bytes.size()), MOCAP_OK);
    EXPECT_EQ(capture_writer_bytes_lost(w), 0u);
    uint64_t before_close = capture_writer_bytes_written(w);
    ASSERT_EQ(capture_writer_close(w), MOCAP_OK);
    EXPECT_GT(read_file_bytes(path).size(), before_close); // close wrote the last chunk

    ReadResult res = read_capture(path);
    ASSERT_EQ(res.open_status, MOCAP_OK) << res.error;
    EXPECT_EQ(res.end_status, MOCAP_ERR_END_OF_STREAM) << res.error;
    ASSERT_EQ(res.recs.size(), recs.size());
    for (size_t i = 0; i < recs.size(); i++) ASSERT_TRUE(res.recs[i] == recs[i]) << "record " << i;
    EXPECT_EQ(res.tail, 0);
    EXPECT_EQ(res.skipped, 0u);
    // About 8 MB of records: many chunks, each within the capacity.
    uint64_t payload = 0;
    for (const auto &rec : recs) payload += rec.bytes.size();
    EXPECT_GE(res.chunks, payload / CAPTURE_CHUNK_CAPACITY + 1);
}

#if !defined(_WIN32) // Windows: reads /proc/self/fd
TEST(CaptureFile, FilesAreNotInheritedByStartedPrograms)
{
    const std::string path = test_temp_path("inherit.mcap");
    capture_writer *w = nullptr;
    OpenedDescriptors dw = descriptors_opened_by([&] {
        ASSERT_EQ(capture_writer_open(path.c_str(), &w), MOCAP_OK) << mocap_last_error();
    });
    EXPECT_EQ(dw.opened.size(), 1u);
    EXPECT_TRUE(dw.inheritable.empty());
    const uint8_t bytes[3] = {1, 2, 3};
    ASSERT_EQ(capture_writer_append(w, 7, bytes, sizeof bytes), MOCAP_OK);
    ASSERT_EQ(capture_writer_close(w), MOCAP_OK);
    capture_reader *r = nullptr;
    OpenedDescriptors dr = descriptors_opened_by([&] {
        ASSERT_EQ(capture_reader_open(path.c_str(), &r), MOCAP_OK) << mocap_last_error();
    });
    EXPECT_EQ(dr.opened.size(), 1u);
    EXPECT_TRUE(dr.inheritable.empty());
    capture_reader_close(r);
}
#endif

TEST(CaptureFile, LongRecordsAreSplitWithTheSameTimestamp)
{
    const std::string path = test_temp_path("split.mcap");
    std::vector<uint8_t> big(2 * CAPTURE_MAX_RECORD + 1808);
    for (size_t i = 0; i < big.size(); i++) big[i] = static_cast<uint8_t>(i * 13 + 5);
    std::vector<uint8_t> exact(CAPTURE_MAX_RECORD, 0xAB);
    capture_writer *w = nullptr;
    ASSERT_EQ(capture_writer_open(path.c_str(), &w), MOCAP_OK);
    ASSERT_EQ(capture_writer_append(w, 777, big.data(), big.size()), MOCAP_OK);
    ASSERT_EQ(capture_writer_append(w, 888, exact.data(), exact.size()), MOCAP_OK);
    ASSERT_EQ(capture_writer_close(w), MOCAP_OK);

    ReadResult res = read_capture(path);
    ASSERT_EQ(res.open_status, MOCAP_OK) << res.error;
    ASSERT_EQ(res.recs.size(), 4u);
    std::vector<uint8_t> joined;
    for (int i = 0; i < 3; i++) {
        EXPECT_EQ(res.recs[i].ns, 777);
        EXPECT_LE(res.recs[i].bytes.size(), static_cast<size_t>(CAPTURE_MAX_RECORD));
        joined.insert(joined.end(), res.recs[i].bytes.begin(), res.recs[i].bytes.end());
    }
    EXPECT_EQ(joined, big);
    EXPECT_EQ(res.recs[3].ns, 888);
    EXPECT_EQ(res.recs[3].bytes, exact);
}

TEST(CaptureFile, FullBufferIsWrittenAsAChunkWithoutPolling)
{
    const std::string path = test_temp_path("by_size.mcap");
    const size_t len = 1000;
    const size_t fit = CAPTURE_CHUNK_CAPACITY / (len + 10); // records of 1000 bytes per chunk
    std::vector<Rec> recs = random_records(7, fit + 1, 1, 100);
    for (auto &rec : recs) rec.bytes.assign(len, static_cast<uint8_t>(rec.ns));
    capture_writer *w = nullptr;
    ASSERT_EQ(capture_writer_open(path.c_str(), &w), MOCAP_OK);
    const uint64_t header_only = capture_writer_bytes_written(w);
    for (size_t i = 0; i < fit; i++)
        ASSERT_EQ(capture_writer_append(w, recs[i].ns, recs[i].bytes.data(), len), MOCAP_OK);
    EXPECT_EQ(capture_writer_bytes_written(w), header_only);
    EXPECT_EQ(read_capture(path).recs.size(), 0u);

    ASSERT_EQ(capture_writer_append(w, recs[fit].ns, recs[fit].bytes.data(), len), MOCAP_OK);
    EXPECT_GT(capture_writer_bytes_written(w), header_only + fit * len);
    ReadResult seen = read_capture(path); // a second reader while the writer is still open
    ASSERT_EQ(seen.open_status, MOCAP_OK) << seen.error;
    ASSERT_EQ(seen.recs.size(), fit);
    EXPECT_TRUE(seen.recs[fit - 1] == recs[fit - 1]);
    EXPECT_EQ(seen.tail, 0);
    ASSERT_EQ(capture_writer_close(w), MOCAP_OK);
    EXPECT_EQ(read_capture(path).recs.size(), fit + 1);
}

TEST(CaptureFile, PollWritesAChunkOnceTheOldestRecordIs100msOld)
{
    const std::string path = test_temp_path("by_age.mcap");
    const int64_t t0 = 5000000000LL;
    const uint8_t a[] = {1, 2, 3}, b[] = {4, 5}, c[] = {6};
    capture_writer *w = nullptr;
    ASSERT_EQ(capture_writer_open(path.c_str(), &w), MOCAP_OK);
    const uint64_t header_only = capture_writer_bytes_written(w);
    ASSERT_EQ(capture_writer_append(w, t0, a, sizeof a), MOCAP_OK);
    ASSERT_EQ(capture_writer_append(w, t0 + 60000000, b, sizeof b), MOCAP_OK);
    // Younger than the interval: the writer batches instead of writing tiny chunks.
    ASSERT_EQ(capture_writer_poll(w, t0 + 50000000), MOCAP_OK);
    ASSERT_EQ(capture_writer_poll(w, t0 + CAPTURE_FLUSH_INTERVAL_NS - 1), MOCAP_OK);
    EXPECT_EQ(capture_writer_bytes_written(w), header_only);

    ASSERT_EQ(capture_writer_poll(w, t0 + CAPTURE_FLUSH_INTERVAL_NS), MOCAP_OK);
    ReadResult seen = read_capture(path);
    ASSERT_EQ(seen.recs.size(), 2u);
    EXPECT_EQ(seen.recs[0].ns, t0);
    EXPECT_EQ(seen.recs[1].bytes, std::vector<uint8_t>(b, b + sizeof b));
    EXPECT_EQ(seen.chunks, 1u);

    // The age counts from the oldest record still buffered, not from the last write.
    ASSERT_EQ(capture_writer_append(w, t0 + 150000000, c, sizeof c), MOCAP_OK);
    const uint64_t after_first = capture_writer_bytes_written(w);
    ASSERT_EQ(capture_writer_poll(w, t0 + 200000000), MOCAP_OK);
    EXPECT_EQ(capture_writer_bytes_written(w), after_first);
    ASSERT_EQ(capture_writer_poll(w, t0 + 250000000), MOCAP_OK);
    seen = read_capture(path);
    ASSERT_EQ(seen.recs.size(), 3u);
    EXPECT_EQ(seen.recs[2].ns, t0 + 150000000);
    EXPECT_EQ(seen.chunks, 2u);
    EXPECT_EQ(capture_writer_close(w), MOCAP_OK);
}

#if !defined(_WIN32) // Windows: kills a forked writer
namespace {

// Record i of the crash test: deterministic length and bytes, so the parent can check them.
std::vector<uint8_t> crash_record(uint64_t i)
{
    std::vector<uint8_t> bytes(1 + (i * 7919) % 700);
    for (size_t j = 0; j < bytes.size(); j++) bytes[j] = static_cast<uint8_t>(i * 31 + j * 7 + (i >> 8));
    return bytes;
}

struct CrashReport {
    uint64_t durable;  // records older than the flush interval at the last poll
    uint64_t appended;
    int64_t poll_ns;
};

[[noreturn]] void crash_child(const std::string &path, int report_fd)
{
    capture_writer *w = nullptr;
    if (capture_writer_open(path.c_str(), &w) != MOCAP_OK) _exit(2);
    std::vector<int64_t> stamps;
    uint64_t durable = 0;
    const int64_t start = mocap_monotonic_ns();
    int64_t last_poll = start;
    while (mocap_monotonic_ns() - start < 20000000000LL) { // the parent kills us long before
        for (int k = 0; k < 5; k++) {
            std::vector<uint8_t> bytes = crash_record(stamps.size());
            int64_t ns = mocap_monotonic_ns();
            if (capture_writer_append(w, ns, bytes.data(), bytes.size()) != MOCAP_OK) _exit(3);
            stamps.push_back(ns);
        }
        int64_t now = mocap_monotonic_ns();
        if (now - last_poll >= 10000000) {
            if (capture_writer_poll(w, now) != MOCAP_OK) _exit(4);
            last_poll = now;
            while (durable < stamps.size() && now - stamps[durable] >= CAPTURE_FLUSH_INTERVAL_NS)
                durable++;
            CrashReport rep{durable, stamps.size(), now};
            if (write(report_fd, &rep, sizeof rep) != static_cast<ssize_t>(sizeof rep)) _exit(5);
        }
        mocap_sleep_ms(1);
    }
    _exit(6);
}

} // namespace

TEST(CaptureFile, KilledWriterLeavesAnExactPrefix)
{
    const std::string path = test_temp_path("crash.mcap");
    int fds[2];
    ASSERT_EQ(pipe(fds), 0);
    fflush(nullptr);
    const int64_t started = mocap_monotonic_ns(); // before the fork: the child may run first
    pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        close(fds[0]);
        crash_child(path, fds[1]);
    }
    close(fds[1]);
    // Wait until the child reported records that must be on disk, and at least ~400 ms.
    CrashReport last{0, 0, 0};
    bool child_alive = true;
    while (last.durable == 0 || mocap_monotonic_ns() - started < 400000000LL) {
        CrashReport rep;
        ssize_t n = read(fds[0], &rep, sizeof rep);
        if (n != static_cast<ssize_t>(sizeof rep)) {
            child_alive = false;
            break;
        }
        last = rep;
    }
    kill(pid, SIGKILL);
    int wstatus = 0;
    ASSERT_EQ(waitpid(pid, &wstatus, 0), pid);
    ASSERT_TRUE(child_alive) << "child ended early, status " << wstatus;
    ASSERT_TRUE(WIFSIGNALED(wstatus) && WTERMSIG(wstatus) == SIGKILL) << "status " << wstatus;
    // Reports written between the last read and the kill still count.
    CrashReport rep;
    while (read(fds[0], &rep, sizeof rep) == static_cast<ssize_t>(sizeof rep)) last = rep;
    close(fds[0]);
    ASSERT_GT(last.durable, 0u);

    ReadResult res = read_capture(path);
    ASSERT_EQ(res.open_status, MOCAP_OK) << res.error;
    EXPECT_EQ(res.end_status, MOCAP_ERR_END_OF_STREAM) << res.error;
    EXPECT_EQ(res.skipped, 0u);
    EXPECT_GE(res.recs.size(), last.durable);
    for (size_t i = 0; i < res.recs.size(); i++) {
        ASSERT_EQ(res.recs[i].bytes, crash_record(i)) << "record " << i;
        ASSERT_GE(res.recs[i].ns, started);
        if (i > 0) {
            ASSERT_GE(res.recs[i].ns, res.recs[i - 1].ns);
        }
    }
    if (res.recs.size() >= last.durable && last.durable > 0) {
        EXPECT_LE(res.recs[last.durable - 1].ns, last.poll_ns - CAPTURE_FLUSH_INTERVAL_NS);
    }
}
#endif

TEST(CaptureFile, CorruptMiddleChunkIsSkippedAndLaterChunksStillRead)
{
    const std::string path = test_temp_path("corrupt.mcap");
    auto groups = make_groups(11, 5, 20, 300);
    auto offsets = write_chunks(path, groups);
    ASSERT_EQ(offsets.size(), 6u);
    const std::vector<uint8_t> good = read_file_bytes(path);
    const std::vector<Rec> expected = concat(groups, 2);

    // Every byte of the third chunk's header, and a spread of its payload bytes.
    std::vector<uint64_t> targets;
    for (uint64_t off = offsets[2]; off < offsets[2] + 36; off++) targets.push_back(off);
    for (uint64_t off = offsets[2] + 36; off < offsets[3]; off += 97) targets.push_back(off);
    targets.push_back(offsets[3] - 1);
    const std::string bad_path = test_temp_path("corrupt_copy.mcap");
    for (uint64_t off : targets) {
        for (uint8_t flip : {0x01, 0x80}) {
            std::vector<uint8_t> bytes = good;
            bytes[off] ^= flip;
            write_file_bytes(bad_path, bytes);
            ReadResult res = read_capture(bad_path);
            ASSERT_EQ(res.open_status, MOCAP_OK) << res.error;
            EXPECT_EQ(res.end_status, MOCAP_ERR_END_OF_STREAM) << "offset " << off << res.error;
            ASSERT_EQ(res.recs.size(), expected.size()) << "offset " << off;
            for (size_t i = 0; i < expected.size(); i++)
                ASSERT_TRUE(res.recs[i] == expected[i]) << "offset " << off << " record " << i;
            EXPECT_EQ(res.skipped, 1u) << "offset " << off;
            EXPECT_EQ(res.chunks, 4u) << "offset " << off;
            EXPECT_EQ(res.tail, 0) << "offset " << off;
        }
    }

    // Two damaged chunks in a row are both counted.
    std::vector<uint8_t> bytes = good;
    bytes[offsets[1] + 40] ^= 0xFF;
    bytes[offsets[2] + 40] ^= 0xFF;
    write_file_bytes(bad_path, bytes);
    ReadResult res = read_capture(bad_path);
    EXPECT_EQ(res.skipped, 2u);
    EXPECT_EQ(res.chunks, 3u);
    EXPECT_EQ(res.recs.size(), 60u);

    // A damaged last chunk is a corrupt tail, not a skipped chunk.
    bytes = good;
    bytes[offsets[4] + 50] ^= 0x10;
    write_file_bytes(bad_path, bytes);
    res = read_capture(bad_path);
    EXPECT_EQ(res.end_status, MOCAP_ERR_END_OF_STREAM);
    EXPECT_EQ(res.recs.size(), 80u);
    EXPECT_EQ(res.skipped, 0u);
    EXPECT_EQ(res.tail, 1);
}

// Skipping damaged data gives up at a deadline and resumes on the next call, finding exactly
// what an unhurried read finds: a replay thread stays responsive over any damage.
TEST(CaptureFile, ResyncWithADeadlineResumesWhereItStopped)
{
    auto groups = make_groups(12, 3, 10, 200);
    const std::string path = capture_with_fake_headers("fakes.mcap", 300, groups);
    ReadResult plain = read_capture(path);
    ASSERT_EQ(plain.end_status, MOCAP_ERR_END_OF_STREAM) << plain.error;
    ASSERT_EQ(plain.recs.size(), 30u);
    EXPECT_EQ(plain.chunks, 3u);

    capture_reader *r = nullptr;
    ASSERT_EQ(capture_reader_open(path.c_str(), &r), MOCAP_OK) << mocap_last_error();
    std::vector<Rec> recs;
    int timeouts = 0;
    for (;;) {
        int64_t ns;
        const uint8_t *data;
        size_t len;
        // A deadline already past: every call may look at one candidate at most.
        mocap_status st = capture_reader_next_until(r, 1, &ns, &data, &len);
        if (st == MOCAP_ERR_TIMEOUT) {
            ++timeouts;
            ASSERT_LT(timeouts, 100000);
            continue;
        }
        if (st != MOCAP_OK) {
            EXPECT_EQ(st, MOCAP_ERR_END_OF_STREAM) << mocap_last_error();
            break;
        }
        recs.push_back(Rec{ns, std::vector<uint8_t>(data, data + len)});
    }
    EXPECT_EQ(timeouts, 299);  // one stop per candidate (the first fake is rejected before the search)
    EXPECT_EQ(capture_reader_chunks(r), plain.chunks);
    EXPECT_EQ(capture_reader_skipped(r), plain.skipped);
    capture_reader_close(r);
    ASSERT_EQ(recs.size(), plain.recs.size());
    for (size_t i = 0; i < recs.size(); i++) ASSERT_TRUE(recs[i] == plain.recs[i]) << i;
}

TEST(CaptureFile, TruncationAtEveryOffsetOfTheLastChunkGivesACleanPrefix)
{
    const std::string path = test_temp_path("truncate.mcap");
    auto groups = make_groups(23, 3, 4, 60);
    auto offsets = write_chunks(path, groups);
    ASSERT_EQ(offsets.size(), 4u);
    const std::vector<uint8_t> good = read_file_bytes(path);
    ASSERT_EQ(good.size(), offsets[3]);
    const std::vector<Rec> prefix = concat({groups[0], groups[1]});
    const std::string cut_path = test_temp_path("truncated_copy.mcap");
    for (uint64_t size = offsets[2]; size < offsets[3]; size++) {
        write_file_bytes(cut_path, std::vector<uint8_t>(good.begin(), good.begin() + size));
        ReadResult res = read_capture(cut_path);
        ASSERT_EQ(res.open_status, MOCAP_OK) << res.error;
        EXPECT_EQ(res.end_status, MOCAP_ERR_END_OF_STREAM) << "size " << size << res.error;
        ASSERT_EQ(res.recs.size(), prefix.size()) << "size " << size;
        for (size_t i = 0; i < prefix.size(); i++) ASSERT_TRUE(res.recs[i] == prefix[i]);
        EXPECT_EQ(res.tail, size == offsets[2] ? 0 : 1) << "size " << size;
        EXPECT_EQ(res.skipped, 0u);
    }
    ReadResult whole = read_capture(path);
    EXPECT_EQ(whole.recs.size(), 12u);
    EXPECT_EQ(whole.tail, 0);
}

TEST(CaptureFile, HeaderErrorsAreClear)
{
    const std::string path = test_temp_path("good.mcap");
    write_chunks(path, make_groups(5, 1, 3, 10));
    const std::vector<uint8_t> good = read_file_bytes(path);
    ASSERT_GT(good.size(), 12u);
    const std::string bad = test_temp_path("bad.mcap");

    write_file_bytes(bad, std::vector<uint8_t>{'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd', '\n'});
    ReadResult res = read_capture(bad);
    EXPECT_EQ(res.open_status, MOCAP_ERR_FORMAT);
    EXPECT_TRUE(contains(res.error, "not a mocap capture file")) << res.error;
    EXPECT_TRUE(contains(res.error, bad)) << res.error;

    // Newer version, with a header CRC that is otherwise right.
    std::vector<uint8_t> bytes = good;
    const size_t header_size = bytes[10] | bytes[11] << 8;
    bytes[8] = 2;
    bytes[9] = 0;
    uint32_t crc = crc32_update(0, bytes.data(), header_size - 4);
    for (int i = 0; i < 4; i++) bytes[header_size - 4 + i] = static_cast<uint8_t>(crc >> (8 * i));
    write_file_bytes(bad, bytes);
    res = read_capture(bad);
    EXPECT_EQ(res.open_status, MOCAP_ERR_FORMAT);
    EXPECT_TRUE(contains(res.error, "version 2")) << res.error;
    EXPECT_TRUE(contains(res.error, "version 1")) << res.error;

    bytes = good;
    bytes[30] ^= 0x20; // inside the source description
    write_file_bytes(bad, bytes);
    res = read_capture(bad);
    EXPECT_EQ(res.open_status, MOCAP_ERR_FORMAT);
    EXPECT_TRUE(contains(res.error, "CRC")) << res.error;

    write_file_bytes(bad, {});
    res = read_capture(bad);
    EXPECT_EQ(res.open_status, MOCAP_ERR_FORMAT);
    EXPECT_TRUE(contains(res.error, "empty")) << res.error;

    for (size_t size : {size_t(5), size_t(11), size_t(100), header_size - 1}) {
        write_file_bytes(bad, std::vector<uint8_t>(good.begin(), good.begin() + size));
        res = read_capture(bad);
        EXPECT_EQ(res.open_status, MOCAP_ERR_FORMAT) << size;
        EXPECT_TRUE(contains(res.error, "truncated")) << res.error;
    }

    const std::string missing = test_temp_path("does_not_exist.mcap");
    res = read_capture(missing);
    EXPECT_EQ(res.open_status, MOCAP_ERR_NOT_FOUND);
    EXPECT_TRUE(contains(res.error, missing)) << res.error;

    capture_writer *w = nullptr;
    const std::string no_dir = test_temp_path("no_such_dir") + "/x.mcap";
    EXPECT_EQ(capture_writer_open(no_dir.c_str(), &w), MOCAP_ERR_NOT_FOUND);
    EXPECT_EQ(w, nullptr);
    EXPECT_TRUE(contains(mocap_last_error(), no_dir)) << mocap_last_error();
}

TEST(CaptureFile, HeaderKeepsSourceDescriptionAndCreationTime)
{
    const std::string path = test_temp_path("source.mcap");
    const int64_t before = std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::system_clock::now().time_since_epoch()).count();
    capture_writer *w = nullptr;
    ASSERT_EQ(capture_writer_open_with_source(path.c_str(), "serial port /dev/ttyUSB0", &w),
              MOCAP_OK);
    ASSERT_EQ(capture_writer_close(w), MOCAP_OK);
    const int64_t after = std::chrono::duration_cast<std::chrono::nanoseconds>(
                              std::chrono::system_clock::now().time_since_epoch()).count();
    capture_reader *r = nullptr;
    ASSERT_EQ(capture_reader_open(path.c_str(), &r), MOCAP_OK);
    EXPECT_STREQ(capture_reader_source(r), "serial port /dev/ttyUSB0");
    EXPECT_GE(capture_reader_created_unix_ns(r), before - 1000000000LL);
    EXPECT_LE(capture_reader_created_unix_ns(r), after + 1000000000LL);
    int64_t ns;
    const uint8_t *data;
    size_t len;
    EXPECT_EQ(capture_reader_next(r, &ns, &data, &len), MOCAP_ERR_END_OF_STREAM);
    EXPECT_EQ(capture_reader_tail(r), 0);
    capture_reader_close(r);

    // Too long: cut to 255 bytes, never inside a UTF-8 sequence.
    std::string source(254, 'a');
    source += "\xC3\xA9 and more";
    ASSERT_EQ(capture_writer_open_with_source(path.c_str(), source.c_str(), &w), MOCAP_OK);
    ASSERT_EQ(capture_writer_close(w), MOCAP_OK);
    ASSERT_EQ(capture_reader_open(path.c_str(), &r), MOCAP_OK);
    EXPECT_EQ(std::string(capture_reader_source(r)), std::string(254, 'a'));
    capture_reader_close(r);
}

#if !defined(_WIN32) // Windows: /dev/full, and fork + RLIMIT_FSIZE for a full disk
TEST(CaptureFile, FullDiskIsReportedWithTheFileAndTheCause)
{
    if (access("/dev/full", W_OK) != 0) GTEST_SKIP() << "no writable /dev/full";
    capture_writer *w = nullptr;
    // The header is written at open, so a full disk is reported before recording starts.
    EXPECT_EQ(capture_writer_open("/dev/full", &w), MOCAP_ERR_IO);
    EXPECT_EQ(w, nullptr);
    char cause[128];
    const std::string text = mocap_last_error();
    EXPECT_TRUE(contains(text, "/dev/full")) << text;
    EXPECT_TRUE(contains(text, mocap_errno_text(ENOSPC, cause, sizeof cause))) << text;
    EXPECT_EQ(capture_writer_append(nullptr, 0, nullptr, 0), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(capture_writer_close(nullptr), MOCAP_OK);
}

// A write that fails mid-recording (here the file size limit, EFBIG, standing in for a disk
// that fills up): the writer reports the file, the cause and the lost bytes, refuses every
// later call without crashing, and the file still reads as a clean prefix.
TEST(CaptureFile, WriteErrorIsStickyAndLostBytesAreCounted)
{
    const std::string path = test_temp_path("limited.mcap");
    int fds[2];
    ASSERT_EQ(pipe(fds), 0);
    fflush(nullptr);
    pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        close(fds[0]);
        std::string log;
        auto check = [&](bool ok, const std::string &what) {
            if (!ok) log += what + " | " + mocap_last_error() + "\n";
        };
        signal(SIGXFSZ, SIG_IGN);
        struct rlimit lim = {3000, 3000};
        setrlimit(RLIMIT_FSIZE, &lim);
        capture_writer *w = nullptr;
        check(capture_writer_open(path.c_str(), &w) == MOCAP_OK, "open");
        std::vector<uint8_t> rec(100, 0x42);
        uint64_t appended = 0;
        mocap_status first_error = MOCAP_OK;
        for (int chunk = 0; chunk < 4 && w; chunk++) {
            for (int i = 0; i < 10; i++) {
                mocap_status st = capture_writer_append(w, chunk * 100 + i, rec.data(), rec.size());
                appended += rec.size();
                check(st == MOCAP_OK || st == first_error, "append");
            }
            mocap_status st = capture_writer_flush(w);
            if (st != MOCAP_OK && first_error == MOCAP_OK) {
                first_error = st;
                char cause[128];
                std::string text = mocap_last_error();
                check(st == MOCAP_ERR_IO, "flush status");
                check(contains(text, path), "message names the file: " + text);
                check(contains(text, mocap_errno_text(EFBIG, cause, sizeof cause)),
                      "message names the cause: " + text);
            }
        }
        check(first_error == MOCAP_ERR_IO, "a flush failed");
        check(capture_writer_append(w, 1, rec.data(), rec.size()) == MOCAP_ERR_IO,
              "append after error");
        appended += rec.size();
        check(contains(mocap_last_error(), "not written"), "append reports lost data");
        check(capture_writer_poll(w, INT64_MAX / 2) == MOCAP_ERR_IO, "poll after error");
        check(capture_writer_flush(w) == MOCAP_ERR_IO, "flush after error");
        // Two 10-record chunks fit under the limit; everything else is lost.
        check(capture_writer_bytes_lost(w) == appended - 2000,
              "lost " + std::to_string(capture_writer_bytes_lost(w)) + " of " +
                  std::to_string(appended));
        check(capture_writer_close(w) == MOCAP_ERR_IO, "close after error");
        if (write(fds[1], log.data(), log.size()) < 0) _exit(2);
        _exit(log.empty() ? 0 : 1);
    }
    close(fds[1]);
    std::string log;
    char buf[512];
    ssize_t n;
    while ((n = read(fds[0], buf, sizeof buf)) > 0) log.append(buf, static_cast<size_t>(n));
    close(fds[0]);
    int wstatus = 0;
    ASSERT_EQ(waitpid(pid, &wstatus, 0), pid);
    ASSERT_TRUE(WIFEXITED(wstatus)) << "child crashed, status " << wstatus;
    EXPECT_EQ(WEXITSTATUS(wstatus), 0) << log;

    ReadResult res = read_capture(path);
    ASSERT_EQ(res.open_status, MOCAP_OK) << res.error;
    EXPECT_EQ(res.end_status, MOCAP_ERR_END_OF_STREAM);
    EXPECT_EQ(res.recs.size(), 20u);
    EXPECT_EQ(res.tail, 1); // the failed write left part of a chunk
    EXPECT_EQ(read_file_bytes(path).size(), 3000u);
}
#endif
