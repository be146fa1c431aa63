// OSC 1.0 encoder: byte-exact encodings against bytes worked out by hand from the OSC 1.0 spec
// (padding, big-endian int32/float32/timetag, bundles with size-prefixed elements), and misuse.
#include <gtest/gtest.h>

#include <cmath>

#include <cstring>
#include <vector>

#include "test_support.h"

extern "C" {
#include "osc_encoder.h"
}

namespace {

std::vector<uint8_t> finish(osc_writer &w)
{
    size_t n = osc_writer_finish(&w);
    EXPECT_EQ(w.error, nullptr) << (w.error ? w.error : "");
    return std::vector<uint8_t>(w.buf, w.buf + n);
}

}  // namespace

TEST(OscEncoder, SpecExampleSingleFloat)
{
    uint8_t buf[64];
    osc_writer w;
    osc_writer_init(&w, buf, sizeof buf);
    osc_message_begin(&w, "/oscillator/4/frequency", ",f");
    osc_arg_float(&w, 440.0f);
    osc_message_end(&w);
    // 23 address bytes + 1 NUL = 24 (already aligned); ",f" + 2 NUL; 440.0f = 0x43DC0000.
    EXPECT_EQ(finish(w), hex_bytes("2f6f7363 696c6c61 746f722f 342f6672 65717565 6e637900"
                                   "2c660000 43dc0000"));
}

TEST(OscEncoder, SpecExampleMixedArguments)
{
    uint8_t buf[64];
    osc_writer w;
    osc_writer_init(&w, buf, sizeof buf);
    osc_message_begin(&w, "/foo", ",iisff");
    osc_arg_int32(&w, 1000);
    osc_arg_int32(&w, -1);
    osc_arg_string(&w, "hello");
    osc_arg_float(&w, 1.234f);
    osc_arg_float(&w, 5.678f);
    osc_message_end(&w);
    // "/foo" is 4 bytes: its NUL needs a whole padding word. ",iisff" 6 + 2 NUL.
    EXPECT_EQ(finish(w), hex_bytes("2f666f6f 00000000 2c696973 66660000 000003e8 ffffffff"
                                   "68656c6c 6f000000 3f9df3b6 40b5b22d"));
}

TEST(OscEncoder, StringPaddingAtEveryLength)
{
    const char *strings[] = {"", "a", "ab", "abc", "abcd", "abcde"};
    const size_t padded[] = {4, 4, 4, 4, 8, 8};
    for (int i = 0; i < 6; ++i) {
        uint8_t buf[64];
        std::memset(buf, 0xAA, sizeof buf);  // padding must be written as zeros
        osc_writer w;
        osc_writer_init(&w, buf, sizeof buf);
        osc_message_begin(&w, "/s", ",s");
        osc_arg_string(&w, strings[i]);
        osc_message_end(&w);
        auto bytes = finish(w);
        ASSERT_EQ(bytes.size(), 4 + 4 + padded[i]) << strings[i];
        size_t len = std::strlen(strings[i]);
        EXPECT_EQ(0, std::memcmp(bytes.data() + 8, strings[i], len));
        for (size_t k = 8 + len; k < bytes.size(); ++k) EXPECT_EQ(bytes[k], 0) << strings[i] << " byte " << k;
    }
}

TEST(OscEncoder, NegativeFloatsAndTimetagsAreBigEndian)
{
    uint8_t buf[64];
    osc_writer w;
    osc_writer_init(&w, buf, sizeof buf);
    osc_message_begin(&w, "/t", ",ft");
    osc_arg_float(&w, -1.5f);
    osc_arg_timetag(&w, 0x0102030405060708ull);
    osc_message_end(&w);
    EXPECT_EQ(finish(w), hex_bytes("2f740000 2c667400 bfc00000 01020304 05060708"));
    // NTP epoch 1900: the Unix epoch is 2208988800 s = 0x83AA7E80 later; 0.5 s = 0x80000000.
    EXPECT_EQ(osc_timetag_from_unix(0.0), 0x83AA7E8000000000ull);
    EXPECT_EQ(osc_timetag_from_unix(0.5), 0x83AA7E8080000000ull);
    // Era 1 starts 2^32 s after 1900 (Unix 2085978496, in 2036): the seconds field wraps to 0.
    EXPECT_EQ(osc_timetag_from_unix(2085978496.5), 0x0000000080000000ull);
    // Times with no meaning are sent as "immediately", never converted (undefined for huge values).
    EXPECT_EQ(osc_timetag_from_unix(INFINITY), OSC_TIMETAG_IMMEDIATELY);
    EXPECT_EQ(osc_timetag_from_unix(NAN), OSC_TIMETAG_IMMEDIATELY);
    EXPECT_EQ(osc_timetag_from_unix(-1.0), OSC_TIMETAG_IMMEDIATELY);
    EXPECT_EQ(osc_timetag_from_unix(1e30) >> 32 < 0x100000000ull, true);
}

TEST(OscEncoder, BundleWithSizePrefixedMessages)
{
    uint8_t buf[128];
    osc_writer w;
    osc_writer_init(&w, buf, sizeof buf);
    osc_bundle_begin(&w, OSC_TIMETAG_IMMEDIATELY);
    osc_message_begin(&w, "/a", ",i");
    osc_arg_int32(&w, 7);
    osc_message_end(&w);
    osc_message_begin(&w, "/VMC/Ext/T", ",f");
    osc_arg_float(&w, 2.0f);
    osc_message_end(&w);
    osc_bundle_end(&w);
    EXPECT_EQ(finish(w), hex_bytes("2362756e 646c6500 00000000 00000001"  // "#bundle", timetag 1
                                   "0000000c 2f610000 2c690000 00000007"  // size 12, "/a" ,i 7
                                   "00000014 2f564d43 2f457874 2f540000 2c660000 40000000"));
}

TEST(OscEncoder, NestedBundles)
{
    uint8_t buf[128];
    osc_writer w;
    osc_writer_init(&w, buf, sizeof buf);
    osc_bundle_begin(&w, 5);
    osc_bundle_begin(&w, 6);
    osc_message_begin(&w, "/a", ",i");
    osc_arg_int32(&w, 7);
    osc_message_end(&w);
    osc_bundle_end(&w);
    osc_bundle_end(&w);
    EXPECT_EQ(finish(w), hex_bytes("2362756e 646c6500 00000000 00000005"
                                   "00000020 2362756e 646c6500 00000000 00000006"  // inner: 32 bytes
                                   "0000000c 2f610000 2c690000 00000007"));
}

TEST(OscEncoder, ExactCapacityFitsOneByteLessFails)
{
    for (size_t cap : {size_t(16), size_t(15)}) {
        std::vector<uint8_t> buf(cap);
        osc_writer w;
        osc_writer_init(&w, buf.data(), cap);
        osc_message_begin(&w, "/abc", ",i");
        osc_arg_int32(&w, 1);
        osc_message_end(&w);
        size_t n = osc_writer_finish(&w);
        if (cap == 16) {
            EXPECT_EQ(n, 16u);
        } else {
            EXPECT_EQ(n, 0u);
            ASSERT_NE(w.error, nullptr);
            EXPECT_STREQ(w.error, "buffer too small");
        }
    }
}

TEST(OscEncoder, MisuseIsRefused)
{
    uint8_t buf[128];
    osc_writer w;
    // An argument whose type does not match its tag.
    osc_writer_init(&w, buf, sizeof buf);
    osc_message_begin(&w, "/a", ",f");
    osc_arg_int32(&w, 1);
    osc_message_end(&w);
    EXPECT_EQ(osc_writer_finish(&w), 0u);
    // Fewer arguments than tags.
    osc_writer_init(&w, buf, sizeof buf);
    osc_message_begin(&w, "/a", ",ff");
    osc_arg_float(&w, 1);
    osc_message_end(&w);
    EXPECT_EQ(osc_writer_finish(&w), 0u);
    EXPECT_STREQ(w.error, "fewer arguments than type tags");
    // More arguments than tags.
    osc_writer_init(&w, buf, sizeof buf);
    osc_message_begin(&w, "/a", ",f");
    osc_arg_float(&w, 1);
    osc_arg_float(&w, 2);
    osc_message_end(&w);
    EXPECT_EQ(osc_writer_finish(&w), 0u);
    // Unbalanced bundle, bad address, unknown tag, two top-level messages.
    osc_writer_init(&w, buf, sizeof buf);
    osc_bundle_begin(&w, 1);
    EXPECT_EQ(osc_writer_finish(&w), 0u);
    osc_writer_init(&w, buf, sizeof buf);
    osc_message_begin(&w, "noslash", ",");
    osc_message_end(&w);
    EXPECT_EQ(osc_writer_finish(&w), 0u);
    osc_writer_init(&w, buf, sizeof buf);
    osc_message_begin(&w, "/a", ",x");
    EXPECT_EQ(osc_writer_finish(&w), 0u);
    osc_writer_init(&w, buf, sizeof buf);
    osc_message_begin(&w, "/a", ",");
    osc_message_end(&w);
    osc_message_begin(&w, "/b", ",");
    osc_message_end(&w);
    EXPECT_EQ(osc_writer_finish(&w), 0u);
    // A message with no arguments is fine: address + "," padded.
    osc_writer_init(&w, buf, sizeof buf);
    osc_message_begin(&w, "/a", ",");
    osc_message_end(&w);
    EXPECT_EQ(finish(w), hex_bytes("2f610000 2c000000"));
}
