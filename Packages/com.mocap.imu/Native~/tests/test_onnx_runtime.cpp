// The ONNX Runtime module (src/pose/onnx_runtime.c) against the REAL ONNX Runtime library
// (scripts/fetch_onnxruntime.sh). Contract violations use tiny models made by
// tests/make_onnx_fixtures.py (python3 + onnx); the shipped model is
// Runtime/Models/mocap_pose_fp32.onnx. Tests skip only when ONNX Runtime cannot be loaded.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "onnx_runtime.h"
#include "test_support.h"

#if defined(_WIN32)
#define popen _popen
#define pclose _pclose
#endif

namespace fs = std::filesystem;

namespace {

const fs::path kTestsDir = fs::path(__FILE__).parent_path();
const fs::path kShippedModel =
    kTestsDir / ".." / ".." / "Runtime" / "Models" / "mocap_pose_fp32.onnx";

#define REQUIRE_ORT()                                                                         \
    do {                                                                                      \
        if (!ort_library_available(nullptr))                                                  \
            GTEST_SKIP() << "ONNX Runtime not available: " << mocap_last_error();             \
    } while (0)

// A python3 that can import onnx (Debian's python3-onnx).
std::string python_with_onnx()
{
    std::vector<std::string> candidates;
    if (const char *env = std::getenv("MOCAP_PYTHON")) candidates.push_back(env);
    candidates.push_back("/usr/bin/python3");
    candidates.push_back("python3");
    for (const auto &p : candidates) {
        std::string cmd = "\"" + p + "\" -c \"import onnx\" >/dev/null 2>&1";
        if (std::system(cmd.c_str()) == 0) return p;
    }
    return "";
}

// Writes the fixture models into this test's temporary directory; returns it.
std::string make_fixtures()
{
    std::string dir = test_temp_dir();
#if defined(MOCAP_ONNX_FIXTURES_DIR)
    // Python cannot be started from inside the test here (Windows under Wine): ctest's
    // onnx_fixtures step ran make_onnx_fixtures.py on the build machine before this test.
    std::error_code ec;
    for (const auto &model : fs::directory_iterator(MOCAP_ONNX_FIXTURES_DIR))
        if (!ec) fs::copy_file(model.path(), fs::path(dir) / model.path().filename(),
                                 fs::copy_options::overwrite_existing, ec);
    EXPECT_FALSE(ec) << "copying the fixtures of " MOCAP_ONNX_FIXTURES_DIR ": " << ec.message();
    return dir;
#endif
    std::string py = python_with_onnx();
    EXPECT_FALSE(py.empty()) << "python3 with the onnx package is needed for the fixtures "
                                "(scripts/setup.sh installs python3-onnx; or set MOCAP_PYTHON)";
    std::string cmd = "\"" + py + "\" \"" + (kTestsDir / "make_onnx_fixtures.py").string() +
                      "\" \"" + dir + "\" >/dev/null";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    return dir;
}

struct Opened {
    ort_model *model = nullptr;
    mocap_status status = MOCAP_OK;
    std::string message;
    ~Opened() { ort_model_close(model); }
};

void open_model(const std::string &path, Opened &o, const ort_options *opts = nullptr)
{
    o.status = ort_model_open(path.c_str(), opts, &o.model);
    o.message = o.status == MOCAP_OK ? "" : mocap_last_error();
}

std::vector<float> random_floats(size_t n, unsigned seed, float scale)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-scale, scale);
    std::vector<float> v(n);
    for (auto &x : v) x = u(rng);
    return v;
}

}  // namespace

TEST(OnnxRuntime, LoadsTheRealLibrary)
{
    REQUIRE_ORT();
    std::string version = ort_library_version();
    EXPECT_EQ(version.rfind("1.", 0), 0u) << version;
    EXPECT_NE(std::string(ort_library_path()), "");
}

TEST(OnnxRuntime, MissingModelIsNotFound)
{
    REQUIRE_ORT();
    Opened o;
    std::string path = test_temp_path("no_such_model.onnx");
    open_model(path, o);
    EXPECT_EQ(o.status, MOCAP_ERR_NOT_FOUND);
    EXPECT_EQ(o.model, nullptr);
    EXPECT_NE(o.message.find("no_such_model.onnx"), std::string::npos) << o.message;
}

TEST(OnnxRuntime, NonOnnxFileIsAFormatError)
{
    REQUIRE_ORT();
    std::string path = test_temp_path("notes.onnx");
    write_file_bytes(path, std::vector<uint8_t>{'h', 'e', 'l', 'l', 'o', '\n', 0xff, 0x00, 0x13});
    Opened o;
    open_model(path, o);
    EXPECT_EQ(o.status, MOCAP_ERR_FORMAT);
    EXPECT_NE(o.message.find("not a model ONNX Runtime can load"), std::string::npos) << o.message;
    EXPECT_NE(o.message.find("notes.onnx"), std::string::npos) << o.message;
}

TEST(OnnxRuntime, ContractViolationsAreRefusedByName)
{
    REQUIRE_ORT();
    std::string dir = make_fixtures();
    struct Case {
        const char *file;
        const char *expect;
    } cases[] = {
        {"wrong_input_name.onnx", "input 'imu_orientation' is missing"},
        {"wrong_rank.onnx", "'imu_orientation' has rank 3, the contract needs rank 5"},
        {"missing_metadata.onnx", "'mocap.contract_version' is missing"},
        {"missing_joint_names.onnx", "'mocap.joint_names' is missing"},
        {"wrong_version.onnx", "mocap.contract_version is '9'"},
        {"state_mismatch.onnx", "mocap.state_layers"},
        {"fixed_batch.onnx", "dimension 0 (B) is fixed to 1"},
        {"wrong_joint_name.onnx", "'left_forearm'"},
        {"wrong_output_shape.onnx", "output 'joint_rotations' dimension 2 (24) is 12"},
        // Only the probe run sees this rank; its message must not print dims it never read.
        {"rank_nine_output.onnx", "output 'foot_contact' came out as a rank-9 tensor"},
        // Contract 2: the sensor list and the mask.
        {"v2_unknown_segment.onnx", "'tail' is not a segment this engine knows"},
        {"v2_required_length.onnx", "mocap.sensor_required has 6 entries for the 7 sensors"},
        {"v2_missing_mask.onnx", "input 'imu_mask' is missing"},
        {"v1_with_mask.onnx", "unexpected input 'imu_mask'"},
        {"v2_wrong_sensor_dim.onnx", "dimension 2 (N) is 6, the contract needs 7 (mocap.sensor_order)"},
        {"v2_duplicate_segment.onnx", "names 'head' twice"},
        {"unknown_precision.onnx", "mocap.precision is 'bf16', expected fp32, fp16 or int8"},
        // Contract 3: the geometry the engine does must be described, and fit the graph.
        {"v3_missing_anchor_joints.onnx", "'mocap.anchor_joints' is missing"},
        {"v3_wrong_features.onnx", "'network_input' dimension 2 (F) is 132, the contract needs 138"},
        {"v3_bad_mirror_table.onnx", "mirror sensor table: sensor 2 maps to 1"},
        {"v3_unmasked_optional.onnx", "a network without the mask needs every sensor"},
    };
    for (const auto &c : cases) {
        Opened o;
        open_model(dir + "/" + c.file, o);
        EXPECT_EQ(o.status, MOCAP_ERR_FORMAT) << c.file;
        EXPECT_EQ(o.model, nullptr) << c.file;
        EXPECT_NE(o.message.find(c.expect), std::string::npos) << c.file << ": " << o.message;
        EXPECT_NE(o.message.find(c.file), std::string::npos) << o.message;  // names the model
    }
    // The process is fine after all that: the valid model opens, and so does one whose fixed
    // output sizes are left symbolic in the file (the probe run checks them).
    Opened ok, symbolic;
    open_model(dir + "/valid.onnx", ok);
    EXPECT_EQ(ok.status, MOCAP_OK) << ok.message;
    open_model(dir + "/symbolic_dims.onnx", symbolic);
    EXPECT_EQ(symbolic.status, MOCAP_OK) << symbolic.message;
    // Weights stored as int8 are a precision like fp16: the interface is the same.
    Opened int8;
    open_model(dir + "/int8_precision.onnx", int8);
    ASSERT_EQ(int8.status, MOCAP_OK) << int8.message;
    EXPECT_STREQ(ort_model_get_info(int8.model)->precision, "int8");
}

TEST(OnnxRuntime, ReadsMetadata)
{
    REQUIRE_ORT();
    std::string dir = make_fixtures();
    Opened o;
    open_model(dir + "/valid.onnx", o);
    ASSERT_EQ(o.status, MOCAP_OK) << o.message;
    const ort_model_info *info = ort_model_get_info(o.model);
    ASSERT_NE(info, nullptr);
    EXPECT_EQ(info->contract_version, 1);
    EXPECT_DOUBLE_EQ(info->frame_rate, 60.0);
    EXPECT_EQ(info->state_layers, 2);
    EXPECT_EQ(info->state_size, 4);
    EXPECT_STREQ(info->joint_names[0], "pelvis");
    EXPECT_STREQ(info->joint_names[23], "right_hand");
    EXPECT_EQ(info->joint_parents[0], -1);
    EXPECT_EQ(info->joint_parents[18], 16);
    EXPECT_NEAR(info->rest_offsets[0][1], 0.93f, 1e-6);
    EXPECT_STREQ(info->precision, "fp32");
    EXPECT_STREQ(info->model_name, "fixture");
    // Contract 1 is the six default sensors, all required, no mask.
    EXPECT_EQ(info->sensor_count, 6);
    EXPECT_EQ(info->required_mask, 0x3fu);
    EXPECT_EQ(info->has_mask, 0);
    for (int k = 0; k < 6; ++k) EXPECT_EQ(info->sensor_segments[k], k);
    EXPECT_EQ(ort_stream_mask(nullptr), nullptr);
}

// A contract-2 model declares its own sensors (here the six plus an optional chest) and takes a
// mask; its closed-form outputs (make_onnx_fixtures.py, v2_chest) show what reached it.
TEST(OnnxRuntime, ContractTwoReadsItsSensorSetAndFeedsTheMask)
{
    REQUIRE_ORT();
    std::string dir = make_fixtures();
    Opened o;
    open_model(dir + "/v2_chest.onnx", o);
    ASSERT_EQ(o.status, MOCAP_OK) << o.message;
    const ort_model_info *info = ort_model_get_info(o.model);
    EXPECT_EQ(info->contract_version, 2);
    ASSERT_EQ(info->sensor_count, 7);
    EXPECT_EQ(info->sensor_segments[6], MOCAP_SEGMENT_CHEST);
    EXPECT_EQ(info->sensor_segments[5], MOCAP_SEGMENT_HEAD);
    EXPECT_EQ(info->required_mask, 0x3fu);  // the chest is optional
    EXPECT_EQ(info->has_mask, 1);

    const int B = 2;
    ort_stream *st = nullptr;
    ASSERT_EQ(ort_stream_create(o.model, B, 1, &st), MOCAP_OK) << mocap_last_error();
    ASSERT_NE(ort_stream_mask(st), nullptr);
    std::vector<float> ori = random_floats((size_t)B * 7 * 9, 5, 1.0f);
    std::vector<float> acc = random_floats((size_t)B * 7 * 3, 6, 2.0f);
    std::memcpy(ort_stream_orientation(st), ori.data(), ori.size() * sizeof(float));
    std::memcpy(ort_stream_acceleration(st), acc.data(), acc.size() * sizeof(float));
    const float mask[B][7] = {{1, 1, 1, 1, 1, 1, 1}, {1, 1, 0, 1, 1, 1, 0}};
    std::memcpy(ort_stream_mask(st), mask, sizeof mask);
    ASSERT_EQ(ort_stream_run(st), MOCAP_OK) << mocap_last_error();
    for (int b = 0; b < B; ++b) {
        const float *v = ort_stream_root_velocity(st) + b * 3;
        const float *rot = ort_stream_joint_rotations(st) + (size_t)b * 216;
        float sum = 0;
        for (int k = 0; k < 7; ++k) sum += mask[b][k];
        EXPECT_FLOAT_EQ(v[0], sum) << b;
        EXPECT_FLOAT_EQ(v[1], mask[b][6]) << b;
        EXPECT_FLOAT_EQ(v[2], acc[((size_t)b * 7 + 6) * 3 + 1]) << b;
        for (int k = 0; k < 9; ++k) {
            EXPECT_EQ(rot[k], ori[(size_t)b * 63 + k]) << b;  // joint 0 = sensor 0
            const float identity = (k % 4 == 0) ? 1.0f : 0.0f;
            const float chest = mask[b][6] ? ori[(size_t)b * 63 + 54 + k] : identity;
            EXPECT_FLOAT_EQ(rot[9 * 9 + k], chest) << b;  // joint 9 = the chest when present
        }
    }
    ort_stream_destroy(st);
}

// A contract-3 model holds the network alone; the engine does the geometry around it. The
// fixture's network answers zero residuals (make_onnx_fixtures.py, v3_network), so the engine
// must give the rest pose under the measured pelvis, hands turned as their sensors.
TEST(OnnxRuntime, ContractThreeLeavesTheGeometryToTheEngine)
{
    REQUIRE_ORT();
    std::string dir = make_fixtures();
    Opened o;
    open_model(dir + "/v3_network.onnx", o);
    ASSERT_EQ(o.status, MOCAP_OK) << o.message;
    const ort_model_info *info = ort_model_get_info(o.model);
    EXPECT_EQ(info->contract_version, 3);
    EXPECT_EQ(info->sensor_count, 6);
    EXPECT_EQ(info->has_mask, 1);
    EXPECT_EQ(info->state_size, 4);  // both rows of the mirror average

    const int B = 2, T = 3;
    ort_stream *st = nullptr;
    ASSERT_EQ(ort_stream_create(o.model, B, T, &st), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(ort_stream_state_count(st), (size_t)2 * B * 4);
    const double yaw[B] = {0.6, -2.4};
    std::vector<float> ori((size_t)B * T * 6 * 9, 0.0f);
    for (int b = 0; b < B; ++b)
        for (int t = 0; t < T; ++t) {
            float *f = ori.data() + ((size_t)b * T + t) * 54;
            const float c = (float)std::cos(yaw[b]), s = (float)std::sin(yaw[b]);
            const float pelvis[9] = {c, 0, s, 0, 1, 0, -s, 0, c};
            std::memcpy(f, pelvis, sizeof pelvis);
            std::vector<float> r = random_floats(45, 10 + b * T + t, 1.0f);
            for (int k = 1; k < 6; ++k) {  // any rotation: Gram-Schmidt of random columns
                float *m = f + k * 9;
                double a[3] = {r[(k - 1) * 9 + 0], r[(k - 1) * 9 + 3], r[(k - 1) * 9 + 6]};
                double d[3] = {r[(k - 1) * 9 + 1], r[(k - 1) * 9 + 4], r[(k - 1) * 9 + 7]};
                double na = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
                for (double &x : a) x /= na;
                double dot = a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
                for (int i = 0; i < 3; ++i) d[i] -= dot * a[i];
                double nd = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                for (double &x : d) x /= nd;
                double e[3] = {a[1] * d[2] - a[2] * d[1], a[2] * d[0] - a[0] * d[2], a[0] * d[1] - a[1] * d[0]};
                for (int i = 0; i < 3; ++i) {
                    m[i * 3 + 0] = (float)a[i];
                    m[i * 3 + 1] = (float)d[i];
                    m[i * 3 + 2] = (float)e[i];
                }
            }
        }
    std::memcpy(ort_stream_orientation(st), ori.data(), ori.size() * sizeof(float));
    // each frame's own pelvis acceleration: the fixture passes its heading-frame x to the
    // velocity, so a row or frame given another's features shows there
    std::vector<float> acc = random_floats((size_t)B * T * 6 * 3, 77, 6.0f);
    std::memcpy(ort_stream_acceleration(st), acc.data(), acc.size() * sizeof(float));
    float *mask = ort_stream_mask(st);
    ASSERT_NE(mask, nullptr);
    for (int i = 0; i < B * T * 6; ++i) mask[i] = 1.0f;
    mask[(1 * T + 2) * 6 + 1] = 0.0f;  // the second character's left wrist gone in its last frame
    for (int e = 0; e < 9; ++e) ort_stream_orientation(st)[((1 * T + 2) * 6 + 1) * 9 + e] = 0.0f;
    ASSERT_EQ(ort_stream_run(st), MOCAP_OK) << mocap_last_error();

    auto mul = [](float *out, const float *a, const float *b) {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                out[i * 3 + j] = a[i * 3] * b[j] + a[i * 3 + 1] * b[3 + j] + a[i * 3 + 2] * b[6 + j];
    };
    for (int b = 0; b < B; ++b)
        for (int t = 0; t < T; ++t) {
            const size_t f = (size_t)b * T + t;
            const float *rot = ort_stream_joint_rotations(st) + f * 216;
            const float *in = ori.data() + f * 54;
            for (int e = 0; e < 9; ++e) EXPECT_NEAR(rot[e], in[e], 1e-6) << "pelvis " << b << "," << t;
            for (int j : {3, 6, 9, 12, 16, 18, 20, 1, 7})
                for (int e = 0; e < 9; ++e)
                    EXPECT_NEAR(rot[j * 9 + e], e % 4 == 0 ? 1.0f : 0.0f, 1e-6) << "joint " << j;
            // the hands' global orientation: the pelvis times their local ones (all between rest)
            for (int side = 0; side < 2; ++side) {
                float global[9];
                mul(global, rot, rot + (22 + side) * 9);
                const bool missing = b == 1 && t == 2 && side == 0;
                for (int e = 0; e < 9; ++e)
                    EXPECT_NEAR(global[e], missing ? rot[e] : in[(1 + side) * 9 + e], 2e-5)
                        << "hand " << side << " of " << b << "," << t << (missing ? " (missing)" : "");
            }
            // velocity Ry (x, 0, 1), x = (Ry^T a_pelvis)_x / 30
            const double c = std::cos(yaw[b]), s = std::sin(yaw[b]);
            const float *a = acc.data() + f * 18;
            const double x = (c * a[0] - s * a[2]) / 30.0;
            const float *v = ort_stream_root_velocity(st) + f * 3;
            EXPECT_NEAR(v[0], c * x + s, 1e-5) << b << "," << t;
            EXPECT_NEAR(v[1], 0.0f, 1e-6);
            EXPECT_NEAR(v[2], -s * x + c, 1e-5) << b << "," << t;
            EXPECT_GT(std::fabs(x), 1e-3);  // the signal is there to see
            const float *contact = ort_stream_foot_contact(st) + f * 2;
            EXPECT_NEAR(contact[0], 0.5f, 1e-6);  // left +2 and mirrored right -2 averaged
            EXPECT_NEAR(contact[1], 0.5f, 1e-6);
        }
    // the state went through the graph (+1 per run), both rows of every character
    for (size_t i = 0; i < ort_stream_state_count(st); ++i)
        ASSERT_FLOAT_EQ(ort_stream_state_h(st)[i], 1.0f) << i;
    ort_stream_destroy(st);
}

// The shipped int8 model is contract 3; it must answer what the complete fp32 graph does, to
// the int8 tolerance, streamed as the engine runs it.
TEST(OnnxRuntime, ShippedInt8NetworkAnswersLikeTheCompleteFp32Model)
{
    REQUIRE_ORT();
    const fs::path int8_path = kShippedModel.parent_path() / "mocap_pose_int8.onnx";
    ort_options opts;
    ort_options_defaults(&opts);
    opts.intra_op_threads = 1;
    Opened fp32, int8;
    open_model(kShippedModel.string(), fp32, &opts);
    open_model(int8_path.string(), int8, &opts);
    ASSERT_EQ(fp32.status, MOCAP_OK) << fp32.message;
    ASSERT_EQ(int8.status, MOCAP_OK) << int8.message;
    EXPECT_EQ(ort_model_get_info(int8.model)->contract_version, 3);
    EXPECT_STREQ(ort_model_get_info(int8.model)->precision, "int8");
    EXPECT_EQ(ort_model_get_info(int8.model)->state_size, ort_model_get_info(fp32.model)->state_size);
    ort_stream *a = nullptr, *b = nullptr;
    ASSERT_EQ(ort_stream_create(fp32.model, 1, 1, &a), MOCAP_OK);
    ASSERT_EQ(ort_stream_create(int8.model, 1, 1, &b), MOCAP_OK);
    double worst = 0.0, worst_velocity = 0.0, worst_contact = 0.0;
    for (int t = 0; t < 30; ++t) {
        std::vector<float> acc = random_floats(18, 100 + t, 3.0f);
        for (ort_stream *s : {a, b}) {
            for (int k = 0; k < 6; ++k) {
                const float c = (float)std::cos(0.05 * t + k), sn = (float)std::sin(0.05 * t + k);
                const float m[9] = {c, 0, sn, 0, 1, 0, -sn, 0, c};  // each sensor turned about y
                std::memcpy(ort_stream_orientation(s) + k * 9, m, sizeof m);
            }
            std::memcpy(ort_stream_acceleration(s), acc.data(), 18 * sizeof(float));
            ASSERT_EQ(ort_stream_run(s), MOCAP_OK) << mocap_last_error();
        }
        for (int k = 0; k < 216; ++k)
            worst = std::fmax(worst, std::fabs(ort_stream_joint_rotations(a)[k] - ort_stream_joint_rotations(b)[k]));
        for (int k = 0; k < 3; ++k)
            worst_velocity = std::fmax(worst_velocity, std::fabs(ort_stream_root_velocity(a)[k] -
                                                                 ort_stream_root_velocity(b)[k]));
        for (int k = 0; k < 2; ++k)
            worst_contact = std::fmax(worst_contact, std::fabs(ort_stream_foot_contact(a)[k] -
                                                               ort_stream_foot_contact(b)[k]));
    }
    EXPECT_GT(worst, 0.0);   // quantised weights
    EXPECT_LT(worst, 0.05);  // the quantize check's bound
    EXPECT_LT(worst_velocity, 0.05) << "m/s";
    EXPECT_LT(worst_contact, 0.05);
    ort_stream_destroy(a);
    ort_stream_destroy(b);
}

TEST(OnnxRuntime, CudaWithoutCudaBuildIsRefusedClearly)
{
    REQUIRE_ORT();
    std::string dir = make_fixtures();
    ort_options opts;
    ort_options_defaults(&opts);
    opts.provider = ORT_PROVIDER_CUDA;
    Opened o;
    open_model(dir + "/valid.onnx", o, &opts);
    // The fetched library is a CPU build; a CUDA build would open the model instead.
    if (o.status == MOCAP_OK) GTEST_SKIP() << "this ONNX Runtime has CUDA";
    EXPECT_EQ(o.status, MOCAP_ERR_UNSUPPORTED);
    EXPECT_NE(o.message.find("CUDA"), std::string::npos) << o.message;
    EXPECT_NE(o.message.find("CPUExecutionProvider"), std::string::npos) << o.message;
}

// The fixture's outputs are known in closed form (see make_onnx_fixtures.py): check the binding,
// batch layout and state carrying, and that streaming T=1 equals one call for the whole clip.
TEST(OnnxRuntime, StreamingEqualsWholeClipAndCarriesState)
{
    REQUIRE_ORT();
    std::string dir = make_fixtures();
    ort_options opts;
    ort_options_defaults(&opts);
    opts.intra_op_threads = 1;
    Opened o;
    open_model(dir + "/valid.onnx", o, &opts);
    ASSERT_EQ(o.status, MOCAP_OK) << o.message;
    const int B = 2, N = 12;
    std::vector<float> ori = random_floats((size_t)B * N * 54, 1, 1.0f);
    std::vector<float> acc = random_floats((size_t)B * N * 18, 2, 0.2f);

    ort_stream *whole = nullptr, *step = nullptr;
    ASSERT_EQ(ort_stream_create(o.model, B, N, &whole), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(ort_stream_create(o.model, B, 1, &step), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(ort_stream_state_count(whole), (size_t)2 * B * 4);
    std::memcpy(ort_stream_orientation(whole), ori.data(), ori.size() * sizeof(float));
    std::memcpy(ort_stream_acceleration(whole), acc.data(), acc.size() * sizeof(float));
    ASSERT_EQ(ort_stream_run(whole), MOCAP_OK) << mocap_last_error();

    // Expected, from the closed form.
    for (int b = 0; b < B; ++b) {
        double cum = 0;
        for (int t = 0; t < N; ++t) {
            for (int k = 0; k < 18; ++k) cum += acc[((size_t)b * N + t) * 18 + k];
            const float *v = ort_stream_root_velocity(whole) + ((size_t)b * N + t) * 3;
            for (int k = 0; k < 3; ++k) ASSERT_NEAR(v[k], cum, 1e-4) << b << " " << t;
            const float *rot = ort_stream_joint_rotations(whole) + ((size_t)b * N + t) * 216;
            for (int j = 0; j < 24; ++j)
                for (int k = 0; k < 9; ++k)
                    ASSERT_EQ(rot[j * 9 + k], ori[((size_t)b * N + t) * 54 + (j % 6) * 9 + k]);
            const float *fc = ort_stream_foot_contact(whole) + ((size_t)b * N + t) * 2;
            EXPECT_NEAR(fc[0], 1.0 / (1.0 + std::exp(-cum)), 1e-5);
        }
        // The state after the call is the clip's total for this character.
        for (int l = 0; l < 2; ++l)
            for (int h = 0; h < 4; ++h)
                EXPECT_NEAR(ort_stream_state_h(whole)[(l * B + b) * 4 + h], cum, 1e-4);
    }
    EXPECT_NEAR(ort_stream_state_c(whole)[0], 1.0f, 1e-6);  // 0.5 * 0 + 1

    // Frame by frame, state carried by the stream.
    const float *out_ptr = ort_stream_root_velocity(step);
    for (int t = 0; t < N; ++t) {
        for (int b = 0; b < B; ++b) {
            std::memcpy(ort_stream_orientation(step) + (size_t)b * 54,
                        ori.data() + ((size_t)b * N + t) * 54, 54 * sizeof(float));
            std::memcpy(ort_stream_acceleration(step) + (size_t)b * 18,
                        acc.data() + ((size_t)b * N + t) * 18, 18 * sizeof(float));
        }
        ASSERT_EQ(ort_stream_run(step), MOCAP_OK) << mocap_last_error();
        EXPECT_EQ(ort_stream_root_velocity(step), out_ptr);  // bound buffers, no reallocation
        for (int b = 0; b < B; ++b)
            for (int k = 0; k < 3; ++k)
                ASSERT_NEAR(ort_stream_root_velocity(step)[b * 3 + k],
                            ort_stream_root_velocity(whole)[((size_t)b * N + t) * 3 + k], 1e-4)
                    << "frame " << t << " character " << b;
    }
    for (size_t i = 0; i < ort_stream_state_count(step); ++i) {
        EXPECT_NEAR(ort_stream_state_h(step)[i], ort_stream_state_h(whole)[i], 1e-4);
        EXPECT_NEAR(ort_stream_state_c(step)[i], 2.0f - std::ldexp(1.0f, -(N - 1)), 1e-5);
    }
    // A reset starts over: the first frame's result again.
    ort_stream_reset_state(step);
    ASSERT_EQ(ort_stream_run(step), MOCAP_OK);
    double last_frame_sum = 0;
    for (int k = 0; k < 18; ++k) last_frame_sum += acc[((size_t)0 * N + N - 1) * 18 + k];
    EXPECT_NEAR(ort_stream_root_velocity(step)[0], last_frame_sum, 1e-4);
    ort_stream_destroy(whole);
    ort_stream_destroy(step);
}

TEST(OnnxRuntime, RejectsBadStreamShapes)
{
    REQUIRE_ORT();
    std::string dir = make_fixtures();
    Opened o;
    open_model(dir + "/valid.onnx", o);
    ASSERT_EQ(o.status, MOCAP_OK) << o.message;
    ort_stream *s = nullptr;
    EXPECT_EQ(ort_stream_create(o.model, 0, 1, &s), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(ort_stream_create(o.model, 1, 0, &s), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(s, nullptr);
}

// mocapctl infer + model-info on the fixture, through tensor bundle files.
namespace {
std::string run_capture(const std::string &cmd)
{
    std::string out;
    FILE *p = popen(cmd.c_str(), "r");
    if (!p) return out;
    char buf[512];
    while (fgets(buf, sizeof buf, p)) out += buf;
    int rc = pclose(p);
    out += "\nrc=" + std::to_string(rc);
    return out;
}
}  // namespace

TEST(OnnxRuntime, MocapctlInferStreamMatchesWholeClip)
{
    REQUIRE_ORT();
    std::string dir = make_fixtures();
    const int B = 1, N = 7;
    std::vector<float> ori = random_floats((size_t)B * N * 54, 3, 1.0f);
    std::vector<float> acc = random_floats((size_t)B * N * 18, 4, 0.3f);
    std::vector<uint8_t> bundle = tensor_bundle_bytes({{"imu_orientation", {B, N, 6, 3, 3}, ori},
                                                       {"imu_acceleration", {B, N, 6, 3}, acc}});
    std::string in = dir + "/in.tensors";
    write_file_bytes(in, bundle);
    std::string base = std::string(MOCAP_MOCAPCTL) + " infer --model " + dir + "/valid.onnx" +
                       " --input " + in + " --threads 1 --output ";
    std::string r1 = run_capture(base + dir + "/whole.tensors 2>&1");
    ASSERT_NE(r1.find("rc=0"), std::string::npos) << r1;
    std::string r2 = run_capture(base + dir + "/stream.tensors --stream 2>&1");
    ASSERT_NE(r2.find("rc=0"), std::string::npos) << r2;
    EXPECT_NE(r2.find("timing: calls 7 frames_per_call 1"), std::string::npos) << r2;
    std::string r3 = run_capture(base + dir + "/chunks.tensors --frames 3 2>&1");
    ASSERT_NE(r3.find("rc=0"), std::string::npos) << r3;
    auto whole = tensor_bundle_get(read_file_bytes(dir + "/whole.tensors"), "root_velocity");
    auto stream = tensor_bundle_get(read_file_bytes(dir + "/stream.tensors"), "root_velocity");
    auto chunks = tensor_bundle_get(read_file_bytes(dir + "/chunks.tensors"), "root_velocity");
    ASSERT_EQ(whole.size(), (size_t)N * 3);
    ASSERT_EQ(stream.size(), whole.size());
    ASSERT_EQ(chunks.size(), whole.size());
    double cum = 0;
    for (int t = 0; t < N; ++t) {
        for (int k = 0; k < 18; ++k) cum += acc[(size_t)t * 18 + k];
        EXPECT_NEAR(whole[t * 3], cum, 1e-4);
        EXPECT_NEAR(stream[t * 3], cum, 1e-4);
        EXPECT_NEAR(chunks[t * 3], cum, 1e-4);
    }
    auto state = tensor_bundle_get(read_file_bytes(dir + "/chunks.tensors"), "state_out_h");
    ASSERT_EQ(state.size(), 8u);
    EXPECT_NEAR(state[0], cum, 1e-4);

    std::string info = run_capture(std::string(MOCAP_MOCAPCTL) + " model-info " + dir +
                                   "/valid.onnx 2>&1");
    EXPECT_NE(info.find("right_hand"), std::string::npos) << info;
    EXPECT_NE(info.find("layers 2, size 4"), std::string::npos) << info;
    std::string bad = run_capture(std::string(MOCAP_MOCAPCTL) + " model-info " + dir +
                                  "/wrong_version.onnx 2>&1");
    EXPECT_NE(bad.find("contract_version is '9'"), std::string::npos) << bad;
    EXPECT_EQ(bad.find("rc=0"), std::string::npos) << bad;
    // A mistyped MOCAP_ONNXRUNTIME_PATH is an error naming it, not a quiet fall back to the
    // fetched build (which would have loaded here).
#if defined(_WIN32)
    const std::string with_typo = "set MOCAP_ONNXRUNTIME_PATH=/nonexistent/libonnxruntime-cuda.so&& ";
#else
    const std::string with_typo = "MOCAP_ONNXRUNTIME_PATH=/nonexistent/libonnxruntime-cuda.so ";
#endif
    std::string typo = run_capture(with_typo +
                                   std::string(MOCAP_MOCAPCTL) + " model-info " + dir + "/valid.onnx 2>&1");
    EXPECT_EQ(typo.find("rc=0"), std::string::npos) << typo;
    EXPECT_NE(typo.find("/nonexistent/libonnxruntime-cuda.so"), std::string::npos) << typo;
    EXPECT_EQ(typo.find("right_hand"), std::string::npos) << typo;
}

// The model the package ships (untrained or trained): valid, and streaming == whole clip.
TEST(OnnxRuntime, ShippedModelIsValidAndStreams)
{
    REQUIRE_ORT();
    ASSERT_TRUE(fs::exists(kShippedModel)) << kShippedModel << " is missing";
    ort_options opts;
    ort_options_defaults(&opts);
    opts.intra_op_threads = 1;
    Opened o;
    open_model(kShippedModel.string(), o, &opts);
    ASSERT_EQ(o.status, MOCAP_OK) << o.message;
    const ort_model_info *info = ort_model_get_info(o.model);
    EXPECT_EQ(info->contract_version, 1);
    EXPECT_GT(info->frame_rate, 0);
    EXPECT_STREQ(info->joint_names[15], "head");
    const int N = 8;
    // A still T-pose: identity orientations, zero accelerations.
    ort_stream *whole = nullptr, *step = nullptr;
    ASSERT_EQ(ort_stream_create(o.model, 1, N, &whole), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(ort_stream_create(o.model, 1, 1, &step), MOCAP_OK) << mocap_last_error();
    std::vector<float> acc = random_floats((size_t)N * 18, 5, 2.0f);
    for (int t = 0; t < N; ++t)
        for (int s = 0; s < 6; ++s)
            for (int k = 0; k < 9; ++k)
                ort_stream_orientation(whole)[(t * 6 + s) * 9 + k] = (k % 4 == 0) ? 1.0f : 0.0f;
    std::memcpy(ort_stream_acceleration(whole), acc.data(), acc.size() * sizeof(float));
    ASSERT_EQ(ort_stream_run(whole), MOCAP_OK) << mocap_last_error();
    for (int t = 0; t < N; ++t) {
        std::memcpy(ort_stream_orientation(step), ort_stream_orientation(whole) + t * 54, 54 * 4);
        std::memcpy(ort_stream_acceleration(step), acc.data() + t * 18, 18 * 4);
        ASSERT_EQ(ort_stream_run(step), MOCAP_OK) << mocap_last_error();
        for (int k = 0; k < 216; ++k) {
            float a = ort_stream_joint_rotations(step)[k];
            float b = ort_stream_joint_rotations(whole)[t * 216 + k];
            ASSERT_TRUE(std::isfinite(a));
            ASSERT_NEAR(a, b, 2e-3) << "frame " << t << " value " << k;
        }
        for (int k = 0; k < 3; ++k)
            ASSERT_NEAR(ort_stream_root_velocity(step)[k], ort_stream_root_velocity(whole)[t * 3 + k],
                        2e-3);
    }
    // Rotations are rotations.
    const float *r = ort_stream_joint_rotations(whole);
    for (int j = 0; j < 24 * N; ++j) {
        const float *m = r + j * 9;
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                double dot = 0;
                for (int k = 0; k < 3; ++k) dot += m[k * 3 + a] * m[k * 3 + b];
                ASSERT_NEAR(dot, a == b ? 1.0 : 0.0, 1e-3) << "matrix " << j;
            }
    }
    ort_stream_destroy(whole);
    ort_stream_destroy(step);
}
