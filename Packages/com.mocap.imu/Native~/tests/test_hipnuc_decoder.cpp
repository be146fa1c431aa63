// HiPNUC decoder: public test vectors, resynchronisation and exact error accounting, chunking
// independence, packet-level edge cases and encode/decode round trips.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "hipnuc_decoder.h"
#include "test_support.h"

namespace {

using Bytes = std::vector<uint8_t>;

// Public sample frames (the project's shared reference: hipnuc-protocol.md beside the checkout).
const char *kVector1 = // Hi229 manual, 0x91
    "5AA54C006C519100A03B01A80297BDBB04009CA0653EA226453F5CE7303FE2D45AC2E59DA0C1EB23EEC278779941"
    "ABAAD1C1AB2A0AC28DE142428F1DA8C11E0C36C2E6E55A3FC1949E3EB8C09EBEBEDF8DBE";
const char *kVector2 = // SDK example_data.c, 0x91
    "5AA54C0014BB91081523 09A2C44708151C00CCE861BE9A35563E65EA723F31D07CBD75DDC5BB6BD724BC8988FC40"
    "01006A41AB2A70C296D45041ED03434141F4F4C2CCCAF8BE736A19BEF0001C3D8D375C3F";
const char *kVector3 = // HI221 manual, chained
    "5AA51500A98BA0EAFFD00345FFB0000000000000D087006F27F5FF";
const char *kVector4 = // Hi229 manual, chained 90 A0 B0 C0 D0 F0
    "5AA52300FD619000A055023D01E202B0FEFF17004400C080FF60FF32FFD064F26C0EBB01F000000000";

constexpr uint32_t kImusolFields = HIPNUC_FIELD_TIME | HIPNUC_FIELD_ACC | HIPNUC_FIELD_GYR |
                                   HIPNUC_FIELD_MAG | HIPNUC_FIELD_EULER | HIPNUC_FIELD_QUAT;

uint32_t bits(float f)
{
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

float from_bits(uint32_t u)
{
    float f;
    std::memcpy(&f, &u, sizeof f);
    return f;
}

void expect_words(const float *values, std::initializer_list<uint32_t> words, const char *what)
{
    size_t i = 0;
    for (uint32_t w : words) {
        EXPECT_EQ(bits(values[i]), w) << what << "[" << i << "]";
        i++;
    }
}

bool frames_equal(const hipnuc_frame &a, const hipnuc_frame &b)
{
    if (a.payload_length != b.payload_length || a.first_tag != b.first_tag ||
        a.gateway_id != b.gateway_id || a.sample_count != b.sample_count)
        return false;
    return std::memcmp(a.samples, b.samples, a.sample_count * sizeof(hipnuc_sample)) == 0;
}

// A decoder plus everything it delivered. Heap-allocated: both structs are a few KB.
struct DecodeRun {
    hipnuc_decoder dec;
    std::vector<hipnuc_frame> frames;
    uint64_t frame_bytes = 0;

    explicit DecodeRun(int layout = HIPNUC_LAYOUT_AUTO) { hipnuc_decoder_init(&dec, layout); }

    static void on_frame(void *user, const hipnuc_frame *f)
    {
        auto *run = static_cast<DecodeRun *>(user);
        run->frames.push_back(*f);
        run->frame_bytes += HIPNUC_HEADER_SIZE + f->payload_length;
    }
    void feed(const uint8_t *p, size_t n) { hipnuc_decoder_feed(&dec, p, n, on_frame, this); }
    void feed(const Bytes &b) { feed(b.data(), b.size()); }
    void feed_bytewise(const Bytes &b)
    {
        for (uint8_t c : b) feed(&c, 1);
    }
    void feed_random_chunks(const Bytes &b, uint32_t seed, size_t max_chunk)
    {
        std::mt19937 rng(seed);
        size_t pos = 0;
        while (pos < b.size()) {
            size_t n = std::min<size_t>(1 + rng() % max_chunk, b.size() - pos);
            feed(b.data() + pos, n);
            pos += n;
        }
    }
    const hipnuc_stats &stats() const { return dec.stats; }
    // Every byte is in a delivered frame, was skipped, or is still buffered.
    void expect_bytes_accounted() const
    {
        EXPECT_EQ(dec.stats.bytes_in, frame_bytes + dec.stats.bytes_skipped + dec.length);
        EXPECT_EQ(dec.stats.frames_ok, frames.size());
        uint64_t samples = 0;
        for (const auto &f : frames) samples += f.sample_count;
        EXPECT_EQ(dec.stats.samples, samples);
    }
};

std::unique_ptr<DecodeRun> make_run(int layout = HIPNUC_LAYOUT_AUTO)
{
    return std::make_unique<DecodeRun>(layout);
}

Bytes frame_of(const Bytes &payload)
{
    Bytes out(payload.size() + HIPNUC_HEADER_SIZE);
    size_t n = hipnuc_encode_frame(payload.data(), payload.size(), out.data(), out.size());
    EXPECT_EQ(n, out.size());
    return out;
}

void append(Bytes &to, const Bytes &from) { to.insert(to.end(), from.begin(), from.end()); }

hipnuc_sample make_sample(uint32_t node, uint32_t t)
{
    hipnuc_sample s;
    std::memset(&s, 0, sizeof s);
    s.fields = HIPNUC_FIELD_NODE_ID | kImusolFields;
    s.source_tag = HIPNUC_TAG_GWSOL;
    s.node_id = node;
    s.time_ms = t;
    for (int i = 0; i < 3; i++) {
        s.acc_g[i] = 0.01f * static_cast<float>(node) - 0.3f * static_cast<float>(i) + 1e-4f * t;
        s.gyr_dps[i] = -12.5f * static_cast<float>(i) + static_cast<float>(t % 97);
        s.mag_ut[i] = 40.25f - static_cast<float>(node * 3 + i);
        s.euler_deg[i] = static_cast<float>((t * 7 + node * 13 + i * 31) % 360) - 180.f;
    }
    const float c = std::cos(0.001f * t + node), sn = std::sin(0.001f * t + node);
    s.quat[0] = c;
    s.quat[1] = sn * 0.6f;
    s.quat[2] = 0.f;
    s.quat[3] = sn * 0.8f;
    return s;
}

Bytes gwsol_payload(uint8_t gateway, const std::vector<hipnuc_sample> &samples)
{
    Bytes out(HIPNUC_GWSOL_HEADER_SIZE + samples.size() * HIPNUC_IMUSOL_SIZE);
    size_t n = hipnuc_encode_gwsol(gateway, samples.data(), static_cast<uint32_t>(samples.size()),
                                   out.data(), out.size());
    EXPECT_EQ(n, out.size());
    return out;
}

Bytes imusol_payload(const hipnuc_sample &s, int layout)
{
    Bytes out(HIPNUC_IMUSOL_SIZE);
    hipnuc_encode_imusol(&s, layout, out.data());
    return out;
}

std::vector<hipnuc_sample> nodes(uint32_t n, uint32_t t)
{
    std::vector<hipnuc_sample> v;
    for (uint32_t i = 0; i < n; i++) v.push_back(make_sample(i + 1, t + i));
    return v;
}

} // namespace

// ---- Public test vectors. Expected values are read off the hex by hand: little-endian words,
// ---- floats given by their IEEE-754 bit patterns (so the comparison is exact).

TEST(HipnucVectors, Vector1Hi229ManualUsesNodeIdLayout)
{
    auto run = make_run();
    run->feed(hex_bytes(kVector1));
    ASSERT_EQ(run->frames.size(), 1u);
    const hipnuc_frame &f = run->frames[0];
    EXPECT_EQ(f.payload_length, 0x4C);
    EXPECT_EQ(f.first_tag, 0x91);
    ASSERT_EQ(f.sample_count, 1u);
    const hipnuc_sample &s = f.samples[0];
    // Bytes 1..7 "00 A0 3B 01 A8 02 97": read as status layout, the pressure would be the word
    // 0x9702A801 (about -4e-25 Pa), which is implausible, so AUTO keeps the node-id layout.
    EXPECT_EQ(s.fields, HIPNUC_FIELD_NODE_ID | kImusolFields);
    EXPECT_EQ(s.node_id, 0u);
    EXPECT_EQ(s.source_tag, 0x91);
    EXPECT_EQ(s.time_ms, 0x0004BBBDu); // "BDBB0400" = 310205 ms
    expect_words(s.acc_g, {0x3E65A09C, 0x3F4526A2, 0x3F30E75C}, "acc"); // 0.224 0.770 0.691
    expect_words(s.gyr_dps, {0xC25AD4E2, 0xC1A09DE5, 0xC2EE23EB}, "gyr");
    expect_words(s.mag_ut, {0x41997778, 0xC1D1AAAB, 0xC20A2AAB}, "mag");
    expect_words(s.euler_deg, {0x4242E18D, 0xC1A81D8F, 0xC2360C1E}, "euler"); // 48.7 -21.0 -45.5
    expect_words(s.quat, {0x3F5AE5E6, 0x3E9E94C1, 0xBE9EC0B8, 0xBE8DDFBE}, "quat");
    EXPECT_NEAR(s.acc_g[0], 0.2243, 1e-4);
    EXPECT_EQ(run->stats().crc_failures, 0u);
    EXPECT_EQ(run->stats().bytes_skipped, 0u);
    run->expect_bytes_accounted();
}

TEST(HipnucVectors, Vector1ForcedStatusLayoutReadsTheReservedBytes)
{
    auto run = make_run(HIPNUC_LAYOUT_STATUS_WORD);
    run->feed(hex_bytes(kVector1));
    ASSERT_EQ(run->frames.size(), 1u);
    const hipnuc_sample &s = run->frames[0].samples[0];
    EXPECT_EQ(s.fields, HIPNUC_FIELD_STATUS | HIPNUC_FIELD_PRESSURE | kImusolFields);
    EXPECT_EQ(s.status, 0xA000); // "00 A0"
    EXPECT_EQ(s.temperature_c, 0x3B);
    EXPECT_EQ(bits(s.pressure_pa), 0x9702A801u);
}

TEST(HipnucVectors, Vector2SdkExampleUsesStatusWordLayout)
{
    auto run = make_run();
    run->feed(hex_bytes(kVector2));
    ASSERT_EQ(run->frames.size(), 1u);
    ASSERT_EQ(run->frames[0].sample_count, 1u);
    const hipnuc_sample &s = run->frames[0].samples[0];
    // "91 0815 23 09A2C447": status 0x1508, 0x23 = 35 C, pressure word 0x47C4A209 = 100676.07 Pa.
    EXPECT_EQ(s.fields, HIPNUC_FIELD_STATUS | HIPNUC_FIELD_PRESSURE | kImusolFields);
    EXPECT_EQ(s.status, 0x1508);
    EXPECT_EQ(s.temperature_c, 35);
    EXPECT_EQ(bits(s.pressure_pa), 0x47C4A209u);
    EXPECT_NEAR(s.pressure_pa, 100676.07, 0.01);
    EXPECT_EQ(s.time_ms, 1840392u); // "08151C00" = 0x001C1508
    // "CCE861BE 9A35563E 65EA723F" = -0.2206, 0.2092, 0.9489 g
    expect_words(s.acc_g, {0xBE61E8CC, 0x3E56359A, 0x3F72EA65}, "acc");
    EXPECT_NEAR(s.acc_g[0], -0.22, 0.005);
    EXPECT_NEAR(s.acc_g[1], 0.21, 0.005);
    EXPECT_NEAR(s.acc_g[2], 0.95, 0.005);
    expect_words(s.gyr_dps, {0xBD7CD031, 0xBBC5DD75, 0xBC24D76B}, "gyr");
    expect_words(s.mag_ut, {0x40FC8889, 0x416A0001, 0xC2702AAB}, "mag");
    expect_words(s.euler_deg, {0x4150D496, 0x414303ED, 0xC2F4F441}, "euler");
    expect_words(s.quat, {0xBEF8CACC, 0xBE196A73, 0x3D1C00F0, 0x3F5C378D}, "quat");
    const double norm = std::sqrt(double(s.quat[0]) * s.quat[0] + double(s.quat[1]) * s.quat[1] +
                                  double(s.quat[2]) * s.quat[2] + double(s.quat[3]) * s.quat[3]);
    EXPECT_NEAR(norm, 1.0, 1e-3);
    run->expect_bytes_accounted();
}

TEST(HipnucVectors, Vector2ForcedNodeIdLayout)
{
    auto run = make_run(HIPNUC_LAYOUT_NODE_ID);
    run->feed(hex_bytes(kVector2));
    ASSERT_EQ(run->frames.size(), 1u);
    const hipnuc_sample &s = run->frames[0].samples[0];
    EXPECT_EQ(s.fields, HIPNUC_FIELD_NODE_ID | kImusolFields);
    EXPECT_EQ(s.node_id, 8u);
    EXPECT_EQ(s.pressure_pa, 0.f);
}

TEST(HipnucVectors, Vector3ChainedAccGyrEuler)
{
    // Payload (21 bytes) walked by item size: "A0 EAFF D003 45FF" "B0 0000 0000 0000"
    // "D0 8700 6F27 F5FF". The manual's "A0 + D0 + B0 + D0" counts the 0xD0 byte inside the
    // acceleration item; walking by size must not treat it as a tag.
    auto run = make_run();
    run->feed(hex_bytes(kVector3));
    ASSERT_EQ(run->frames.size(), 1u);
    const hipnuc_frame &f = run->frames[0];
    EXPECT_EQ(f.first_tag, 0xA0);
    ASSERT_EQ(f.sample_count, 1u);
    const hipnuc_sample &s = f.samples[0];
    EXPECT_EQ(s.fields, HIPNUC_FIELD_ACC | HIPNUC_FIELD_GYR | HIPNUC_FIELD_EULER);
    EXPECT_EQ(s.source_tag, 0xA0);
    EXPECT_FLOAT_EQ(s.acc_g[0], -22 * 0.001f);  // 0xFFEA
    EXPECT_FLOAT_EQ(s.acc_g[1], 976 * 0.001f);  // 0x03D0
    EXPECT_FLOAT_EQ(s.acc_g[2], -187 * 0.001f); // 0xFF45
    for (float g : s.gyr_dps) EXPECT_EQ(g, 0.f);
    EXPECT_FLOAT_EQ(s.euler_deg[0], 10095 * 0.01f); // roll  0x276F / 100
    EXPECT_FLOAT_EQ(s.euler_deg[1], 135 * 0.01f);   // pitch 0x0087 / 100
    EXPECT_FLOAT_EQ(s.euler_deg[2], -11 * 0.1f);    // yaw   0xFFF5 / 10
    EXPECT_EQ(run->stats().unknown_tags, 0u);
    EXPECT_EQ(run->stats().truncated_packets, 0u);
}

TEST(HipnucVectors, Vector4ChainedAllItems)
{
    auto run = make_run();
    run->feed(hex_bytes(kVector4));
    ASSERT_EQ(run->frames.size(), 1u);
    ASSERT_EQ(run->frames[0].sample_count, 1u);
    const hipnuc_sample &s = run->frames[0].samples[0];
    EXPECT_EQ(s.fields, HIPNUC_FIELD_NODE_ID | HIPNUC_FIELD_ACC | HIPNUC_FIELD_GYR |
                            HIPNUC_FIELD_MAG | HIPNUC_FIELD_EULER | HIPNUC_FIELD_PRESSURE);
    EXPECT_EQ(s.source_tag, 0x90);
    EXPECT_EQ(s.node_id, 0u);                    // "90 00"
    EXPECT_FLOAT_EQ(s.acc_g[0], 597 * 0.001f);   // 0x0255
    EXPECT_FLOAT_EQ(s.acc_g[1], 317 * 0.001f);   // 0x013D
    EXPECT_FLOAT_EQ(s.acc_g[2], 738 * 0.001f);   // 0x02E2
    EXPECT_FLOAT_EQ(s.gyr_dps[0], -2 * 0.1f);    // 0xFFFE
    EXPECT_FLOAT_EQ(s.gyr_dps[1], 23 * 0.1f);    // 0x0017
    EXPECT_FLOAT_EQ(s.gyr_dps[2], 68 * 0.1f);    // 0x0044
    EXPECT_FLOAT_EQ(s.mag_ut[0], -128 * 0.1f);   // 0xFF80 mGauss; 1 mGauss = 0.1 uT
    EXPECT_FLOAT_EQ(s.mag_ut[1], -160 * 0.1f);   // 0xFF60
    EXPECT_FLOAT_EQ(s.mag_ut[2], -206 * 0.1f);   // 0xFF32
    EXPECT_FLOAT_EQ(s.euler_deg[0], 3692 * 0.01f);  // roll  0x0E6C / 100 (second word)
    EXPECT_FLOAT_EQ(s.euler_deg[1], -3484 * 0.01f); // pitch 0xF264 / 100 (first word)
    EXPECT_FLOAT_EQ(s.euler_deg[2], 443 * 0.1f);    // yaw   0x01BB / 10
    EXPECT_EQ(s.pressure_pa, 0.f);               // "F0 00000000"
    run->expect_bytes_accounted();
}

TEST(HipnucVectors, EncoderReproducesVectorBytes)
{
    // Re-framing a vector's payload must reproduce its header and CRC exactly.
    for (const char *hex : {kVector1, kVector2, kVector3, kVector4}) {
        const Bytes frame = hex_bytes(hex);
        const Bytes payload(frame.begin() + HIPNUC_HEADER_SIZE, frame.end());
        EXPECT_EQ(frame_of(payload), frame) << hex;
    }
    // Vector 2 uses all 76 bytes in the status layout, so the block re-encodes byte-exactly.
    auto run = make_run();
    run->feed(hex_bytes(kVector2));
    ASSERT_EQ(run->frames.size(), 1u);
    const Bytes block = imusol_payload(run->frames[0].samples[0], HIPNUC_LAYOUT_STATUS_WORD);
    EXPECT_EQ(frame_of(block), hex_bytes(kVector2));
}

// ---- Stream handling ----

TEST(HipnucStream, ChunkingDoesNotChangeTheResult)
{
    // A stream exercising every path: garbage, all vectors, gateway frames, a bad CRC, a bad
    // length, a corrupted length field, stray sync bytes.
    Bytes stream = {0x00, 0x5A, 0x11, 0xA5, 0x5A};
    append(stream, hex_bytes(kVector1));
    append(stream, {0x5A, 0xA5, 0x00, 0x00});
    append(stream, hex_bytes(kVector2));
    Bytes bad = hex_bytes(kVector3);
    bad[10] ^= 0x40;
    append(stream, bad);
    append(stream, hex_bytes(kVector3));
    for (uint32_t t = 0; t < 20; t++) append(stream, frame_of(gwsol_payload(3, nodes(6, t))));
    Bytes lying = hex_bytes(kVector4);
    lying[3] = 0x07; // claims 0x0723 = 1827 bytes, swallowing frames that follow
    append(stream, lying);
    append(stream, hex_bytes(kVector4));
    for (uint32_t t = 0; t < 10; t++) append(stream, frame_of(gwsol_payload(4, nodes(16, t))));
    append(stream, {0x5A, 0xA5, 0x4C});

    auto whole = make_run();
    whole->feed(stream);
    // v1, v2, v3, 20 gateway frames, v4, 10 gateway frames; the corrupted v3 and the lying v4
    // fail their CRC, "5A A5 00 00" is a bad length.
    ASSERT_EQ(whole->frames.size(), 3u + 20u + 1u + 10u);
    EXPECT_EQ(whole->stats().crc_failures, 2u);
    EXPECT_EQ(whole->stats().bad_lengths, 1u);
    whole->expect_bytes_accounted();

    auto bytewise = make_run();
    bytewise->feed_bytewise(stream);
    bytewise->expect_bytes_accounted();

    for (uint32_t seed = 1; seed <= 20; seed++) {
        auto chunked = make_run();
        chunked->feed_random_chunks(stream, seed, seed < 10 ? 16 : 3000);
        chunked->expect_bytes_accounted();
        for (DecodeRun *other : {bytewise.get(), chunked.get()}) {
            ASSERT_EQ(other->frames.size(), whole->frames.size()) << "seed " << seed;
            for (size_t i = 0; i < whole->frames.size(); i++)
                ASSERT_TRUE(frames_equal(other->frames[i], whole->frames[i])) << "frame " << i;
            ASSERT_EQ(std::memcmp(&other->dec.stats, &whole->dec.stats, sizeof(hipnuc_stats)), 0);
            ASSERT_EQ(other->dec.length, whole->dec.length);
        }
    }
    // The trailing "5A A5 4C" is an incomplete header waiting for more bytes.
    EXPECT_EQ(whole->dec.length, 3u);
}

TEST(HipnucStream, GarbageBeforeAndBetweenFramesIsSkippedAndCounted)
{
    Bytes stream = {0x01, 0x02, 0x03};               // 3 bytes without a sync
    append(stream, hex_bytes(kVector1));
    append(stream, {0x5A, 0x00, 0xA5, 0xA5, 0x5A}); // stray syncs: 5 bytes
    append(stream, hex_bytes(kVector4));
    append(stream, {0xFF, 0x5A});                    // 2 bytes...
    append(stream, hex_bytes(kVector3));             // ...and "5A 5A A5" resyncs on the second
    for (auto feeder : {0, 1}) {
        auto run = make_run();
        if (feeder == 0) run->feed(stream); else run->feed_bytewise(stream);
        ASSERT_EQ(run->frames.size(), 3u);
        EXPECT_EQ(run->frames[0].first_tag, 0x91);
        EXPECT_EQ(run->frames[1].first_tag, 0x90);
        EXPECT_EQ(run->frames[2].first_tag, 0xA0);
        EXPECT_EQ(run->stats().bytes_skipped, 3u + 5u + 2u);
        EXPECT_EQ(run->stats().crc_failures, 0u);
        EXPECT_EQ(run->stats().bad_lengths, 0u);
        EXPECT_EQ(run->dec.length, 0u);
        run->expect_bytes_accounted();
    }
}

TEST(HipnucStream, TruncatedFrameIsSkippedAndTheNextFrameDecoded)
{
    const Bytes v2 = hex_bytes(kVector2);
    Bytes stream(v2.begin(), v2.begin() + 40); // cut inside its payload
    // The cut frame has a single 0x5A (its sync), so rescanning skips all 40 of its bytes.
    ASSERT_EQ(std::count(stream.begin(), stream.end(), 0x5A), 1);
    append(stream, hex_bytes(kVector1));
    append(stream, hex_bytes(kVector3));
    auto run = make_run();
    run->feed(stream);
    ASSERT_EQ(run->frames.size(), 2u);
    EXPECT_EQ(run->frames[0].samples[0].time_ms, 310205u); // vector 1
    EXPECT_EQ(run->frames[1].first_tag, 0xA0);
    EXPECT_EQ(run->stats().crc_failures, 1u);
    EXPECT_EQ(run->stats().bytes_skipped, 40u);
    run->expect_bytes_accounted();

    // A frame cut by the end of the input waits in the buffer and completes with the next feed.
    auto tail = make_run();
    const Bytes v1 = hex_bytes(kVector1);
    tail->feed(v1.data(), 50);
    EXPECT_TRUE(tail->frames.empty());
    EXPECT_EQ(tail->dec.length, 50u);
    tail->feed(v1.data() + 50, v1.size() - 50);
    EXPECT_EQ(tail->frames.size(), 1u);
    EXPECT_EQ(tail->dec.length, 0u);

    // reset() drops the pending bytes: the rest of the frame is then garbage.
    auto reset = make_run();
    reset->feed(v1.data(), 50);
    hipnuc_decoder_reset(&reset->dec);
    EXPECT_EQ(reset->dec.length, 0u);
    reset->feed(v1.data() + 50, v1.size() - 50);
    EXPECT_TRUE(reset->frames.empty());
    EXPECT_EQ(reset->stats().bytes_skipped, v1.size() - 50);
}

TEST(HipnucStream, ImpossibleLengthsResyncImmediately)
{
    const uint16_t lengths[] = {0, HIPNUC_MAX_PAYLOAD + 1, 0xFFFF};
    for (uint16_t len : lengths) {
        Bytes stream = {0x5A, 0xA5, static_cast<uint8_t>(len), static_cast<uint8_t>(len >> 8)};
        // Alone, the header is rejected at once: nothing is held back waiting for a payload.
        auto alone = make_run();
        alone->feed(stream);
        EXPECT_EQ(alone->dec.length, 0u) << len;
        EXPECT_EQ(alone->stats().bad_lengths, 1u);
        EXPECT_EQ(alone->stats().bytes_skipped, 4u);

        append(stream, hex_bytes(kVector2));
        for (auto feeder : {0, 1}) {
            auto run = make_run();
            if (feeder == 0) run->feed(stream); else run->feed_bytewise(stream);
            ASSERT_EQ(run->frames.size(), 1u) << len;
            EXPECT_EQ(run->stats().bad_lengths, 1u);
            EXPECT_EQ(run->stats().bytes_skipped, 4u);
            EXPECT_EQ(run->stats().crc_failures, 0u);
            run->expect_bytes_accounted();
        }
    }
    // The largest legal length is accepted (a 32-node gateway packet).
    auto run = make_run();
    run->feed(frame_of(gwsol_payload(1, nodes(HIPNUC_MAX_NODES, 0))));
    ASSERT_EQ(run->frames.size(), 1u);
    EXPECT_EQ(run->frames[0].payload_length, HIPNUC_MAX_PAYLOAD);
    EXPECT_EQ(run->stats().bad_lengths, 0u);
}

TEST(HipnucStream, CrcFailuresAreCountedAndFollowingFramesKept)
{
    Bytes stream;
    for (int i = 0; i < 3; i++) {
        Bytes bad = hex_bytes(kVector1);
        bad[20 + i] ^= 0x01; // payload bit
        append(stream, bad);
        append(stream, hex_bytes(kVector4));
    }
    Bytes bad_crc = hex_bytes(kVector3);
    bad_crc[4] ^= 0x80; // the CRC field itself
    append(stream, bad_crc);
    auto run = make_run();
    run->feed(stream);
    EXPECT_EQ(run->frames.size(), 3u);
    for (const auto &f : run->frames) EXPECT_EQ(f.first_tag, 0x90);
    EXPECT_EQ(run->stats().crc_failures, 4u);
    // The rejected frames hold no 5A A5 pair besides their sync, so all their bytes are skipped.
    EXPECT_EQ(run->stats().bytes_skipped, 3 * hex_bytes(kVector1).size() + bad_crc.size());
    run->expect_bytes_accounted();
}

TEST(HipnucStream, CorruptedLengthFieldDoesNotLoseFollowingFrames)
{
    Bytes lying = hex_bytes(kVector1);
    lying[2] = 0x00;
    lying[3] = 0x09; // 0x0900 = 2304 payload bytes: the candidate swallows the frames behind it
    Bytes stream = lying;
    const uint32_t followers = 20;
    for (uint32_t t = 0; t < followers; t++)
        append(stream, frame_of(gwsol_payload(9, nodes(2, t))));
    const size_t claimed_end = HIPNUC_HEADER_SIZE + 0x0900;
    const size_t follower_size =
        HIPNUC_HEADER_SIZE + HIPNUC_GWSOL_HEADER_SIZE + 2 * HIPNUC_IMUSOL_SIZE;
    ASSERT_LT(lying.size() + 10 * follower_size, claimed_end); // >= 10 frames lie inside
    ASSERT_GT(stream.size(), claimed_end);                     // and the candidate can be judged
    for (auto feeder : {0, 1, 2}) {
        auto run = make_run();
        if (feeder == 0) run->feed(stream);
        else if (feeder == 1) run->feed_bytewise(stream);
        else run->feed_random_chunks(stream, 99, 700);
        ASSERT_EQ(run->frames.size(), followers) << "feeder " << feeder;
        for (uint32_t t = 0; t < followers; t++) {
            EXPECT_EQ(run->frames[t].gateway_id, 9);
            ASSERT_EQ(run->frames[t].sample_count, 2u);
            EXPECT_EQ(run->frames[t].samples[0].time_ms, t);
        }
        EXPECT_EQ(run->stats().crc_failures, 1u);
        // Vector 1 has no 5A A5 pair besides its sync, so all of the lying frame is skipped.
        EXPECT_EQ(run->stats().bytes_skipped, lying.size());
        EXPECT_EQ(run->dec.length, 0u);
        run->expect_bytes_accounted();
    }
}

// At the end of a stream no byte will complete a candidate whose length field was corrupted:
// flush gives up on it and delivers the intact frames it was holding, losing nothing else.
TEST(HipnucStream, FlushAtEndOfInputDeliversFramesHeldBehindACorruptedLength)
{
    Bytes lying = hex_bytes(kVector1);
    lying[2] = 0x00;
    lying[3] = 0x09; // claims 2304 payload bytes, more than the rest of the stream holds
    Bytes stream = lying;
    const uint32_t followers = 5;
    for (uint32_t t = 0; t < followers; t++)
        append(stream, frame_of(gwsol_payload(7, nodes(3, t))));
    Bytes partial = frame_of(gwsol_payload(7, nodes(3, 99)));
    partial.resize(partial.size() / 2); // a frame cut off by the end of the capture
    append(stream, partial);
    ASSERT_LT(stream.size(), HIPNUC_HEADER_SIZE + 0x0900u);
    for (auto feeder : {0, 1}) {
        auto run = make_run();
        if (feeder == 0) run->feed(stream);
        else run->feed_random_chunks(stream, 5, 300);
        EXPECT_EQ(run->frames.size(), 0u) << "everything waits behind the lying length";
        hipnuc_decoder_flush(&run->dec, DecodeRun::on_frame, run.get());
        ASSERT_EQ(run->frames.size(), followers);
        for (uint32_t t = 0; t < followers; t++) EXPECT_EQ(run->frames[t].samples[0].time_ms, t);
        EXPECT_EQ(run->dec.length, 0u);
        EXPECT_EQ(run->stats().bytes_skipped, lying.size() + partial.size());
        run->expect_bytes_accounted();
    }
    auto empty = make_run();
    hipnuc_decoder_flush(&empty->dec, DecodeRun::on_frame, empty.get()); // nothing buffered
    EXPECT_EQ(empty->stats().bytes_skipped, 0u);
}

// ---- Packet contents ----

TEST(HipnucPackets, GatewayNodeCountBeyondThePayloadIsTruncated)
{
    Bytes payload = gwsol_payload(2, nodes(6, 100));
    payload[2] = 7; // claims one node more than present
    auto run = make_run();
    run->feed(frame_of(payload));
    ASSERT_EQ(run->frames.size(), 1u); // CRC-valid frames are always delivered
    EXPECT_EQ(run->frames[0].sample_count, 0u);
    EXPECT_EQ(run->stats().truncated_packets, 1u);
    EXPECT_EQ(run->stats().samples, 0u);
    EXPECT_EQ(run->stats().node_overflows, 0u);

    // A payload too short for the gateway header itself.
    hipnuc_frame out;
    hipnuc_stats stats{};
    const uint8_t stub[] = {0x62, 0x01, 0x00};
    EXPECT_EQ(hipnuc_parse_payload(stub, sizeof stub, HIPNUC_LAYOUT_AUTO, &out, &stats), 0);
    EXPECT_EQ(stats.truncated_packets, 1u);
}

TEST(HipnucPackets, GatewayNodeCountAboveMaximumDecodesTheFirstNodes)
{
    // 33 claimed, 32 present: exactly HIPNUC_MAX_PAYLOAD, so it travels as a valid frame.
    Bytes payload = gwsol_payload(5, nodes(HIPNUC_MAX_NODES, 0));
    payload[2] = HIPNUC_MAX_NODES + 1;
    auto run = make_run();
    run->feed(frame_of(payload));
    ASSERT_EQ(run->frames.size(), 1u);
    EXPECT_EQ(run->frames[0].sample_count, static_cast<uint32_t>(HIPNUC_MAX_NODES));
    EXPECT_EQ(run->frames[0].samples[HIPNUC_MAX_NODES - 1].node_id, HIPNUC_MAX_NODES);
    EXPECT_EQ(run->stats().node_overflows, 1u);
    EXPECT_EQ(run->stats().truncated_packets, 0u);

    // Parsed directly, a packet may really hold more nodes than we keep.
    const Bytes big = gwsol_payload(5, nodes(40, 0));
    hipnuc_frame out;
    hipnuc_stats stats{};
    EXPECT_EQ(hipnuc_parse_payload(big.data(), big.size(), HIPNUC_LAYOUT_AUTO, &out, &stats),
              HIPNUC_MAX_NODES);
    EXPECT_EQ(stats.node_overflows, 1u);
    EXPECT_EQ(stats.samples, static_cast<uint64_t>(HIPNUC_MAX_NODES));
}

TEST(HipnucPackets, GatewayBlocksAlwaysCarryNodeIds)
{
    // A block whose bytes 1..7 would pass as a plausible status layout is still read as node id.
    std::vector<hipnuc_sample> v = nodes(2, 0);
    Bytes payload = gwsol_payload(1, v);
    const Bytes plausible = hex_bytes("9108152309A2C447"); // vector 2's first 8 bytes
    std::copy(plausible.begin(), plausible.end(), payload.begin() + HIPNUC_GWSOL_HEADER_SIZE);
    hipnuc_frame out;
    ASSERT_EQ(hipnuc_parse_payload(payload.data(), payload.size(), HIPNUC_LAYOUT_STATUS_WORD, &out,
                                   nullptr),
              2);
    EXPECT_EQ(out.gateway_id, 1);
    EXPECT_EQ(out.samples[0].fields, HIPNUC_FIELD_NODE_ID | kImusolFields);
    EXPECT_EQ(out.samples[0].node_id, 0x08u);
    EXPECT_EQ(out.samples[0].source_tag, HIPNUC_TAG_GWSOL);
    EXPECT_EQ(out.samples[1].node_id, 2u);
}

TEST(HipnucPackets, NonFiniteFloatsAreDeliveredUnchanged)
{
    const float nan = from_bits(0x7FC12345u);
    const float inf = std::numeric_limits<float>::infinity();
    std::vector<hipnuc_sample> v = nodes(3, 5);
    v[0].acc_g[0] = nan;
    v[0].quat[3] = inf;
    v[1].gyr_dps[2] = -inf;
    v[2].euler_deg[1] = nan;
    auto run = make_run();
    run->feed(frame_of(gwsol_payload(1, v)));
    ASSERT_EQ(run->frames.size(), 1u);
    ASSERT_EQ(run->frames[0].sample_count, 3u);
    for (int i = 0; i < 3; i++)
        EXPECT_EQ(std::memcmp(&run->frames[0].samples[i], &v[i], sizeof v[i]), 0) << i;
    EXPECT_EQ(bits(run->frames[0].samples[0].acc_g[0]), 0x7FC12345u);

    // AUTO never picks the status layout on a non-finite or implausible pressure/temperature.
    struct Case { float pressure; int8_t temperature; bool status_layout; };
    const Case cases[] = {{nan, 20, false},          {inf, 20, false},
                          {-inf, 20, false},         {9999.f, 20, false},
                          {120001.f, 20, false},     {101325.f, 101, false},
                          {101325.f, -41, false},    {101325.f, 20, true},
                          {10000.f, -40, true},      {120000.f, 100, true}};
    for (const Case &c : cases) {
        hipnuc_sample s = make_sample(7, 1);
        s.pressure_pa = c.pressure;
        s.temperature_c = c.temperature;
        s.status = 0x0208;
        const Bytes block = imusol_payload(s, HIPNUC_LAYOUT_STATUS_WORD);
        hipnuc_frame out;
        ASSERT_EQ(hipnuc_parse_payload(block.data(), block.size(), HIPNUC_LAYOUT_AUTO, &out,
                                       nullptr),
                  1);
        const hipnuc_sample &d = out.samples[0];
        if (c.status_layout) {
            EXPECT_EQ(d.fields & (HIPNUC_FIELD_STATUS | HIPNUC_FIELD_NODE_ID), HIPNUC_FIELD_STATUS);
            EXPECT_EQ(d.status, 0x0208);
            EXPECT_EQ(d.temperature_c, c.temperature);
            EXPECT_EQ(bits(d.pressure_pa), bits(c.pressure));
        } else {
            EXPECT_EQ(d.fields & (HIPNUC_FIELD_STATUS | HIPNUC_FIELD_NODE_ID),
                      HIPNUC_FIELD_NODE_ID)
                << c.pressure << " " << int(c.temperature);
            EXPECT_EQ(d.node_id, 0x08u); // low byte of the status word
        }
    }
}

TEST(HipnucPackets, UnknownTagStopsParsingButKeepsEarlierSamples)
{
    // 0x91 block, then an unknown tag: the block's sample is delivered.
    Bytes payload = imusol_payload(make_sample(4, 9), HIPNUC_LAYOUT_NODE_ID);
    append(payload, {0x77, 0x91, 0x00});
    auto run = make_run();
    run->feed(frame_of(payload));
    ASSERT_EQ(run->frames.size(), 1u);
    ASSERT_EQ(run->frames[0].sample_count, 1u);
    EXPECT_EQ(run->frames[0].samples[0].node_id, 4u);
    EXPECT_EQ(run->stats().unknown_tags, 1u);

    // Unknown first tag: a frame with no samples.
    run->feed(frame_of({0x33, 0x01, 0x02}));
    ASSERT_EQ(run->frames.size(), 2u);
    EXPECT_EQ(run->frames[1].first_tag, 0x33);
    EXPECT_EQ(run->frames[1].sample_count, 0u);
    EXPECT_EQ(run->stats().unknown_tags, 2u);

    // Inside a chain: "90 05" + "A0 ..." + unknown 0xE0: node id and acc survive.
    run->feed(frame_of({0x90, 0x05, 0xA0, 0x01, 0x00, 0x02, 0x00, 0x03, 0x00, 0xE0, 0xB0}));
    ASSERT_EQ(run->frames.size(), 3u);
    ASSERT_EQ(run->frames[2].sample_count, 1u);
    const hipnuc_sample &s = run->frames[2].samples[0];
    EXPECT_EQ(s.fields, HIPNUC_FIELD_NODE_ID | HIPNUC_FIELD_ACC);
    EXPECT_EQ(s.node_id, 5u);
    EXPECT_FLOAT_EQ(s.acc_g[2], 0.003f);
    EXPECT_EQ(run->stats().unknown_tags, 3u);

    // A gateway block that is not 0x91 counts as an unknown tag; earlier blocks are kept.
    Bytes gw = gwsol_payload(1, nodes(3, 0));
    gw[HIPNUC_GWSOL_HEADER_SIZE + 2 * HIPNUC_IMUSOL_SIZE] = 0x92;
    run->feed(frame_of(gw));
    ASSERT_EQ(run->frames.size(), 4u);
    EXPECT_EQ(run->frames[3].sample_count, 2u);
    EXPECT_EQ(run->stats().unknown_tags, 4u);
    EXPECT_EQ(run->stats().frames_ok, 4u);
    run->expect_bytes_accounted();
}

TEST(HipnucPackets, LegacyChainQuaternionPressureAndTruncation)
{
    Bytes p = {0xD1};
    for (uint32_t w : {0x3F800000u, 0x00000000u, 0xBF000000u, 0x3E800000u}) // 1, 0, -0.5, 0.25
        for (int i = 0; i < 4; i++) p.push_back(static_cast<uint8_t>(w >> (8 * i)));
    append(p, {0xF0, 0x00, 0x50, 0xC3, 0x47}); // 0x47C35000 = 100000 Pa
    append(p, {0x90, 0x02, 0x90, 0x03});       // a repeated item overwrites: node id 3
    append(p, {0xB0, 0x0A, 0x00});             // 0xB0 needs 7 bytes: truncated
    hipnuc_frame out;
    hipnuc_stats stats{};
    ASSERT_EQ(hipnuc_parse_payload(p.data(), p.size(), HIPNUC_LAYOUT_AUTO, &out, &stats), 1);
    const hipnuc_sample &s = out.samples[0];
    EXPECT_EQ(s.source_tag, 0xD1);
    EXPECT_EQ(s.fields, HIPNUC_FIELD_QUAT | HIPNUC_FIELD_PRESSURE | HIPNUC_FIELD_NODE_ID);
    EXPECT_EQ(s.quat[0], 1.f);
    EXPECT_EQ(s.quat[2], -0.5f);
    EXPECT_EQ(s.quat[3], 0.25f);
    EXPECT_EQ(s.pressure_pa, 100000.f);
    EXPECT_EQ(s.node_id, 3u);
    EXPECT_EQ(stats.truncated_packets, 1u);
    EXPECT_EQ(stats.unknown_tags, 0u);

    // A 0x91 block cut short.
    Bytes cut = imusol_payload(make_sample(1, 1), HIPNUC_LAYOUT_NODE_ID);
    cut.resize(HIPNUC_IMUSOL_SIZE - 1);
    hipnuc_stats cut_stats{};
    EXPECT_EQ(
        hipnuc_parse_payload(cut.data(), cut.size(), HIPNUC_LAYOUT_AUTO, &out, &cut_stats), 0);
    EXPECT_EQ(cut_stats.truncated_packets, 1u);
}

// ---- Encoding ----

TEST(HipnucEncode, GatewayRoundTripIn16And32NodesWithArbitraryChunks)
{
    for (uint32_t count : {16u, 32u}) {
        Bytes stream;
        std::vector<std::vector<hipnuc_sample>> sent;
        for (uint32_t t = 0; t < 12; t++) {
            sent.push_back(nodes(count, 1000 * t));
            append(stream, frame_of(gwsol_payload(static_cast<uint8_t>(t), sent.back())));
        }
        for (uint32_t seed = 0; seed < 8; seed++) {
            auto run = make_run();
            if (seed == 0) run->feed_bytewise(stream);
            else run->feed_random_chunks(stream, seed, 1 + seed * 700);
            ASSERT_EQ(run->frames.size(), sent.size());
            for (size_t t = 0; t < sent.size(); t++) {
                const hipnuc_frame &f = run->frames[t];
                EXPECT_EQ(f.first_tag, HIPNUC_TAG_GWSOL);
                EXPECT_EQ(f.gateway_id, t);
                ASSERT_EQ(f.sample_count, count);
                for (uint32_t i = 0; i < count; i++)
                    ASSERT_EQ(std::memcmp(&f.samples[i], &sent[t][i], sizeof(hipnuc_sample)), 0)
                        << "count " << count << " frame " << t << " node " << i;
            }
            EXPECT_EQ(run->stats().samples, uint64_t{count} * sent.size());
            EXPECT_EQ(run->stats().bytes_skipped, 0u);
            run->expect_bytes_accounted();
        }
    }
}

TEST(HipnucEncode, ImusolStatusLayoutRoundTrip)
{
    hipnuc_sample s = make_sample(0, 123456);
    s.fields = HIPNUC_FIELD_STATUS | HIPNUC_FIELD_PRESSURE | kImusolFields;
    s.node_id = 0;
    s.status = 0x0E18;
    s.temperature_c = -12;
    s.pressure_pa = 95000.5f;
    s.source_tag = HIPNUC_TAG_IMUSOL;
    hipnuc_frame out;
    const Bytes block = imusol_payload(s, HIPNUC_LAYOUT_STATUS_WORD);
    ASSERT_EQ(hipnuc_parse_payload(block.data(), block.size(), HIPNUC_LAYOUT_AUTO, &out, nullptr),
              1);
    EXPECT_EQ(std::memcmp(&out.samples[0], &s, sizeof s), 0);
}

TEST(HipnucEncode, FrameLimits)
{
    Bytes payload(HIPNUC_MAX_PAYLOAD + 1, 0x91);
    Bytes out(HIPNUC_HEADER_SIZE + payload.size());
    EXPECT_EQ(hipnuc_encode_frame(payload.data(), payload.size(), out.data(), out.size()), 0u);
    EXPECT_EQ(hipnuc_encode_frame(payload.data(), 10, out.data(), 15), 0u); // cap too small
    EXPECT_EQ(hipnuc_encode_frame(payload.data(), 10, out.data(), 16), 16u);

    // The payload may already sit where the frame puts it.
    const Bytes v3 = hex_bytes(kVector3);
    Bytes buf(v3.size(), 0xEE);
    std::copy(v3.begin() + HIPNUC_HEADER_SIZE, v3.end(), buf.begin() + HIPNUC_HEADER_SIZE);
    EXPECT_EQ(hipnuc_encode_frame(buf.data() + HIPNUC_HEADER_SIZE, v3.size() - HIPNUC_HEADER_SIZE,
                                  buf.data(), buf.size()),
              v3.size());
    EXPECT_EQ(buf, v3);

    std::vector<hipnuc_sample> v = nodes(6, 0);
    Bytes gw(HIPNUC_GWSOL_HEADER_SIZE + 6 * HIPNUC_IMUSOL_SIZE);
    EXPECT_EQ(hipnuc_encode_gwsol(1, v.data(), 6, gw.data(), gw.size() - 1), 0u);
    EXPECT_EQ(hipnuc_encode_gwsol(1, v.data(), 6, gw.data(), gw.size()), 464u);
    EXPECT_EQ(gw[0], 0x62);
    EXPECT_EQ(gw[2], 6);
}
