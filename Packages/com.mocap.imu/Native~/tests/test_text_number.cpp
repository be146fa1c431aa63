// Numbers in the engine's text formats are '.'-decimal whatever LC_NUMERIC the host process set:
// the conversions with an explicit locale point, then the real files in a real comma locale
// (de_DE, generated with localedef: the host may run with the user's locale).
#include <gtest/gtest.h>

#include <clocale>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "test_support.h"

extern "C" {
#include "bvh_writer.h"
#include "calibration.h"
#include "error.h"
#include "onnx_runtime.h"
#include "text_number.h"
}

namespace {

const std::filesystem::path kTestsDir = std::filesystem::path(__FILE__).parent_path();
const std::string kShippedModel =
    (kTestsDir / ".." / ".." / "Runtime" / "Models" / "mocap_pose_fp32.onnx").string();

// Switches LC_NUMERIC to German (decimal comma) for one test and back; skips when the machine
// cannot build that locale.
struct CommaLocale {
    std::string previous;
    bool active = false;

    void enter()
    {
#if defined(_WIN32)
        // Windows has German built in (a name msvcrt and the UCRT both accept).
        const char *current = std::setlocale(LC_NUMERIC, nullptr);
        previous = current ? current : "C";
        active = std::setlocale(LC_NUMERIC, "German_Germany.1252") != nullptr;
#else
        const std::string dir = test_temp_dir() + "/locales";
        std::filesystem::create_directories(dir);
        const std::string cmd = "localedef -i de_DE -f UTF-8 \"" + dir + "/de_DE.UTF-8\" >/dev/null 2>&1";
        if (std::system(cmd.c_str()) != 0 && !std::filesystem::exists(dir + "/de_DE.UTF-8")) return;
        setenv("LOCPATH", dir.c_str(), 1);
        const char *now = std::setlocale(LC_NUMERIC, nullptr);
        previous = now ? now : "C";
        active = std::setlocale(LC_NUMERIC, "de_DE.UTF-8") != nullptr;
#endif
    }
    ~CommaLocale()
    {
        if (active) std::setlocale(LC_NUMERIC, previous.c_str());
    }
};

}  // namespace

TEST(TextNumber, UseDotRewritesTheLocalePoint)
{
    char text[32] = "0,5 1,25";
    text_use_dot(text, ',');
    EXPECT_STREQ(text, "0.5 1.25");
    char same[16] = "0.5";
    text_use_dot(same, '.');
    EXPECT_STREQ(same, "0.5");
}

TEST(TextNumber, FilesAreWrittenAndReadWithADotInACommaLocale)
{
    CommaLocale locale;
    locale.enter();
    if (!locale.active) GTEST_SKIP() << "no de_DE locale could be built here (localedef)";
    char probe[16];
    snprintf(probe, sizeof probe, "%g", 0.5);
    ASSERT_STREQ(probe, "0,5") << "the locale is not a comma locale";
    ASSERT_EQ(text_locale_point(), ',');

    // The conversions: '.' in, '.' out, ',' is a separator as in the C locale.
    char *end = nullptr;
    const char *list = "0.75,1.5";
    EXPECT_EQ(text_strtod(list, &end), 0.75);
    EXPECT_EQ(end, list + 4);
    const char *spaced = "  -1.25e-3 rest";
    EXPECT_EQ(text_strtod(spaced, &end), -1.25e-3);
    EXPECT_EQ(end, spaced + 10);
    const char *none = "x1";
    text_strtod(none, &end);
    EXPECT_EQ(end, none);
    EXPECT_TRUE(std::isinf(text_strtod("inf", &end)));
    char formatted[32];
    text_format_double(formatted, sizeof formatted, "%.3f", 2.5);
    EXPECT_STREQ(formatted, "2.500");

    // A calibration file: '.' on disk, read back bit for bit.
    static mocap_calibration cal, loaded;
    const int32_t six[6] = {0, 1, 2, 3, 4, 5};
    calib_identity(&cal, 6, six);
    cal.valid_mask = 0x3F;
    cal.heading_mask = 0x3F;
    cal.acceleration_offset[2][1] = 0.125f;
    cal.world_to_model[1][0] = 0.6f;
    cal.world_to_model[1][1] = 0.8f;
    cal.world_to_model[1][3] = -0.8f;
    cal.world_to_model[1][4] = 0.6f;
    const std::string cal_path = test_temp_path("comma.calibration");
    ASSERT_EQ(calib_save(&cal, cal_path.c_str()), MOCAP_OK) << mocap_last_error();
    const auto cal_bytes = read_file_bytes(cal_path);
    const std::string cal_text(cal_bytes.begin(), cal_bytes.end());
    EXPECT_NE(cal_text.find(" 0.125"), std::string::npos) << cal_text;
    EXPECT_EQ(cal_text.find(" 0,125"), std::string::npos) << cal_text;
    ASSERT_EQ(calib_load(cal_path.c_str(), &loaded), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(std::memcmp(&loaded.world_to_model, &cal.world_to_model, sizeof cal.world_to_model), 0);
    EXPECT_EQ(loaded.acceleration_offset[2][1], 0.125f);

    // A BVH file: offsets, frame time and motion values with '.'.
    bvh_skeleton sk;
    std::memset(&sk, 0, sizeof sk);
    sk.joint_count = 2;
    std::snprintf(sk.names[0], BVH_NAME_CAP, "pelvis");
    std::snprintf(sk.names[1], BVH_NAME_CAP, "spine");
    sk.parents[0] = -1;
    sk.parents[1] = 0;
    sk.offsets[0][1] = 0.93f;
    sk.offsets[1][1] = 0.125f;
    const std::string bvh_path = test_temp_path("comma.bvh");
    bvh_writer *w = nullptr;
    ASSERT_EQ(bvh_writer_open(bvh_path.c_str(), &sk, 1.0 / 60.0, BVH_ORDER_ZXY, &w), MOCAP_OK) << mocap_last_error();
    const float root[3] = {0.5f, 0.93f, -0.25f};
    float rotations[2][4] = {{0.9659258f, 0.2588190f, 0, 0}, {1, 0, 0, 0}};  // 30 deg about x
    ASSERT_EQ(bvh_writer_append(w, root, rotations), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(bvh_writer_close(w), MOCAP_OK) << mocap_last_error();
    const auto bvh_bytes = read_file_bytes(bvh_path);
    const std::string bvh(bvh_bytes.begin(), bvh_bytes.end());
    EXPECT_NE(bvh.find("OFFSET 0.000000 0.125000 0.000000"), std::string::npos) << bvh;
    EXPECT_NE(bvh.find("Frame Time: 0.01666667"), std::string::npos) << bvh;
    EXPECT_NE(bvh.find("0.5 0.93 -0.25 0 30 0"), std::string::npos) << bvh;
    EXPECT_EQ(bvh.find(','), std::string::npos) << bvh;

    // The model's metadata (frame rate, rest offsets: text inside the .onnx) reads the same.
    if (!ort_library_available(nullptr)) GTEST_SKIP() << "ONNX Runtime not available: " << mocap_last_error();
    ort_model *m = nullptr;
    ASSERT_EQ(ort_model_open(kShippedModel.c_str(), nullptr, &m), MOCAP_OK) << mocap_last_error();
    const ort_model_info *info = ort_model_get_info(m);
    EXPECT_DOUBLE_EQ(info->frame_rate, 60.0);
    EXPECT_GT(info->rest_offsets[0][1], 0.8f);  // the pelvis stands about 0.9 m high
    EXPECT_LT(info->rest_offsets[0][1], 1.1f);
    ort_model_close(m);
}
