// SPSC ring and triple buffer: single-thread semantics, then two-thread stress tests that also
// run under ThreadSanitizer (label "threads").
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <string>
#include <thread>

#include "error.h"
#include "spsc_ring.h"

namespace {

struct Item {
    uint64_t seq;
    uint64_t check; // ~seq: a torn or stale copy shows up as a mismatch
};

Item make_item(uint64_t seq) { return Item{seq, ~seq}; }

std::string last_error()
{
    char buf[256];
    mocap_copy_error(buf, sizeof buf);
    return buf;
}

TEST(SpscRing, CapacityIsRoundedUpToAPowerOfTwo)
{
    const size_t asked[] = {1, 2, 3, 5, 8, 9, 1000};
    const uint64_t want[] = {1, 2, 4, 8, 8, 16, 1024};
    for (size_t i = 0; i < sizeof asked / sizeof asked[0]; i++) {
        spsc_ring r;
        ASSERT_EQ(spsc_ring_init(&r, sizeof(Item), asked[i]), 0);
        EXPECT_EQ(r.capacity, want[i]) << asked[i];
        // Exactly capacity elements fit: no slot is sacrificed to tell full from empty.
        for (uint64_t k = 0; k < want[i]; k++) {
            const Item in = make_item(k);
            ASSERT_EQ(spsc_ring_push(&r, &in), 0);
        }
        Item x = make_item(99);
        EXPECT_EQ(spsc_ring_push(&r, &x), -1);
        EXPECT_EQ(spsc_ring_size(&r), (size_t)want[i]);
        spsc_ring_destroy(&r);
        EXPECT_EQ(r.storage, nullptr);
    }
}

TEST(SpscRing, RejectsZeroElementSizeWithAMessage)
{
    mocap_clear_error();
    spsc_ring r;
    EXPECT_EQ(spsc_ring_init(&r, 0, 16), -1);
    EXPECT_EQ(r.storage, nullptr);
    EXPECT_NE(last_error().find("spsc ring"), std::string::npos) << last_error();
    spsc_ring_destroy(&r); // safe after a failed init
}

TEST(SpscRing, FullEmptyAndOrder)
{
    spsc_ring r;
    ASSERT_EQ(spsc_ring_init(&r, sizeof(Item), 4), 0);
    Item x{};
    EXPECT_EQ(spsc_ring_pop(&r, &x), -1);
    EXPECT_EQ(spsc_ring_peek(&r), nullptr);
    EXPECT_EQ(spsc_ring_size(&r), 0u);
    for (uint64_t k = 0; k < 4; k++) {
        Item in = make_item(k);
        ASSERT_EQ(spsc_ring_push(&r, &in), 0);
        EXPECT_EQ(spsc_ring_size(&r), (size_t)k + 1);
    }
    Item extra = make_item(77);
    EXPECT_EQ(spsc_ring_push(&r, &extra), -1);
    EXPECT_EQ(spsc_ring_reserve(&r), nullptr);
    EXPECT_EQ(spsc_ring_size(&r), 4u);
    for (uint64_t k = 0; k < 4; k++) {
        ASSERT_EQ(spsc_ring_pop(&r, &x), 0);
        EXPECT_EQ(x.seq, k);
        EXPECT_EQ(x.check, ~k);
    }
    EXPECT_EQ(spsc_ring_pop(&r, &x), -1);
    EXPECT_EQ(spsc_ring_size(&r), 0u);
    spsc_ring_destroy(&r);
}

TEST(SpscRing, WrapsAroundManyTimes)
{
    spsc_ring r;
    ASSERT_EQ(spsc_ring_init(&r, sizeof(Item), 4), 0);
    uint64_t next_in = 0, next_out = 0;
    for (int round = 0; round < 1000; round++) {
        const int n = 1 + round % 4; // 1..4 elements, so fill levels and offsets vary
        for (int i = 0; i < n; i++) {
            Item in = make_item(next_in++);
            ASSERT_EQ(spsc_ring_push(&r, &in), 0);
        }
        EXPECT_EQ(spsc_ring_size(&r), (size_t)n);
        for (int i = 0; i < n; i++) {
            Item x{};
            ASSERT_EQ(spsc_ring_pop(&r, &x), 0);
            ASSERT_EQ(x.seq, next_out);
            ASSERT_EQ(x.check, ~next_out);
            next_out++;
        }
    }
    EXPECT_EQ(next_out, next_in);
    // Indices grow without bound; only the slot is masked.
    EXPECT_EQ(mocap_atomic_load_u64(&r.head), next_in);
    EXPECT_EQ(mocap_atomic_load_u64(&r.tail), next_out);
    spsc_ring_destroy(&r);
}

TEST(SpscRing, ReserveCommitAndPeekRelease)
{
    spsc_ring r;
    ASSERT_EQ(spsc_ring_init(&r, sizeof(Item), 2), 0);
    Item *slot = static_cast<Item *>(spsc_ring_reserve(&r));
    ASSERT_NE(slot, nullptr);
    EXPECT_EQ(spsc_ring_reserve(&r), slot); // same slot until committed
    *slot = make_item(5);
    EXPECT_EQ(spsc_ring_peek(&r), nullptr) << "invisible before commit";
    EXPECT_EQ(spsc_ring_size(&r), 0u);
    spsc_ring_commit(&r);
    EXPECT_EQ(spsc_ring_size(&r), 1u);

    Item *slot2 = static_cast<Item *>(spsc_ring_reserve(&r));
    ASSERT_NE(slot2, nullptr);
    EXPECT_NE(slot2, slot);
    *slot2 = make_item(6);
    spsc_ring_commit(&r);
    EXPECT_EQ(spsc_ring_reserve(&r), nullptr); // full

    const Item *p = static_cast<const Item *>(spsc_ring_peek(&r));
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(p->seq, 5u);
    EXPECT_EQ(spsc_ring_peek(&r), p); // peeking twice does not consume
    EXPECT_EQ(spsc_ring_size(&r), 2u);
    spsc_ring_release(&r);
    EXPECT_EQ(spsc_ring_size(&r), 1u);
    // Releasing freed exactly one slot, and it is the one just read.
    EXPECT_EQ(spsc_ring_reserve(&r), slot);
    p = static_cast<const Item *>(spsc_ring_peek(&r));
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(p->seq, 6u);
    EXPECT_EQ(p->check, ~6ull);
    spsc_ring_release(&r);
    EXPECT_EQ(spsc_ring_peek(&r), nullptr);
    spsc_ring_destroy(&r);
}

TEST(SpscRing, TwoThreadStressKeepsOrderWithoutLossOrDuplication)
{
    constexpr uint64_t kCount = 2000000;
    spsc_ring r;
    ASSERT_EQ(spsc_ring_init(&r, sizeof(Item), 256), 0);
    std::atomic<uint64_t> producer_full{0};

    // Both sides alternate between the copying and the in-place calls.
    std::thread producer([&] {
        uint64_t full = 0;
        for (uint64_t k = 0; k < kCount; k++) {
            if (k & 1) {
                Item *slot;
                while ((slot = static_cast<Item *>(spsc_ring_reserve(&r))) == nullptr) {
                    full++;
                    std::this_thread::yield();
                }
                *slot = make_item(k);
                spsc_ring_commit(&r);
            } else {
                const Item in = make_item(k);
                while (spsc_ring_push(&r, &in) != 0) {
                    full++;
                    std::this_thread::yield();
                }
            }
        }
        producer_full.store(full);
    });

    uint64_t expected = 0, mismatches = 0;
    while (expected < kCount) {
        Item x{};
        if (expected & 1) {
            const Item *p = static_cast<const Item *>(spsc_ring_peek(&r));
            if (!p) {
                std::this_thread::yield();
                continue;
            }
            x = *p;
            spsc_ring_release(&r);
        } else if (spsc_ring_pop(&r, &x) != 0) {
            std::this_thread::yield();
            continue;
        }
        if (x.seq != expected || x.check != ~expected) {
            if (mismatches++ == 0)
                ADD_FAILURE() << "expected " << expected << " got " << x.seq;
        }
        expected = x.seq + 1; // resynchronise so one error does not cascade
    }
    producer.join();
    EXPECT_EQ(mismatches, 0u);
    EXPECT_EQ(expected, kCount);
    Item x{};
    EXPECT_EQ(spsc_ring_pop(&r, &x), -1) << "nothing extra left behind";
    EXPECT_EQ(mocap_atomic_load_u64(&r.head), kCount);
    spsc_ring_destroy(&r);
}

struct Wide {
    uint64_t v[16];
};

TEST(TripleBuffer, TakeReturnsNewestOnceThenNull)
{
    triple_buffer b;
    ASSERT_EQ(triple_buffer_init(&b, sizeof(Wide)), 0);
    EXPECT_EQ(triple_buffer_take(&b), nullptr) << "nothing published yet";

    for (uint64_t v = 1; v <= 3; v++) {
        Wide *w = static_cast<Wide *>(triple_buffer_write_slot(&b));
        ASSERT_NE(w, nullptr);
        for (uint64_t &f : w->v)
            f = v;
        triple_buffer_publish(&b);
    }
    const Wide *got = static_cast<const Wide *>(triple_buffer_take(&b));
    ASSERT_NE(got, nullptr);
    EXPECT_EQ(got->v[0], 3u) << "older unread values are superseded";
    EXPECT_EQ(got->v[15], 3u);
    EXPECT_EQ(triple_buffer_take(&b), nullptr) << "nothing new since";

    // The producer never writes into the slot the consumer holds, however often it publishes.
    for (uint64_t v = 4; v < 20; v++) {
        Wide *w = static_cast<Wide *>(triple_buffer_write_slot(&b));
        EXPECT_NE(static_cast<const void *>(w), static_cast<const void *>(got));
        for (uint64_t &f : w->v)
            f = v;
        triple_buffer_publish(&b);
        EXPECT_EQ(got->v[0], 3u);
    }
    got = static_cast<const Wide *>(triple_buffer_take(&b));
    ASSERT_NE(got, nullptr);
    EXPECT_EQ(got->v[7], 19u);
    triple_buffer_destroy(&b);
    EXPECT_EQ(b.storage, nullptr);
}

TEST(TripleBuffer, RejectsZeroElementSize)
{
    triple_buffer b;
    EXPECT_EQ(triple_buffer_init(&b, 0), -1);
    EXPECT_EQ(b.storage, nullptr);
    triple_buffer_destroy(&b);
}

TEST(TripleBuffer, TwoThreadStressNeverTornNeverBackwards)
{
    constexpr uint64_t kLast = 300000;
    triple_buffer b;
    ASSERT_EQ(triple_buffer_init(&b, sizeof(Wide)), 0);

    std::thread producer([&] {
        for (uint64_t v = 1; v <= kLast; v++) {
            Wide *w = static_cast<Wide *>(triple_buffer_write_slot(&b));
            for (uint64_t &f : w->v)
                f = v;
            triple_buffer_publish(&b);
            if (v % 128 == 0)
                std::this_thread::yield(); // let the consumer interleave on a busy machine
        }
    });

    uint64_t last_seen = 0, taken = 0, torn = 0, backwards = 0;
    while (last_seen < kLast) {
        const Wide *w = static_cast<const Wide *>(triple_buffer_take(&b));
        if (!w) {
            std::this_thread::yield();
            continue;
        }
        taken++;
        const uint64_t v = w->v[0];
        for (uint64_t f : w->v)
            torn += f != v;
        // Each take hands over a value published after the previous one.
        backwards += v <= last_seen;
        last_seen = v;
    }
    producer.join();
    EXPECT_EQ(torn, 0u);
    EXPECT_EQ(backwards, 0u);
    EXPECT_EQ(last_seen, kLast) << "the final value is delivered";
    EXPECT_GT(taken, 0u);
    EXPECT_EQ(triple_buffer_take(&b), nullptr);
    triple_buffer_destroy(&b);
}

} // namespace
