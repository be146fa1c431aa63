// CRC-16/XMODEM and CRC-32 against their catalogue check values and against bit-by-bit
// references, at every length and alignment the sliced implementations distinguish.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "crc.h"

namespace {

// Straight from the definitions: MSB-first, poly 0x1021, no reflection, no xor-out.
uint16_t crc16_bitwise(uint16_t crc, const uint8_t *data, size_t len)
{
    for (size_t i = 0; i < len; i++) {
        crc ^= static_cast<uint16_t>(data[i] << 8);
        for (int b = 0; b < 8; b++)
            crc = (crc & 0x8000) ? static_cast<uint16_t>((crc << 1) ^ 0x1021)
                                 : static_cast<uint16_t>(crc << 1);
    }
    return crc;
}

// Reflected poly 0xEDB88320, init and xor-out 0xFFFFFFFF, continued like zlib's crc32().
uint32_t crc32_bitwise(uint32_t crc, const uint8_t *data, size_t len)
{
    crc = ~crc;
    for (size_t i = 0; i < len; i++) {
        crc ^= data[i];
        for (int b = 0; b < 8; b++) crc = (crc & 1) ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
    }
    return ~crc;
}

std::vector<uint8_t> random_bytes(size_t n, uint32_t seed)
{
    std::mt19937 rng(seed);
    std::vector<uint8_t> out(n);
    for (auto &b : out) b = static_cast<uint8_t>(rng());
    return out;
}

const uint8_t kCheck[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};

} // namespace

TEST(Crc16Xmodem, CatalogueCheckValue)
{
    EXPECT_EQ(crc16_xmodem_update(0, kCheck, sizeof kCheck), 0x31C3);
}

TEST(Crc32, CatalogueCheckValue)
{
    EXPECT_EQ(crc32_update(0, kCheck, sizeof kCheck), 0xCBF43926u);
    const char *fox = "The quick brown fox jumps over the lazy dog";
    EXPECT_EQ(crc32_update(0, reinterpret_cast<const uint8_t *>(fox), std::strlen(fox)),
              0x414FA339u);
}

TEST(Crc, EmptyInputLeavesValueUnchanged)
{
    EXPECT_EQ(crc16_xmodem_update(0x1234, nullptr, 0), 0x1234);
    EXPECT_EQ(crc32_update(0, nullptr, 0), 0u);
    EXPECT_EQ(crc32_update(0xDEADBEEFu, nullptr, 0), 0xDEADBEEFu);
}

TEST(Crc, MatchesBitwiseReferenceAtEveryLengthAndAlignment)
{
    const auto data = random_bytes(256, 7);
    for (size_t offset = 0; offset < 8; offset++) {
        for (size_t len = 0; len + offset <= 100; len++) {
            const uint8_t *p = data.data() + offset;
            ASSERT_EQ(crc16_xmodem_update(0, p, len), crc16_bitwise(0, p, len))
                << "offset " << offset << " len " << len;
            ASSERT_EQ(crc16_xmodem_update(0xBEEF, p, len), crc16_bitwise(0xBEEF, p, len));
            ASSERT_EQ(crc32_update(0, p, len), crc32_bitwise(0, p, len))
                << "offset " << offset << " len " << len;
            ASSERT_EQ(crc32_update(0x12345678u, p, len), crc32_bitwise(0x12345678u, p, len));
        }
    }
}

TEST(Crc, LargeBufferMatchesReference)
{
    const auto data = random_bytes(70001, 11);
    EXPECT_EQ(crc16_xmodem_update(0, data.data(), data.size()),
              crc16_bitwise(0, data.data(), data.size()));
    EXPECT_EQ(crc32_update(0, data.data(), data.size()),
              crc32_bitwise(0, data.data(), data.size()));
}

TEST(Crc, ContinuationEqualsOneShot)
{
    const auto data = random_bytes(300, 3);
    const uint16_t whole16 = crc16_xmodem_update(0, data.data(), data.size());
    const uint32_t whole32 = crc32_update(0, data.data(), data.size());
    for (size_t split = 0; split <= data.size(); split++) {
        uint16_t c16 = crc16_xmodem_update(0, data.data(), split);
        c16 = crc16_xmodem_update(c16, data.data() + split, data.size() - split);
        ASSERT_EQ(c16, whole16) << "split " << split;
        uint32_t c32 = crc32_update(0, data.data(), split);
        c32 = crc32_update(c32, data.data() + split, data.size() - split);
        ASSERT_EQ(c32, whole32) << "split " << split;
    }
}

TEST(Crc16Xmodem, SingleBitFlipsAreDetected)
{
    auto data = random_bytes(64, 5);
    const uint16_t good = crc16_xmodem_update(0, data.data(), data.size());
    for (size_t bit = 0; bit < data.size() * 8; bit++) {
        data[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
        ASSERT_NE(crc16_xmodem_update(0, data.data(), data.size()), good) << "bit " << bit;
        data[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    }
}
