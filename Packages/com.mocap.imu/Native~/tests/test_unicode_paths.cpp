// Paths are UTF-8 in the whole API. On Windows the narrow C and Win32 calls would read them in
// the ANSI code page (a file would land under a garbled name, or not open at all), so every file
// and library the engine opens goes through platform.h's UTF-8 functions. These tests work in a
// folder with a non-ASCII name, on Linux and on Windows (under Wine), and check under which name
// the files really are on the disk, listed independently of the engine.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "platform.h"
#include "test_support.h"

extern "C" {
#include "capture_file.h"
#include "mocap_imu.h"
#include "onnx_runtime.h"
#include "synth.h"
}

namespace fs = std::filesystem;

namespace {

const fs::path kTestsDir = fs::path(__FILE__).parent_path();
const fs::path kShippedModel = kTestsDir / ".." / ".." / "Runtime" / "Models" / "mocap_pose_fp32.onnx";
// Latin-1 letters (in the Windows-1252 code page) and CJK (in none of the European ones).
const std::string kFolderName = "mocap-\xC3\xA4\xC3\xB6\xC3\xBC-\xE6\x97\xA5\xE6\x9C\xAC";   // mocap-äöü-日本
const std::string kFileStem = "aufnahme-\xC3\x9F-\xE6\x97\xA5\xE6\x9C\xAC";                 // aufnahme-ß-日本

// A fresh folder with the non-ASCII name inside this test's temporary folder, as UTF-8.
std::string unicode_folder()
{
    const std::string dir = test_temp_dir() + "/" + kFolderName;
    fs::create_directories(fs::u8path(dir));
    return dir;
}

// The names (UTF-8) of the files in a folder, read by the standard library, not the engine.
std::set<std::string> names_in(const std::string &utf8_dir)
{
    std::set<std::string> names;
    for (const auto &entry : fs::directory_iterator(fs::u8path(utf8_dir)))
        names.insert(entry.path().filename().u8string());
    return names;
}

std::string slurp(const std::string &utf8_path)
{
    std::ifstream in(fs::u8path(utf8_path), std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

}  // namespace

TEST(UnicodePaths, FolderIsReallyNamedInUnicode)
{
    const std::string dir = unicode_folder();
    const std::set<std::string> names = names_in(fs::path(dir).parent_path().u8string());
    EXPECT_EQ(names.count(kFolderName), 1u) << "the folder was created under another name";
}

TEST(UnicodePaths, CaptureIsWrittenAndReadBackUnderAUnicodePath)
{
    const std::string dir = unicode_folder();
    const std::string path = dir + "/" + kFileStem + ".cap";
    std::vector<std::vector<uint8_t>> records;
    for (int i = 0; i < 50; ++i) {
        std::vector<uint8_t> bytes((size_t)(1 + i * 7));
        for (size_t k = 0; k < bytes.size(); ++k) bytes[k] = (uint8_t)(i * 31 + k);
        records.push_back(bytes);
    }
    capture_writer *w = nullptr;
    ASSERT_EQ(capture_writer_open(path.c_str(), &w), MOCAP_OK) << mocap_last_error();
    for (size_t i = 0; i < records.size(); ++i)
        ASSERT_EQ(capture_writer_append(w, (int64_t)i * 1000000, records[i].data(), records[i].size()), MOCAP_OK)
            << mocap_last_error();
    ASSERT_EQ(capture_writer_close(w), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(names_in(dir), std::set<std::string>{kFileStem + ".cap"});

    capture_reader *r = nullptr;
    ASSERT_EQ(capture_reader_open(path.c_str(), &r), MOCAP_OK) << mocap_last_error();
    size_t n = 0;
    int64_t t = 0;
    const uint8_t *data = nullptr;
    size_t len = 0;
    while (capture_reader_next(r, &t, &data, &len) == MOCAP_OK) {
        ASSERT_LT(n, records.size());
        EXPECT_EQ(t, (int64_t)n * 1000000);
        ASSERT_EQ(std::vector<uint8_t>(data, data + len), records[n]) << "record " << n;
        ++n;
    }
    EXPECT_EQ(capture_reader_tail(r), 0);
    capture_reader_close(r);
    EXPECT_EQ(n, records.size());
}

// The generator's capture and truth CSV, then a replay session through the public API.
TEST(UnicodePaths, GeneratedCaptureReplaysThroughTheSession)
{
    const std::string dir = unicode_folder();
    const std::string capture = dir + "/" + kFileStem + ".cap";
    const std::string truth = dir + "/" + kFileStem + ".truth.csv";
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.heading_s = 0.5;
    cfg.strap_s = 0.2;
    cfg.tpose_s = 0.5;
    cfg.motion_s = 1.0;
    ASSERT_EQ(synth_write_capture(&cfg, synth_builtin_motion("walk"), nullptr, capture.c_str(), truth.c_str()),
              MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(names_in(dir), (std::set<std::string>{kFileStem + ".cap", kFileStem + ".truth.csv"}));
    EXPECT_GT(fs::file_size(fs::u8path(truth)), 1000u);

    mocap_session_config config;
    mocap_config_defaults(&config);
    config.source_kind = MOCAP_SOURCE_REPLAY;
    ASSERT_LT(capture.size(), sizeof config.path);
    std::snprintf(config.path, sizeof config.path, "%s", capture.c_str());
    mocap_session *s = nullptr;
    ASSERT_EQ(mocap_session_open(&config, &s), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_session_start(s), MOCAP_OK) << mocap_last_error();
    std::vector<mocap_frame> buf(64);
    size_t frames = 0;
    mocap_status st = MOCAP_OK;
    for (int spins = 0; spins < 20000 && st != MOCAP_ERR_END_OF_STREAM; ++spins) {
        uint32_t n = 0;
        st = mocap_session_drain(s, buf.data(), (uint32_t)buf.size(), &n);
        frames += n;
        if (n == 0) mocap_sleep_ms(1);
    }
    mocap_session_close(s);
    EXPECT_EQ(st, MOCAP_ERR_END_OF_STREAM);
    // 2.2 s at the session's frame rate, give or take the edges.
    EXPECT_GT(frames, 100u);
}

// ONNX Runtime itself loaded from the non-ASCII folder (LoadLibraryExW on Windows), the model
// opened from it (ORT's CreateSession takes a wide path there) and a BVH written beside them.
TEST(UnicodePaths, OnnxRuntimeAndTheModelLoadAndABvhIsWritten)
{
#if !defined(MOCAP_TEST_ORT_LIB)
    FAIL() << "built without ONNX Runtime headers (scripts/fetch_onnxruntime.sh, then cmake)";
#else
    const std::string dir = unicode_folder();
    const fs::path library(MOCAP_TEST_ORT_LIB);
    ASSERT_TRUE(fs::exists(library)) << library << " is missing: scripts/fetch_onnxruntime.sh";
    // The library and what sits beside it (onnxruntime_providers_shared.dll on Windows).
    for (const auto &entry : fs::directory_iterator(library.parent_path()))
        if (entry.is_regular_file())
            fs::copy_file(entry.path(), fs::u8path(dir + "/" + entry.path().filename().u8string()));
    const std::string library_copy = dir + "/" + library.filename().u8string();
    const std::string model_copy = dir + "/" + kFileStem + ".onnx";
    fs::copy_file(kShippedModel, fs::u8path(model_copy));

    mocap_model_options options;
    ASSERT_EQ(mocap_model_options_defaults(&options), MOCAP_OK);
    ASSERT_LT(library_copy.size(), sizeof options.onnxruntime_path);
    std::snprintf(options.onnxruntime_path, sizeof options.onnxruntime_path, "%s", library_copy.c_str());
    options.intra_op_threads = 1;
    mocap_model *model = nullptr;
    ASSERT_EQ(mocap_model_open(model_copy.c_str(), &options, &model), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(std::string(ort_library_path()), library_copy) << "ONNX Runtime came from elsewhere";
    mocap_model_info info;
    ASSERT_EQ(mocap_model_get_info(model, &info), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(std::string(info.joint_names[0]), "pelvis");

    const std::string bvh = dir + "/" + kFileStem + ".bvh";
    mocap_bvh_writer *writer = nullptr;
    ASSERT_EQ(mocap_bvh_open(bvh.c_str(), &info, nullptr, &writer), MOCAP_OK) << mocap_last_error();
    mocap_pose pose;
    std::memset(&pose, 0, sizeof pose);
    for (auto &q : pose.joint_rotations) q[0] = 1.0f;
    pose.root_position[1] = 0.9f;
    ASSERT_EQ(mocap_bvh_append(writer, &pose), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_bvh_append(writer, &pose), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_bvh_close(writer), MOCAP_OK) << mocap_last_error();
    mocap_model_close(model);

    EXPECT_EQ(names_in(dir).count(kFileStem + ".bvh"), 1u);
    const std::string text = slurp(bvh);
    EXPECT_EQ(text.rfind("HIERARCHY", 0), 0u) << text.substr(0, 200);
    EXPECT_NE(text.find("Frames: 2"), std::string::npos);
#endif
}
